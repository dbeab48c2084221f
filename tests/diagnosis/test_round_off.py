"""A channel the baseline fits to the float's round-off carries nothing to find (identify.ROUND_OFF_SHARE): the
generator's Coulomb case with exact encoders on a rigid link has its tip follow the motor to 1e-18 m, where a
free-period map (transmission_error) fitted the round-off and was named at x2.2-2.5."""

import pytest

from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import GenConfig, case_plan, make_case
from teleop.io.recording_io import read_interchange


@pytest.mark.parametrize("index", [2, 20])
def test_a_tip_exact_to_round_off_names_nothing_there(tmp_path, index):
    effect, setup = case_plan(index + 1)[index]
    case = make_case(index, effect, setup, 3, GenConfig(None, 10.0, 1.0, "literature"))
    doc = diagnose(read_interchange(case.write(tmp_path / "c.csv"))).as_dict()
    assert doc["channels"]["tip_pos"]["rmse_baseline"] < 1e-15           # the premise: round-off only
    assert [f["effect"] for f in doc["findings"]] == ["coulomb_friction"], doc["findings"]
