"""The blind stiffness-ranking protocol as seed 000 §5.2 ran it, as pure functions of the answers so far.

Zones are the areas in the order they are presented (zone 0 is the seed's "Zone 1"). Zones 1 and 2 are
compared first; then zone 3 is compared with zones 1 and 2, respectively; then zone 4 with zones 1-3. A
participant who is unsure asks for more pokes of the same two zones and the comparison is asked again.
After each new zone its place in the ranking is the number of earlier zones judged harder than it.
Finally the ranking becomes ratings: hardest 8-10, softest 1-3, the others in between.

Because the next step is a pure function of the answers, a study that is interrupted resumes exactly
where it stopped by replaying the saved answers (see `human.py`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from teleop.core.errors import InputError

HARDER = "harder"   # the new zone is harder than the reference zone
SOFTER = "softer"
UNSURE = "unsure"   # poke both zones again and ask again
ANSWERS = (HARDER, SOFTER, UNSURE)

HARDEST_RATINGS = (8, 9, 10)
SOFTEST_RATINGS = (1, 2, 3)


@dataclass(frozen=True)
class Compare:
    """Ask whether zone `new` is harder than zone `ref` (0-based zone numbers); `repeat` = unsure so far."""

    new: int
    ref: int
    repeat: int = 0


@dataclass(frozen=True)
class Rate:
    """Ask for the ratings of the zones in `ranking` (zone numbers, hardest first)."""

    ranking: tuple


def presentation(rng: np.random.Generator, n_areas: int) -> tuple:
    """Random presentation order: the slot (pad position index) shown as zone 0, 1, ... ."""
    return tuple(int(i) for i in rng.permutation(n_areas))


def ranking_from_answers(n_zones: int, answers) -> tuple:
    """The ranking (zone numbers, hardest first) after the decisive answers given so far.

    answers: sequence of (Compare, answer) pairs in the order asked; UNSURE answers are ignored.
    Zone k joins at index = number of earlier zones judged harder than k (exact when consistent).
    """
    verdict = {}
    for step, answer in answers:
        if answer != UNSURE:
            verdict[(step.new, step.ref)] = answer
    ranking = [0] if n_zones else []
    for k in range(1, n_zones):
        if not all((k, j) in verdict for j in range(k)):
            break
        n_harder = sum(verdict[(k, j)] == SOFTER for j in range(k))
        ranking.insert(n_harder, k)
    return tuple(ranking)


def next_step(n_zones: int, answers):
    """The next question: a Compare, a Rate, or None once ratings are given (see `finished`).

    answers: sequence of (Compare, answer) pairs in the order asked.
    """
    asked = list(answers)
    unsure_run = 0
    for step, answer in reversed(asked):
        if answer != UNSURE:
            break
        unsure_run += 1
    if asked and asked[-1][1] == UNSURE:
        last = asked[-1][0]
        return Compare(last.new, last.ref, unsure_run)
    decided = {(s.new, s.ref) for s, a in asked if a != UNSURE}
    for k in range(1, n_zones):
        for j in range(k):
            if (k, j) not in decided:
                return Compare(k, j, 0)
    return Rate(ranking_from_answers(n_zones, asked))


def check_answer(answer: str) -> str:
    if answer not in ANSWERS:
        raise InputError(f"answer '{answer}': expected one of {', '.join(ANSWERS)}")
    return answer


def check_ratings(ranking, ratings) -> None:
    """Refuse ratings that break the seed's rules: hardest 8-10, softest 1-3, strictly decreasing.

    ranking: zone numbers hardest first; ratings: the integer rating of each zone in the same order.
    """
    r = [int(v) for v in ratings]
    if len(r) != len(ranking):
        raise InputError(f"ratings: expected {len(ranking)} numbers, got {len(r)}")
    if r[0] not in HARDEST_RATINGS:
        raise InputError(f"ratings: the hardest zone must get 8, 9 or 10, got {r[0]}")
    if r[-1] not in SOFTEST_RATINGS:
        raise InputError(f"ratings: the softest zone must get 1, 2 or 3, got {r[-1]}")
    if any(a <= b for a, b in zip(r, r[1:])):
        raise InputError(f"ratings {r}: expected strictly decreasing numbers from hardest to softest")


def ratings_from_positions(ranking, position, hardest: int, softest: int) -> list:
    """Ratings (hardest first) from remembered hardness positions in [0, 1] of the middle zones.

    position: (n,) position of each ranked zone on the participant's scale (0 softest, 1 hardest);
    the ends are pinned to `hardest` and `softest`; the middle ones are rounded and kept strictly
    decreasing and inside (softest, hardest).
    """
    n = len(ranking)
    p = np.clip(np.asarray(position, dtype=float), 0.0, 1.0)
    ratings = [hardest] + [int(np.rint(softest + p[i] * (hardest - softest))) for i in range(1, n - 1)] + [softest]
    for i in range(1, n - 1):  # keep room below for the remaining zones, and strictly below the previous
        lo = softest + (n - 1 - i)
        ratings[i] = int(min(max(ratings[i], lo), ratings[i - 1] - 1))
    return ratings
