"""Campaign kind `noop`: empty tasks, to measure what a scheduler and the store cost per task.

    [campaign]
    kind = "noop"
    [study]
    tasks = 500
"""

from __future__ import annotations

from pathlib import Path

from teleop.apps.campaign.identity import Task
from teleop.apps.campaign.values import get_int
from teleop.core.config import check_keys
from teleop.core.errors import InputError

KIND = "noop"


def parse(doc: dict, where: str, base_dir: Path) -> int:
    check_keys(doc, ("study",), where)
    study = doc.get("study", {})
    if not isinstance(study, dict):
        raise InputError(f"{where}: [study] must be a table")
    check_keys(study, ("tasks",), f"{where} [study]")
    return get_int(study, "tasks", f"{where} [study]", minimum=1)


def tasks(campaign) -> list:
    return [Task(KIND, {"seed": campaign.seed, "index": i}, f"empty task {i}") for i in range(campaign.study)]


def execute(identity: dict) -> dict:
    return {"index": identity["index"]}


def summarise(campaign, load) -> dict:
    return {"kind": KIND, "finished": sum(load(t) is not None for t in tasks(campaign))}


def table(summary: dict) -> str:
    return f"{summary['finished']} empty tasks finished"


def write_outputs(summary: dict, out_dir: Path) -> list:
    return []
