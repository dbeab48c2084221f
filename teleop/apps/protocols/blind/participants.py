"""Simulated participants who judge hardness only from the force the stylus rendered during their pushes.

Perception model:
- each poke gives a stiffness k = dF/dx of its loading phase (stats.loading_slope, a Theil-Sen fit), from
  the rendered force against the participant's own stylus displacement; forces below a detection threshold
  are not felt;
- the percept is log k plus Gaussian noise (Weber's law: noise constant in log stiffness). The stiffness
  JND is the Weber fraction J at 75 % correct in a two-interval comparison, so one percept has
  sigma = ln(1 + J) / (sqrt(2) z_0.75). Default J = 0.23: Jones & Hunter (1990), "A perceptual analysis of
  stiffness", Experimental Brain Research 79:150-156 (stiffness Weber fraction 23 %);
- a remembered zone drifts (random walk, `memory_noise` in log stiffness per palpation of another zone)
  and is refreshed when poked again;
- a difference below ln(1 + J) leaves the participant unsure: both zones are poked again, up to
  `max_repeats` times, then the participant answers anyway;
- a participant presses until the stylus force reaches a comfortable level or the hand has travelled its
  push depth, whichever comes first; push depth, speed and press force vary per participant (person
  level) and per poke (log-normal spreads).

Ratings (the `rating` rule a participant is made with; the study's, `run_simulated_study(rating=...)`):
- "positions" (the former rule): the hardest zone gets a draw from 8-10, the softest one from 1-3, the middle
  ones 60 % even spacing and 40 % remembered magnitude between them. The ends and most of the middle are set
  by the rule, so only the ranking is an outcome of what was felt.
- "anchored": every rating is read off a log-stiffness scale anchored by two training pads. Before the
  study the coordinator lets the participant press the hardest and the softest pad, named as "about 9" and
  "about 2" (the middles of the seed's bands for the hardest, 8-10, and the softest, 1-3, zone); their
  percepts (the same Weber noise, TRAINING_POKES presses each) fix the scale, and each zone's rating is
  RATING_SOFT + (RATING_HARD - RATING_SOFT) (L - L_soft) / (L_hard - L_soft), rounded and clipped to 1-10,
  with L the zone's remembered log stiffness and the anchors' memories drifting like any other zone's
  (`memory_noise` per press of another pad). No pad's rating is fixed: the ends move with what the chain
  renders in the study against what it rendered in training, the middle ones with where their stiffness
  falls between the anchors; the ranking comes from the comparisons as before, so a rating may tie or
  disagree with it (the seed's protocol asked for numbers after the ranking, ours keep both as felt).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from teleop.apps.protocols.blind.probe import Poke, PokeRequest, PressAborted
from teleop.apps.protocols.blind.protocol import HARDER, SOFTER, UNSURE, Compare, ratings_from_positions
from teleop.apps.protocols.blind.stats import loading_slope
from teleop.core.errors import InputError

Z75 = 0.6744897501960817  # standard normal quantile at 0.75
K_FLOOR = 1.0              # [N/m] what "nothing felt" is perceived as (log of zero is undefined)
GENTLER = 0.7              # a press the rig stopped is repeated at this fraction of its force (or depth)

# random streams of one participant, keyed so the same poke gets the same motor and noise draws whatever
# the JND (common random numbers across the points of a JND curve)
_PERSON, _MOTOR, _NOISE, _MEMORY, _RATING, _TRAIN_MOTOR, _TRAIN_NOISE = range(7)
RATING_RULES = ("positions", "anchored")
RATING_HARD, RATING_SOFT = 9.0, 2.0  # the anchored scale's training pads: middles of the seed's 8-10 and 1-3
TRAINING_POKES = 2                   # presses of each training pad before the study (rating "anchored")


def weber_sigma(jnd: float) -> float:
    """Noise std of one log-stiffness percept for a Weber fraction `jnd` (75 % correct, two intervals)."""
    return math.log1p(jnd) / (math.sqrt(2.0) * Z75)


@dataclass(frozen=True)
class ParticipantParams:
    """A simulated participant population.

    Attributes:
        jnd: stiffness Weber fraction (see module docstring; Jones & Hunter 1990: 0.23).
        depth: mean travel of the hand's push target along the stylus axis [m] (the stylus itself stops
            short of it against the rendered force).
        speed: mean speed of the hand's push target [m/s].
        person_spread: log-normal std of a person's own mean depth and speed around the population's.
        poke_spread: log-normal std of depth and speed from one poke to the next.
        memory_noise: drift of a remembered log stiffness per palpation of another zone.
        force_threshold: smallest force felt on the stylus [N].
        force: mean stylus force at which a participant stops pressing [N] (the pressure exploratory
            procedure of Lederman & Klatzky 1987, Cognitive Psychology 19:342-368: press until the force is
            comfortable; LaMotte 2000, J Neurophysiol 83:1777, subjects pressing rubber with a stylus); the
            depth still caps the press, so soft areas are pressed to `depth` and stiff ones to this force.
            Default 0.2 N, set by what the robot can take on the rigid area: at the rig's force scale (0.1)
            it asks 2 N of the tip, and the stylus force lags the contact (~7 ms, see the rig), so a press
            stops late by ~0.6 N more on rigid (9.1 kN/m x 10 mm/s at the tip x 7 ms). The heaviest
            pressers (2.5 sigma of the person and poke spreads: x1.57) then put ~3.9 N on the tip, under
            the ~5.5 N along z that cable tensions in [0.2, 5.5] N hold at the home pose (a 5.7 N press
            with 1.4 N sideways faulted the loop, measured); at 0.3 N they reach it, and presses the robot
            stops are repeated more gently (max_aborts). Depth pushes (None; --press-force 0) drive rigid
            past the cables' limit every time.
        max_repeats: extra pokes of an unsure pair before answering anyway.
        max_aborts: presses the rig may stop in a row (the robot faulted, the stylus went limp) before the
            participant gives up; each one is repeated at GENTLER times its force (or depth, for depth
            pushes), as a coordinator would ask after resetting the robot.
        spacing: weight of even spacing (vs remembered magnitude) when placing the middle ratings (rating
            rule "positions").
    """

    jnd: float = 0.23
    depth: float = 0.008
    speed: float = 0.020
    person_spread: float = 0.15
    poke_spread: float = 0.10
    memory_noise: float = 0.05
    force_threshold: float = 0.02
    max_repeats: int = 2
    max_aborts: int = 3
    spacing: float = 0.6
    force: float | None = 0.2

    def __post_init__(self):
        checks = {"jnd": self.jnd > 0, "depth": self.depth > 0, "speed": self.speed > 0,
                  "person_spread": self.person_spread >= 0, "poke_spread": self.poke_spread >= 0,
                  "memory_noise": self.memory_noise >= 0, "force_threshold": self.force_threshold >= 0,
                  "max_repeats": self.max_repeats >= 0, "max_aborts": self.max_aborts >= 0,
                  "spacing": 0 <= self.spacing <= 1,
                  "force": self.force is None or self.force > 0}
        for name, ok in checks.items():
            value = getattr(self, name)
            if not ok or (value is not None and not math.isfinite(value)):
                raise InputError(f"participant parameter {name}={value!r} is out of range")


class SimulatedParticipant:
    """One participant: pokes zones through `palpate(zone, request) -> Poke` and answers the protocol.

    seed: the participant's own entropy (e.g. (study seed, participant number)); all draws derive from it.
    rating: how the ranking becomes ratings (RATING_RULES, module docstring); "anchored" needs `train` first.
    """

    def __init__(self, params: ParticipantParams, palpate, seed, rating: str = "positions"):
        check_rating_rule(rating)
        self.rating = rating
        self.params = params
        self._palpate = palpate
        self._seed = tuple(int(s) for s in np.atleast_1d(seed))
        person = self._rng(_PERSON)
        self.depth = params.depth * math.exp(params.person_spread * person.standard_normal())
        self.speed = params.speed * math.exp(params.person_spread * person.standard_normal())
        self.force = (None if params.force is None
                      else params.force * math.exp(params.person_spread * person.standard_normal()))
        self._sigma = weber_sigma(params.jnd)
        self._percepts: dict[int, list] = {}
        self._drift: dict[int, float] = {}
        self._memory = self._rng(_MEMORY)
        self.pokes: list = []  # (zone, Poke, slope [N/m])
        self.aborted = 0       # presses the rig stopped (PressAborted), each repeated more gently

    def _rng(self, stream: int, *key) -> np.random.Generator:
        return np.random.default_rng((*self._seed, stream, *key))

    def _press(self, palpate, key, motor: np.random.Generator, noise: np.random.Generator) -> tuple:
        """One press through `palpate(key, request)`: (log-stiffness percept, Poke, loading slope [N/m])."""
        p = self.params
        depth = self.depth * math.exp(p.poke_spread * motor.standard_normal())
        speed = self.speed * math.exp(p.poke_spread * motor.standard_normal())
        force = None if self.force is None else self.force * math.exp(p.poke_spread * motor.standard_normal())
        request = PokeRequest(depth=depth, speed=speed, force=force)
        for attempt in range(p.max_aborts + 1):
            try:
                trace: Poke = palpate(key, request)
                break
            except PressAborted:  # the stylus went limp: press again, more gently
                self.aborted += 1
                if attempt == p.max_aborts:
                    raise
                request = (PokeRequest(request.depth * GENTLER, request.speed) if request.force is None else
                           PokeRequest(request.depth, request.speed, request.force * GENTLER))
        k = loading_slope(trace.x, trace.f, p.force_threshold)
        return math.log(max(k, K_FLOOR)) + self._sigma * noise.standard_normal(), trace, k

    def _blur(self, pressed) -> None:
        """Feeling `pressed` blurs the memory of every other zone and training pad."""
        for other in self._drift:
            if other != pressed:
                self._drift[other] += self.params.memory_noise * self._memory.standard_normal()

    def poke(self, zone: int) -> float:
        """Push on `zone` once and remember it; returns the log-stiffness percept."""
        n = len(self._percepts.get(zone, []))
        percept, trace, k = self._press(self._palpate, zone, self._rng(_MOTOR, zone, n), self._rng(_NOISE, zone, n))
        self._blur(zone)
        self._percepts.setdefault(zone, []).append(percept)
        self._drift[zone] = 0.0
        self.pokes.append((zone, trace, k))
        return percept

    def train(self, press_pad) -> None:
        """Press the two training pads (rating "anchored"): press_pad(anchor, request) -> Poke, anchor 0 the
        hardest pad (rated RATING_HARD), 1 the softest (RATING_SOFT). Their percepts anchor the scale."""
        for anchor in (0, 1):
            key = ("train", anchor)
            for n in range(TRAINING_POKES):
                percept, _trace, _k = self._press(press_pad, anchor, self._rng(_TRAIN_MOTOR, anchor, n),
                                                  self._rng(_TRAIN_NOISE, anchor, n))
                self._blur(key)
                self._percepts.setdefault(key, []).append(percept)
                self._drift[key] = 0.0

    def remembered(self, zone: int) -> float:
        return float(np.mean(self._percepts[zone])) + self._drift[zone]

    def compare(self, step: Compare) -> str:
        """Answer HARDER / SOFTER (zone step.new vs step.ref) or UNSURE (asks for more pokes)."""
        if step.repeat > 0:
            self.poke(step.ref)
            self.poke(step.new)
        else:
            for zone in (step.ref, step.new):
                if zone not in self._percepts:
                    self.poke(zone)
        d = self.remembered(step.new) - self.remembered(step.ref)
        if abs(d) < math.log1p(self.params.jnd) and step.repeat < self.params.max_repeats:
            return UNSURE
        return HARDER if d > 0 else SOFTER

    def rate(self, ranking) -> list:
        """Ratings of the ranked zones (hardest first), by the rule `params.rating` (module docstring)."""
        if self.rating == "anchored":
            return self.rate_anchored(ranking)
        rng = self._rng(_RATING)
        hardest, softest = int(rng.integers(8, 11)), int(rng.integers(1, 4))
        L = np.array([self.remembered(z) for z in ranking])
        span = L[0] - L[-1]
        magnitude = (L - L[-1]) / span if span > 0 else np.linspace(1.0, 0.0, len(ranking))
        even = np.linspace(1.0, 0.0, len(ranking))
        s = self.params.spacing
        return ratings_from_positions(ranking, s * even + (1 - s) * magnitude, hardest, softest)

    def rate_anchored(self, ranking) -> list:
        """Ratings (hardest first) read off the scale the training pads anchor (`train` first)."""
        key_hard, key_soft = ("train", 0), ("train", 1)
        if key_hard not in self._percepts or key_soft not in self._percepts:
            raise InputError("anchored ratings need the training pads pressed first (SimulatedParticipant.train)")
        return anchored_ratings([self.remembered(z) for z in ranking], self.remembered(key_hard),
                                self.remembered(key_soft))


def check_rating_rule(rating: str) -> None:
    """Refuse a rating rule not in RATING_RULES (InputError naming it)."""
    if rating not in RATING_RULES:
        raise InputError(f"rating rule {rating!r}: expected one of {', '.join(RATING_RULES)}")


def anchored_ratings(percepts, hard: float, soft: float) -> list:
    """Integer ratings 1-10 of log-stiffness percepts on the scale where `hard` reads RATING_HARD and `soft`
    RATING_SOFT (log stiffness of the training pads); anchors felt the wrong way round (hard <= soft) leave
    no scale, and every zone reads the scale's middle."""
    L = np.asarray(percepts, dtype=float)
    span = hard - soft
    pos = (L - soft) / span if span > 0 else np.full(L.shape, 0.5)
    r = RATING_SOFT + (RATING_HARD - RATING_SOFT) * pos
    return [int(v) for v in np.clip(np.rint(r), 1, 10)]
