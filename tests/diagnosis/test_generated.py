"""A small fixed subset of generated concealed-effect recordings: the right name first, `none` when clean,
parameters within 20 %, held-out improvement >= 2x. (The full run: `teleop bench diagnose`.)"""

import pytest

from teleop.diagnosis.generator import make_case
from teleop.diagnosis.scoring import run_case

CASES = [("backlash", "rig"), ("cable_compliance", "rig"), ("capstan_friction", "rig"),
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


def test_report_is_reproducible_byte_for_byte(tmp_path):
    from teleop.diagnosis.diagnose import diagnose
    from teleop.diagnosis.recording_io import read_interchange
    from teleop.outputs import dumps_json

    case = make_case(3, "stribeck_friction", "rig", seed=5)
    path = case.write(tmp_path / "c.csv")
    a = dumps_json(diagnose(read_interchange(path), seed=1).as_dict())
    b = dumps_json(diagnose(read_interchange(path), seed=1).as_dict())
    assert a == b
