"""A recordings campaign: every file diagnosed (the report of `teleop diagnose`), the findings tabulated
effect x recording (CSV, heat map), a malformed recording reported with its path while the others finish."""

import csv
import json

from teleop.apps.campaign.recordings import tasks
from teleop.apps.campaign.runner import run_campaign
from teleop.apps.campaign.spec import load_campaign
from teleop.apps.campaign.store import ResultStore
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import make_case
from teleop.io.recording_io import read_recording
from teleop.io.outputs import dumps_json


def test_findings_table_heat_map_and_a_bad_recording(tmp_path):
    recs = tmp_path / "recs"
    make_case(1008, "backlash", "rig", seed=11).write(recs / "a_backlash.csv")
    make_case(1016, "coulomb_friction", "rig", seed=11).write(recs / "b_coulomb.csv")
    (recs / "c_broken.csv").write_text("t_s,motor_pos_mm\n0.0,oops\n")
    path = tmp_path / "fleet.toml"
    path.write_text('[campaign]\nkind = "diagnose"\nseed = 2\n[[recordings]]\npaths = ["recs/*.csv"]\n')
    campaign = load_campaign(path)
    report = run_campaign(campaign, tmp_path / "out", "none", bar=False)

    assert report.ran == 3 and [t.label for t, _ in report.failed] == [str(recs / "c_broken.csv")]
    assert "InputError" in report.failed[0][1] and "c_broken.csv" in report.failed[0][1]
    rows = list(csv.reader((tmp_path / "out" / "findings.csv").open()))
    assert rows[0][0] == "recording" and [r[0] for r in rows[1:]] == [str(recs / "a_backlash.csv"),
                                                                      str(recs / "b_coulomb.csv")]
    found = {r[0].split("/")[-1]: {c: float(v) for c, v in zip(rows[0][1:], r[1:]) if v} for r in rows[1:]}
    assert any(c.startswith("backlash on ") and v >= 2 for c, v in found["a_backlash.csv"].items())
    assert any(c.startswith("coulomb_friction on ") and v >= 2 for c, v in found["b_coulomb.csv"].items())
    assert (tmp_path / "out" / "findings.png").stat().st_size > 0
    # a task's result is the report `teleop diagnose FILE --seed 2` makes
    task = [t for t in tasks(campaign) if t.label.endswith("a_backlash.csv")][0]
    assert task.identity["baseline"] == ["capstan_friction"] and task.identity["sindy"] is False  # the defaults
    direct = diagnose(read_recording(task.label), task.identity["holdout"], seed=2).as_dict()
    assert ResultStore(tmp_path / "out").load(task) == json.loads(dumps_json(direct))
