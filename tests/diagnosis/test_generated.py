"""A small fixed subset of generated concealed-effect recordings: the right name first, `none` when clean,
parameters within 20 %, held-out improvement >= 2x. (The full run: `teleop bench diagnose`.)"""

import pytest

from teleop.diagnosis.generator import make_case
from teleop.diagnosis.scoring import run_case

CASES = [("backlash", "rig"), ("cable_compliance", "rig"), ("stribeck_friction", "rig"),
         ("coulomb_friction", "rig"), ("dahl_hysteresis", "rig"), ("sensor_hysteresis", "rig"),
         ("hertz_contact", "pad"), ("viscoelasticity", "pad"), ("none", "rig"), ("none", "pad")]


@pytest.mark.parametrize("effect, setup", CASES)
def test_concealed_effect_is_named(tmp_path, effect, setup):
    case = make_case(1000 + len(effect), effect, setup, seed=11)
    row = run_case(case, tmp_path)
    assert row["named"] == effect, row
    if effect != "none":
        assert row["params_ok"], row["param_errors"]
        assert row["improvement"] >= 2.0


def test_capstan_is_baseline_by_default_and_a_finding_beyond_a_lossless_one(tmp_path):
    """The generated rig's sheath always has capstan friction: the project's simulation has it too, so by
    default it is no finding; a user whose simulation is lossless is told it is missing."""
    from teleop.diagnosis.diagnose import diagnose
    from teleop.io.recording_io import read_interchange

    case = make_case(7, "none", "rig", seed=3)
    rec = read_interchange(case.write(tmp_path / "c.csv"))
    doc = diagnose(rec).as_dict()
    assert doc["findings"] == [] and doc["baseline"]["effects"]["motor_force"] == ["capstan_friction"]
    lossless = diagnose(rec, baseline=()).as_dict()
    assert lossless["baseline"]["effects"]["motor_force"] == []
    first = lossless["findings"][0]
    assert first["effect"] == "capstan_friction" and first["channel"] == "motor_force"
    assert first["improvement"] >= 2.0


def test_report_is_reproducible_byte_for_byte(tmp_path):
    from teleop.diagnosis.diagnose import diagnose
    from teleop.io.recording_io import read_interchange
    from teleop.io.outputs import dumps_json

    case = make_case(3, "stribeck_friction", "rig", seed=5)
    path = case.write(tmp_path / "c.csv")
    a = dumps_json(diagnose(read_interchange(path), seed=1).as_dict())
    b = dumps_json(diagnose(read_interchange(path), seed=1).as_dict())
    assert a == b
