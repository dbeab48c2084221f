"""Simulated participants and the study driver against a spring test double (the logic, not the chain:
the chain is tested through the real loop in test_blind_rig.py)."""

import numpy as np
import pytest

from teleop.core.errors import InputError
from teleop.apps.protocols.blind.participants import ParticipantParams, SimulatedParticipant, weber_sigma
from teleop.apps.protocols.blind.probe import Poke
from teleop.apps.protocols.blind.protocol import HARDER, SOFTER, UNSURE, Compare, check_ratings
from teleop.apps.protocols.blind.study import Area, run_simulated_study

AREAS = (Area("pla", "rigid PLA", 1.0e5), Area("dragon_skin_30", "Dragon Skin 30", 6671.0),
         Area("ecoflex_00_50", "Ecoflex 00-50", 827.0), Area("ecoflex_00_20", "Ecoflex 00-20", 393.0))


class SpringRig:
    """Test double: the stylus feels gain * k of the area under the slot, capped like a device."""

    def __init__(self, areas, gain=0.05, cap=3.0):
        self.areas = areas
        self.k = {a.name: a.stiffness for a in areas}
        self.gain, self.cap = gain, cap
        self.layout = None
        self.requests = []

    def arrange(self, layout):
        self.layout = layout

    def poke(self, slot, request):
        self.requests.append(request)
        n = 100
        x = np.r_[np.linspace(0, request.depth, n), np.linspace(request.depth, 0, n)]
        k = self.gain * self.k[self.layout[slot]]
        f = np.minimum(k * np.maximum(x - 0.0005, 0), self.cap)
        t = np.r_[np.linspace(0, 1, 2 * n)] * 2 * request.depth / request.speed
        return Poke(t=t, x=x, f=f)


def test_weber_sigma_gives_75_percent_at_one_jnd():
    from scipy.stats import norm

    for j in (0.1, 0.23, 0.4):
        s = weber_sigma(j)
        assert norm.cdf(np.log1p(j) / (np.sqrt(2) * s)) == pytest.approx(0.75)


def test_perfect_rendering_every_participant_ranks_right():
    rig = SpringRig(AREAS)
    res = run_simulated_study(rig, 10, seed=1, params=ParticipantParams())
    assert res.correct_ranking_rate == 1.0 and res.kendall_tau_mean == 1.0
    for r in res.records:
        check_ratings(range(4), [r.ratings[a.name] for a in AREAS])
    assert res.kendall_w == pytest.approx(1.0)
    # rendered slopes follow the rig: neighbour ratios as rendered by the (uncapped) double
    assert res.rendered_stiffness()["ecoflex_00_50"] == pytest.approx(0.05 * 827.0, rel=0.02)


def test_participants_vary_their_pushes():
    rig = SpringRig(AREAS)
    run_simulated_study(rig, 5, seed=3, params=ParticipantParams())
    depths = np.array([r.depth for r in rig.requests])
    speeds = np.array([r.speed for r in rig.requests])
    assert depths.std() / depths.mean() > 0.08 and speeds.std() / speeds.mean() > 0.08


def test_pressing_participants_ask_for_a_force_near_their_own_and_depth_pushers_for_none():
    rig = SpringRig(AREAS)
    run_simulated_study(rig, 5, seed=3, params=ParticipantParams())  # default: press to ~0.2 N
    forces = np.array([r.force for r in rig.requests])
    assert 0.15 < forces.mean() < 0.3 and forces.std() > 0.02
    rig = SpringRig(AREAS)
    run_simulated_study(rig, 2, seed=3, params=ParticipantParams(force=None))
    assert all(r.force is None for r in rig.requests)
    with pytest.raises(InputError):
        ParticipantParams(force=-1.0)


def test_flat_rendering_gives_chance_rankings():
    flat = tuple(Area(a.name, a.label, 500.0) for a in AREAS)  # the rig renders every area alike
    rig = SpringRig(flat)
    res = run_simulated_study(rig, 40, seed=2, params=ParticipantParams())
    res = type(res)(areas=AREAS, records=res.records)  # score against the real order
    assert res.correct_ranking_rate < 0.2
    assert abs(res.kendall_tau_mean) < 0.35


def test_unsure_participant_asks_for_more_pokes_then_answers():
    n_unsure = []
    for seed in range(12):
        calls = []

        def palpate(zone, request):
            calls.append(zone)
            x = np.linspace(0, request.depth, 50)
            return Poke(t=x / request.speed, x=x, f=100.0 * x)  # the same spring under every zone

        p = SimulatedParticipant(ParticipantParams(max_repeats=2), palpate, (seed, 1))
        step, answers = Compare(1, 0, 0), []
        while True:
            answers.append(p.compare(step))
            if answers[-1] != UNSURE:
                break
            step = Compare(1, 0, step.repeat + 1)
        assert answers[-1] in (HARDER, SOFTER) and len(answers) <= 3  # after max_repeats it must answer
        assert len(calls) == 2 + 2 * (len(answers) - 1)                # each unsure pokes both zones again
        n_unsure.append(len(answers) - 1)
    assert 0 < sum(n_unsure)  # equal springs leave participants unsure at times


def test_larger_jnd_lowers_accuracy_on_close_stiffnesses():
    close = (Area("a", "A", 1300.0), Area("b", "B", 1000.0), Area("c", "C", 770.0), Area("d", "D", 600.0))
    acc = {}
    for jnd in (0.1, 0.6):
        rig = SpringRig(close, gain=1.0, cap=100.0)
        res = run_simulated_study(rig, 40, seed=5, params=ParticipantParams(jnd=jnd))
        acc[jnd] = res.correct_ranking_rate
    assert acc[0.1] >= acc[0.6] + 0.3


def test_jnd_curve_shares_pushes_across_jnds_and_accuracy_falls_with_jnd():
    from teleop.apps.bench.blind_jnd import parse_jnds
    from teleop.apps.campaign.blind import jnd_curve, wilson

    assert parse_jnds("0.4, 23%,0.1") == [0.1, 0.23, 0.4]
    lo, hi = wilson(50, 100)
    assert lo < 0.5 < hi and hi - lo == pytest.approx(0.19, abs=0.01)
    close = (Area("a", "A", 1300.0), Area("b", "B", 1000.0), Area("c", "C", 770.0), Area("d", "D", 600.0))
    rig = SpringRig(close, gain=1.0, cap=100.0)
    curve = jnd_curve(rig, [0.05, 0.8], 30, seed=4, base_params=ParticipantParams())
    lo_j, hi_j = curve[0.05], curve[0.8]
    assert [r.layout for r in lo_j.records] == [r.layout for r in hi_j.records]
    # the k-th push on an area is the same push at every JND: the rig is poked once per distinct push,
    # i.e. per participant and area as often as the more demanding JND needed
    distinct = sum(max(len(a.slopes.get(x.name, [])), len(b.slopes.get(x.name, [])))
                   for a, b in zip(lo_j.records, hi_j.records) for x in close)
    assert len(rig.requests) == distinct < sum(r.pokes for c in curve.values() for r in c.records)
    assert lo_j.correct_ranking_rate >= hi_j.correct_ranking_rate + 0.3


def test_a_press_the_rig_stops_is_repeated_more_gently_then_given_up():
    from teleop.apps.protocols.blind.participants import GENTLER
    from teleop.apps.protocols.blind.probe import PressAborted

    asked = []

    def palpate(zone, request):  # the robot stops every press above 0.2 N
        asked.append(request)
        if request.force > 0.2:
            raise PressAborted("blind-test rig: the loop faulted")
        x = np.linspace(0, request.depth, 50)
        return Poke(t=x / request.speed, x=x, f=100.0 * x)

    p = SimulatedParticipant(ParticipantParams(force=0.35, person_spread=0.0, poke_spread=0.0), palpate, (1, 1))
    p.poke(0)
    assert [r.force for r in asked] == pytest.approx([0.35, 0.35 * GENTLER, 0.35 * GENTLER ** 2])
    assert p.aborted == 2 and len(p.pokes) == 1
    p = SimulatedParticipant(ParticipantParams(force=2.0, max_aborts=1), palpate, (1, 1))
    with pytest.raises(PressAborted):
        p.poke(0)


def test_anchored_ratings_read_the_scale_the_training_pads_set():
    from teleop.apps.protocols.blind.participants import RATING_HARD, RATING_SOFT, anchored_ratings

    hard, soft = np.log(500.0), np.log(20.0)
    assert anchored_ratings([hard, soft], hard, soft) == [RATING_HARD, RATING_SOFT]
    mid = 0.5 * (hard + soft)
    assert anchored_ratings([mid], hard, soft) == [round(0.5 * (RATING_HARD + RATING_SOFT))]
    assert anchored_ratings([hard + 5.0, soft - 5.0], hard, soft) == [10, 1]     # clipped to the 1-10 scale
    assert anchored_ratings([hard, soft], soft, hard) == [6, 6]                  # no scale: the middle


def test_anchored_rule_fixes_no_rating_each_follows_what_was_felt():
    """Same participants (same seed), the rig renders the middle pads twice as stiff: with the anchored rule
    their ratings rise; with the positions rule the ranking is unchanged and so (mostly) are the ratings."""
    anchored = {"params": ParticipantParams(), "rating": "anchored"}
    base = run_simulated_study(SpringRig(AREAS), 6, seed=3, **anchored)
    stiffer = tuple(Area(a.name, a.label, a.stiffness * (2.0 if i in (1, 2) else 1.0)) for i, a in enumerate(AREAS))
    moved = run_simulated_study(SpringRig(stiffer), 6, seed=3, **anchored)
    b, m = base.mean_std(), moved.mean_std()
    for name in ("dragon_skin_30", "ecoflex_00_50"):
        assert m[name][0] > b[name][0] + 0.5
    assert base.correct_ranking_rate == 1.0
    # the ends are outcomes too: a rig that renders every pad alike gives them no spread of their own
    flat = run_simulated_study(SpringRig(tuple(Area(a.name, a.label, 5000.0) for a in AREAS)), 4, seed=3,
                               **anchored)
    assert np.ptp(flat.ratings().mean(axis=0)) < 3.0      # the positions rule would spread them 8-10 .. 1-3
    old = run_simulated_study(SpringRig(tuple(Area(a.name, a.label, 5000.0) for a in AREAS)), 4, seed=3,
                              params=ParticipantParams())
    assert np.all(old.ratings().max(axis=1) >= 8) and np.all(old.ratings().min(axis=1) <= 3)


def test_rating_rule_is_checked():
    with pytest.raises(InputError, match="rating rule 'median'"):
        run_simulated_study(SpringRig(AREAS), 1, seed=0, params=ParticipantParams(), rating="median")


def test_cli_rating_rule_belongs_to_simulated_participants(capsys):
    from teleop.apps.cli import main

    assert main(["blind-test", "--operator", "human", "--rating", "anchored"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "--rating anchored" in err
    assert main(["blind-test", "--rating", "median"]) == 2
    assert "--rating" in capsys.readouterr().err
