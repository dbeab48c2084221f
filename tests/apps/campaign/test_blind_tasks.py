"""Blind-study tasks: a participant's streams come from the campaign seed and the participant's number, so
how participants are cut into tasks changes nothing, and a stored record reads back as the same record."""

import dataclasses

from teleop.apps.campaign.blind import BlindStudy, execute, record_from_json, record_to_json, tasks
from teleop.apps.campaign.runner import run_campaign
from teleop.apps.campaign.spec import load_campaign

CAMPAIGN = """
[campaign]
kind = "blind-jnd"
seed = 9
[study]
participants = 3
participants_per_task = 3
jnd = [0.15, 0.6]
[rig]
robot_substeps = 4
"""


def test_cutting_participants_into_other_tasks_changes_no_curve(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(CAMPAIGN)
    whole = load_campaign(path)
    cut: BlindStudy = dataclasses.replace(whole.study, per_task=1)
    split = dataclasses.replace(whole, study=cut)
    assert len(tasks(whole)) == 1 and len(tasks(split)) == 3
    a = run_campaign(whole, tmp_path / "a", "none", bar=False).summary
    b = run_campaign(split, tmp_path / "b", "none", bar=False).summary
    assert a["points"] == b["points"] and a["points"][0]["participants_done"] == 3
    # the records of participant 3 alone (the last task of the split campaign) are those of the whole run
    alone = execute(tasks(split)[2].identity)["participants"][0]
    assert [record_from_json(r) for r in alone] == [record_from_json(r) for r in
                                                    execute(tasks(whole)[0].identity)["participants"][2]]
    assert [record_to_json(record_from_json(r)) for r in alone] == alone
