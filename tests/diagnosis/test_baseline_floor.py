"""The baseline fits effect-free recordings to the noise floor (issue 26 d1): held-out RMSE of the force link
(tip tension -> motor tension) <= 1.2x the true noise, on recordings the diagnosis did not make
(tests.diagnosis._independent: an instant switch on the velocity's sign, a pre-sliding stick), exact motor
encoder, capstan ratios 1.2-5, with the tip sensor and with the load from the spring law (the capstan stays
in the baseline there, its preload the spring's unknown zero). A noisy encoder's turns and the distributed
plant's curved transitions: tests/diagnosis/test_turns_and_transitions.py; the whole table:
`python -m tests.diagnosis.floor_table --seed 0 --plant`."""

import pytest

from teleop.core.physics.links import predict
from teleop.diagnosis.diagnose import split
from teleop.diagnosis.identify import rms
from teleop.diagnosis.links import find_links, link_data
from teleop.io.recording_io import read_interchange
from tests.diagnosis._independent import Case, make
from tests.diagnosis.floor_table import floor_ratio

FLOOR = 1.2


def force_baseline(made, tmp_path):
    """(held-out RMSE / true noise, the baseline Fit) of the recording's force link, read back from its CSV
    (floor_table.floor_ratio, which also checks the Fit's RMSE against its prediction)."""
    return floor_ratio(made, tmp_path / "rec.csv")


CASES = [(1.2, "sine", None), (3.0, "sines", None), (5.0, "sine", None), (2.0, "sine", 8e4), (4.5, "sines", 8e4),
         (5.0, "triangle", 8e4), (5.0, "triangle", None)]   # the last: an instant switch at turns no central
                                                              # difference places (links.exact_turn_rate)


@pytest.mark.parametrize("tip", [True, False], ids=["tip sensor", "spring law"])
@pytest.mark.parametrize("ratio, drive, stick_k", CASES)
def test_effect_free_baseline_at_the_noise_floor(tmp_path, ratio, drive, stick_k, tip):
    case = Case(ratio=ratio, drive=drive, stick_k=stick_k, tip=tip, seconds=10.0, freq=1.0, seed=int(ratio * 10))
    ratio_floor, base = force_baseline(make(case), tmp_path)
    assert base.names == ("capstan_friction",)
    assert ratio_floor <= FLOOR, (ratio_floor, base.model)


def test_the_switch_is_not_late(tmp_path):
    """An instant switch is fitted as one: against the noise-free truth the held-out error at the turns is a
    small part of the noise (a switch a sample late costs the whole band there), and a stick of known
    stiffness is fitted as that stiffness."""
    made = make(Case(ratio=4.0, seconds=10.0, freq=1.0, seed=4))
    _, base = force_baseline(made, tmp_path)
    rec = read_interchange(tmp_path / "rec.csv")
    fit_idx, hold_idx = split(rec.n, 0.4)
    d = link_data(rec, next(L for L in find_links(rec) if L.kind == "force"))
    err = (predict(d, base.model) - made.truth["motor_force"])[hold_idx]
    assert abs(err).max() < 2 * made.noise_N, abs(err).max() / made.noise_N
    made = make(Case(ratio=3.0, stick_k=5e4, seconds=10.0, freq=1.0, seed=5))
    _, base = force_baseline(made, tmp_path)
    assert dict(base.model.effects)["capstan_friction"]["k"] == pytest.approx(5e4, rel=0.05)


def test_a_late_switch_is_not_at_the_floor(tmp_path):
    """The check can fail: the same recording's baseline with its switch one stiffness decade softer is off."""
    made = make(Case(ratio=4.0, seconds=10.0, freq=1.0, seed=4))
    _, base = force_baseline(made, tmp_path)
    rec = read_interchange(tmp_path / "rec.csv")
    fit_idx, hold_idx = split(rec.n, 0.4)
    d = link_data(rec, next(L for L in find_links(rec) if L.kind == "force"))
    soft = base.model.with_effects([(n, {**p, "k": 1e6}) for n, p in base.model.effects])
    assert rms((predict(d, soft) - d.y)[hold_idx]) / made.noise_N > 1.5
