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
