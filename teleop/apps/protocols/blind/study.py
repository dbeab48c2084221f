"""Running the blind study with simulated participants on a rig, and its results (Table 3 and more).

The driver plays the coordinator: it lays out the pad for each participant, picks the presentation order
(both by seed), turns a zone into a pad slot when the participant pokes, and records the answers. The
participant only ever receives `Poke` traces.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Protocol

import numpy as np

from teleop.apps.protocols.blind.participants import ParticipantParams, SimulatedParticipant, check_rating_rule
from teleop.apps.protocols.blind.probe import Poke, PokeRequest
from teleop.apps.protocols.blind.protocol import Compare, next_step, presentation
from teleop.apps.protocols.blind.stats import SEED_TABLE3, kendall_tau, kendall_w, mean_std
from teleop.core.errors import InputError
from teleop.io.figures import legend_outside
from teleop.io.outputs import save_figure

_LAYOUT = 100  # random stream of the coordinator (layout and presentation), apart from the participant's


@dataclass(frozen=True)
class Area:
    """One pad area: catalogue key, display label and the pad's true contact stiffness [N/m]."""

    name: str
    label: str
    stiffness: float


class Rig(Protocol):
    """A pad with len(areas) slots that can be rearranged and poked (simulated or real)."""

    areas: tuple  # Area, hardest first (the true order)

    def arrange(self, layout: tuple) -> None:
        """Place area `layout[i]` (an Area.name) in slot i."""

    def poke(self, slot: int, request: PokeRequest) -> Poke: ...


@dataclass(frozen=True)
class ParticipantRecord:
    """One participant's session.

    Attributes:
        participant: 1-based number.
        layout: area name in each pad slot.
        order: area name presented as zone 1, 2, ... .
        answers: (new zone, reference zone, answer) per question, zones 1-based.
        ranking: area names, hardest first, as the participant ranked them.
        ratings: area name -> rating (1-10).
        pokes: number of pokes.
        slopes: area name -> loading slopes dF/dx [N/m] of every poke the participant made there.
        aborted: presses the rig stopped (robot fault) and the participant repeated more gently.
    """

    participant: int
    layout: tuple
    order: tuple
    answers: tuple
    ranking: tuple
    ratings: dict
    pokes: int = 0
    slopes: dict = field(default_factory=dict)
    aborted: int = 0


def coordinator_draws(seed: int, participant: int, areas) -> tuple:
    """(layout, order): the pad layout (area name per slot) and presentation order (slot per zone)."""
    rng = np.random.default_rng((int(seed), int(participant), _LAYOUT))
    names = [a.name for a in areas]
    layout = tuple(names[i] for i in rng.permutation(len(names)))
    order = presentation(rng, len(names))
    return layout, order


def run_participant(palpate: Callable, n_zones: int, params: ParticipantParams, entropy,
                    train: Callable | None = None, rating: str = "positions") -> tuple:
    """Take one simulated participant through the protocol.

    palpate(zone, request) -> Poke; train(anchor, request) -> Poke presses the training pads (anchor 0 the
    hardest, 1 the softest; needed by the rating rule "anchored", pressed before the first zone); rating:
    participants.RATING_RULES. Returns
    (answers [(Compare, answer)], ranking (zones, hardest first), ratings (hardest first), participant).
    """
    person = SimulatedParticipant(params, palpate, entropy, rating)
    if rating == "anchored":
        if train is None:
            raise InputError("the anchored rating rule needs training pads to press (run_participant's train)")
        person.train(train)
    answers = []
    step = next_step(n_zones, answers)
    while isinstance(step, Compare):
        answers.append((step, person.compare(step)))
        step = next_step(n_zones, answers)
    ratings = person.rate(step.ranking)
    return answers, step.ranking, ratings, person


def record_from(participant: int, layout, order, answers, ranking, ratings, person=None) -> ParticipantRecord:
    """A ParticipantRecord from the protocol's zone-level results (zones -> area names via layout/order)."""
    zone_area = [layout[slot] for slot in order]
    slopes: dict = {}
    if person is not None:
        for zone, _trace, k in person.pokes:
            slopes.setdefault(zone_area[zone], []).append(float(k))
    return ParticipantRecord(
        participant=participant, layout=tuple(layout), order=tuple(zone_area),
        answers=tuple((s.new + 1, s.ref + 1, a) for s, a in answers),
        ranking=tuple(zone_area[z] for z in ranking),
        ratings={zone_area[z]: int(r) for z, r in zip(ranking, ratings)},
        pokes=0 if person is None else len(person.pokes), slopes=slopes,
        aborted=0 if person is None else person.aborted)


def run_simulated_study(rig: Rig, participants: int, seed: int, params: ParticipantParams,
                        progress=None, rating: str = "positions") -> "StudyResult":
    """`participants` simulated participants on `rig`; `progress` (optional) is called after each one;
    `rating`: the rule that turns a participant's ranking into ratings (participants.RATING_RULES; "anchored":
    the rig's hardest and softest areas are the training pads)."""
    check_rating_rule(rating)
    areas = tuple(rig.areas)
    records = []
    for p in range(1, participants + 1):
        layout, order = coordinator_draws(seed, p, areas)
        rig.arrange(layout)

        def palpate(zone, request, _order=order):
            return rig.poke(_order[zone], request)

        def train(anchor, request, _layout=layout):  # the training pads: the hardest and the softest area
            return rig.poke(_layout.index(areas[0 if anchor == 0 else -1].name), request)

        answers, ranking, ratings, person = run_participant(palpate, len(areas), params, (seed, p), train, rating)
        records.append(record_from(p, layout, order, answers, ranking, ratings, person))
        if progress is not None:
            progress()
    return StudyResult(areas=areas, records=tuple(records))


@dataclass(frozen=True)
class StudyResult:
    """Results of a blind study: per-participant records and the statistics of Table 3 and beyond.

    areas: Area, hardest first (the true order); records: ParticipantRecord per participant; config: the
    settings, stored in the JSON; expected: what a transparent chain would render per area (rig-dependent).
    """

    areas: tuple
    records: tuple
    config: dict = field(default_factory=dict)
    expected: dict = field(default_factory=dict)  # area name -> stiffness a transparent chain renders [N/m]

    @property
    def truth(self) -> tuple:
        return tuple(a.name for a in self.areas)

    def ratings(self) -> np.ndarray:
        """(participants, areas) ratings, areas in the true order."""
        return np.array([[r.ratings[a] for a in self.truth] for r in self.records], dtype=float)

    @property
    def correct_ranking_rate(self) -> float:
        return float(np.mean([r.ranking == self.truth for r in self.records]))

    @property
    def kendall_tau_mean(self) -> float:
        return float(np.mean([kendall_tau(r.ranking, self.truth) for r in self.records]))

    @property
    def kendall_w(self) -> float:
        return kendall_w(self.ratings())

    def mean_std(self) -> dict:
        """area name -> (mean, std) of the ratings."""
        R = self.ratings()
        return {a: mean_std(R[:, i]) for i, a in enumerate(self.truth)}

    def rendered_stiffness(self) -> dict:
        """area name -> median loading slope dF/dx [N/m] felt on the stylus over every poke (None if none)."""
        out = {}
        for a in self.truth:
            ks = [k for r in self.records for k in r.slopes.get(a, [])]
            out[a] = float(np.median(ks)) if ks else None
        return out

    def neighbour_ratios(self) -> list:
        """[(harder, softer, rendered ratio, true ratio, relative error, pad ratio)] for neighbouring areas.

        The true ratio is that of the stiffness a transparent chain renders (`expected`: the pads in series
        with the robot's own stiffness) when the rig gives it, else that of the pads alone (pad ratio)."""
        rendered = self.rendered_stiffness()
        out = []
        for hi, lo in zip(self.areas, self.areas[1:]):
            pad = hi.stiffness / lo.stiffness
            true = self.expected[hi.name] / self.expected[lo.name] if self.expected else pad
            kr_hi, kr_lo = rendered[hi.name], rendered[lo.name]
            ratio = kr_hi / kr_lo if kr_hi is not None and kr_lo else None
            err = (ratio / true - 1.0) if ratio is not None else None
            out.append((hi.name, lo.name, ratio, true, err, pad))
        return out

    def to_dict(self) -> dict:
        """The JSON (docs/formats.md): per participant order and ratings, "mean", "std", "correct_ranking_rate",
        "kendall_tau_mean", plus Kendall's W, the rendered and true stiffness and the seed's Table 3."""
        ms = self.mean_std()
        rendered = self.rendered_stiffness()
        return {
            "participants": [
                {"participant": r.participant, "layout": list(r.layout), "order": list(r.order),
                 "ratings": {a: r.ratings[a] for a in self.truth}, "ranking": list(r.ranking),
                 "correct": r.ranking == self.truth, "kendall_tau": kendall_tau(r.ranking, self.truth),
                 "pokes": r.pokes, "aborted_presses": r.aborted, "answers": [list(a) for a in r.answers]}
                for r in self.records],
            "mean": {a: ms[a][0] for a in self.truth},
            "std": {a: ms[a][1] for a in self.truth},
            "correct_ranking_rate": self.correct_ranking_rate,
            "kendall_tau_mean": self.kendall_tau_mean,
            "kendall_w": self.kendall_w,
            "true_order": list(self.truth),
            "labels": {a.name: a.label for a in self.areas},
            "true_stiffness_N_per_m": {a.name: a.stiffness for a in self.areas},
            "rendered_stiffness_N_per_m": rendered,
            "expected_stiffness_N_per_m": dict(self.expected),
            "neighbour_ratios": [{"harder": h, "softer": s, "rendered": r, "true": t, "relative_error": e,
                                  "pad": pad} for h, s, r, t, e, pad in self.neighbour_ratios()],
            "seed_table3": {a: {"mean": row["mean"], "std": row["std"]} for a, row in zip(self.truth, SEED_TABLE3)},
            "config": self.config,
        }

    def table(self) -> str:
        """Table 3's layout (ratings per participant, mean and std per area) beside the seed's numbers."""
        ms = self.mean_std()
        n = len(self.records)
        width = max(len(a.label) for a in self.areas) + 2
        head = "area".ljust(width) + "".join(f"{r.participant:>4}" for r in self.records)
        head += "   mean   std | seed mean   std"
        lines = [head]
        for area, seed_row in zip(self.areas, SEED_TABLE3):
            m, s = ms[area.name]
            row = area.label.ljust(width) + "".join(f"{r.ratings[area.name]:>4}" for r in self.records)
            row += f" {m:6.2f} {s:5.2f} | {seed_row['mean']:9.1f} {seed_row['std']:5.2f}"
            lines.append(row)
        lines.append("")
        lines.append(f"participants {n}: correct ranking {self.correct_ranking_rate:.0%}, "
                     f"Kendall tau mean {self.kendall_tau_mean:.3f}, Kendall W {self.kendall_w:.3f}")
        aborted = sum(r.aborted for r in self.records)
        if aborted:
            lines.append(f"presses the robot stopped (cable tension out of range) and repeated more gently: {aborted} "
                         f"of {sum(r.pokes for r in self.records) + aborted}")
        rendered = self.rendered_stiffness()
        if any(v is not None for v in rendered.values()):
            lines.append("")
            head = "area".ljust(width) + " rendered dF/dx [N/m]   pad stiffness [N/m]"
            lines.append(head + ("   transparent chain [N/m]" if self.expected else ""))
            for a in self.areas:
                k = rendered[a.name]
                ks = "        -" if k is None else f"{k:9.1f}"
                row = a.label.ljust(width) + f" {ks:>20}   {a.stiffness:19.1f}"
                if a.name in self.expected:
                    row += f"   {self.expected[a.name]:23.1f}"
                lines.append(row)
            lines.append("")
            true_head = "transparent ratio" if self.expected else "       true ratio"
            lines.append("neighbours".ljust(2 * width) + f" rendered ratio   {true_head}   error   pad ratio")
            labels = {a.name: a.label for a in self.areas}
            for h, s, r, t, e, pad in self.neighbour_ratios():
                pair = f"{labels[h]} / {labels[s]}"
                rs = "     -" if r is None else f"{r:6.2f}"
                es = "     -" if e is None else f"{e:+6.0%}"
                lines.append(pair.ljust(2 * width) + f" {rs:>14}   {t:17.2f}   {es}   {pad:9.2f}")
        return "\n".join(lines)

    def plot(self, path) -> None:
        """PNG: ratings per area (box plot, seed's means marked) and rendered vs true stiffness (log-log)."""
        import matplotlib  # heavy: loaded only to draw

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # heavy: loaded only to draw

        R = self.ratings()
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5.5))
        labels = [a.label for a in self.areas]
        ax1.boxplot([R[:, i] for i in range(R.shape[1])])
        ax1.set_xticks(range(1, len(labels) + 1), labels)
        ax1.plot([], [], color="C1", label="simulated participants: median, quartiles, range")  # the boxes
        ax1.plot(range(1, len(labels) + 1), [row["mean"] for row in SEED_TABLE3], "r*", ms=10,
                 label="seed 000 Table 3 mean")
        ax1.set_ylabel("rating (1 soft - 10 hard) [-]")
        ax1.set_ylim(0, 11)
        ax1.set_yticks(range(0, 11, 2))
        ax1.set_title(f"{len(self.records)} participants, correct ranking {self.correct_ranking_rate:.0%}")
        legend_outside(ax1, "below")
        ax1.tick_params(axis="x", labelrotation=15)
        rendered = self.rendered_stiffness()
        pts = [(a.stiffness, rendered[a.name], a.label) for a in self.areas if rendered[a.name]]
        if pts:
            k_true, k_r, names = zip(*pts)
            ax2.loglog(k_true, k_r, "o-", label="rendered on the stylus (median over the presses)")
            ax2.set_xlim(min(k_true) / 1.5, max(k_true) * 3)  # room for the labels of the end points
            for x, y, s in pts:
                ax2.annotate(s, (x, y), textcoords="offset points", xytext=(5, -10), fontsize=8)
            # a perfectly transparent chain keeps every ratio: a line of slope 1 through the geometric mean
            g = np.exp(np.mean(np.log(k_r)) - np.mean(np.log(k_true)))
            xs = np.array([min(k_true), max(k_true)])
            ax2.loglog(xs, g * xs, "k--", lw=0.8, label="ratios kept (slope 1)")
            if self.expected:
                ax2.loglog([a.stiffness for a in self.areas], [self.expected[a.name] for a in self.areas], "s:",
                           color="grey", label="transparent chain (robot compliance in series)")
            legend_outside(ax2, "below")
        ax2.set_xlabel("pad stiffness [N/m]")
        ax2.set_ylabel("rendered on the stylus dF/dx [N/m]")
        ax2.set_title("transparency of the chain")
        fig.suptitle(self.figure_title(), fontsize=10)
        fig.tight_layout()
        save_figure(fig, path)

    def figure_title(self) -> str:
        """What the study figure is: the test, who rated (simulated or real participants) and, for the
        simulated robot, its plant and sensor."""
        c = self.config
        if c.get("operator") == "human":
            return (f"teleop blind-test: blind stiffness ranking (seed 000 Table 3), human participants, "
                    f"seed {c.get('seed')}")
        rig = c.get("rig", {})
        return (f"teleop blind-test: blind stiffness ranking (seed 000 Table 3), simulated participants and robot\n"
                f"plant {rig.get('plant', 'matched')}, sensor {rig.get('sensor', 'fsr')}, seed {c.get('seed')}")
