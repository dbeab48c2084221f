"""Naming where the baseline has absorbed most of an effect: an addition that takes the chain from above
ACCEPT of the residual's white noise down to within NEAR_FLOOR of it pays from NEAR_ACCEPT on; without
the floor, or ending above it, the plain ACCEPT rule holds. A stretch read through the sheath (no tip force
sensor) is named by the compliance's general form."""

import math

from scenes.cable_rig import LITERATURE, simulate
from teleop.core.physics.links import Link, LinkModel
from teleop.diagnosis import identify as I
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import GenConfig, make_case
from teleop.diagnosis.scoring import run_case
from teleop.io.recording_io import read_interchange

LINK = Link("force", "motor_force", "tip_force", "motor_pos")


def _fit(rmse_hold: float, rmse_fit: float, k: int) -> I.Fit:
    return I.Fit(LinkModel(LINK, 1.0, 0.0, 1.0, 1.0, (), 0), {}, rmse_fit, rmse_hold, k, 1000.0)


def test_near_floor_rule():
    before = _fit(1.30, 1.30, 3)
    near = _fit(1.30 / 1.15, 1.10, 5)           # improves by 1.15 < ACCEPT, to 1.13 of a floor of 1.0
    assert not I._pays(near, before)            # the plain rule: not 20 % better
    assert I._pays(near, before, floor=1.0)     # within NEAR_FLOOR of the floor, better by >= NEAR_ACCEPT
    assert not I._pays(near, before, floor=0.9)   # 1.13 / 0.9 = 1.26 of the floor: not near it
    small = _fit(1.30 / 1.05, 1.25, 5)          # near the floor but improves by less than NEAR_ACCEPT
    assert 1.05 < I.NEAR_ACCEPT and not I._pays(small, before, floor=1.2)
    worse_ic = _fit(1.30 / 1.15, 1.31, 5)       # the information criterion must still improve
    assert not I._pays(worse_ic, before, floor=1.0)
    assert math.isclose(I.NEAR_ACCEPT, math.sqrt(I.ACCEPT))


def test_a_dahl_beside_a_tip_sensor_hysteresis_is_named_too(tmp_path):
    """A tip force sensor's hysteresis and a Dahl friction on the motor force (literature ranges): the
    capstan's mu had taken most of the Dahl (held out 1.35x the noise, 1.13x with the Dahl); both named."""
    cols = ("motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")
    rig = simulate([0, 99, 7], ("sensor_hysteresis", "dahl_hysteresis"), cols, "spring", None, 10.0, 1.0,
                   ranges=LITERATURE)
    assert rig.effects["sensor_hysteresis"]["channel"] == "tip_force"
    path = tmp_path / "rig.csv"
    rig.write(path)
    doc = diagnose(read_interchange(path)).as_dict()
    named = {(f["effect"], f["channel"]) for f in doc["findings"][:2]}
    assert named == {("sensor_hysteresis", "tip_force"), ("dahl_hysteresis", "motor_force")}, doc["findings"]


def test_a_stretch_without_the_tip_force_sensor_is_named(tmp_path):
    """An external load, the tip force not recorded: the position link's load is the motor force, which
    switches by e^(+-mu Theta) at each reversal; the compliance's general form reads the tip tension
    through the sheath and is named, its stiffness within 20 %, at least twice better held out."""
    case = make_case(1, "cable_compliance", "rig", 1, GenConfig(None, 10.0, 1.0, "literature"))
    assert "tip_force_N" not in case.columns and case.load == "external"
    row = run_case(case, tmp_path)
    assert row["named"] == "cable_compliance", row["all_named"]
    assert row["params_ok"], row["param_errors"]
    assert row["improvement"] >= 2.0



def test_parsimony_among_the_candidates_that_pay():
    """A simpler candidate within PARSIMONY that does not pay no longer vetoes one that does (a Dahl taking
    a chain from 1.21x its residual's white noise to 1.07x, a viscous friction 6 % behind it); among paying
    candidates the simpler one still wins, and where none pays the plain parsimony stands."""
    current = _fit(1.825, 1.80, 4)
    dahl = _fit(1.612, 1.55, 6)
    viscous = _fit(1.710, 1.63, 5)
    floor = 1.51
    assert viscous.rmse_hold <= dahl.rmse_hold * (1 + I.PARSIMONY)
    assert I._pick([dahl, viscous], None) is viscous                      # parsimony alone
    assert not I._pays(viscous, current, floor) and I._pays(dahl, current, floor)
    assert I._pick_paying([dahl, viscous], current, floor, None) is dahl
    near_simple = _fit(1.640, 1.56, 5)                                      # pays too: the simpler one wins
    assert I._pick_paying([dahl, near_simple], current, floor, None) is near_simple
    assert I._pick_paying([viscous], current, floor, None) is viscous      # none pays: as before
