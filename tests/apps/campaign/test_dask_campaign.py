"""A tiny blind-study campaign on a real Dask LocalCluster (2 worker processes) against the in-process run:
byte-identical results, a failing grid point reported with its parameters while the other finishes, a
worker process killed under a task (Dask runs the task again elsewhere; its result is written once), and a
run killed with SIGKILL resumed with nothing lost and nothing repeated."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import dask
import psutil
import pytest

from teleop.apps.campaign.runner import run_campaign
from teleop.apps.campaign.spec import load_campaign
from teleop.apps.campaign.store import ResultStore

# 2 grid points x 4 participants, one participant per task: the force = 4 N point asks 40 N of the robot's
# tip and every press faults it (max_aborts = 0: the participant gives up at once), so its 4 tasks fail
CAMPAIGN = """
[campaign]
kind = "blind-jnd"
seed = 3
[study]
participants = 4
participants_per_task = 1
jnd = [0.1, 0.8]
[rig]
robot_substeps = 4
[participant]
max_aborts = 0
[grid]
force = [0.2, 4.0]
"""


def files(d: Path) -> dict:
    """name -> bytes of every result file (not the dot-named temp file of a write the kill interrupted)."""
    return {p.name: p.read_bytes() for p in sorted(d.glob("*.json")) if not p.name.startswith(".")}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    root = tmp_path_factory.mktemp("campaign")
    path = root / "c.toml"
    path.write_text(CAMPAIGN)
    campaign = load_campaign(path)
    report = run_campaign(campaign, root / "none", "none", bar=False)
    return path, campaign, report, root / "none"


def test_local_cluster_is_byte_identical_and_a_failing_task_is_reported(reference, tmp_path):
    path, campaign, ref, ref_dir = reference
    assert ref.total == 8 and ref.ran == 8 and len(ref.failed) == 4
    assert {t.label for t, _ in ref.failed} == {f"force=4.0; participants {p}-{p}" for p in range(1, 5)}
    assert all("PressAborted" in err for _, err in ref.failed)
    ok, bad = ref.summary["points"]
    assert ok["complete"] and ok["participants_done"] == 4 and len(ok["curve"]) == 2
    assert bad["participants_done"] == 0 and len(ref.summary["tasks"]["failed"]) == 4
    assert len(files(ref_dir / "tasks")) == 4 and len(files(ref_dir / "failed")) == 4

    report = run_campaign(campaign, tmp_path, "local:2", bar=False)
    assert report.ran == 8 and len(report.failed) == 4
    assert len(report.warm_seconds) == 2 and len({o.worker for o in report.outcomes}) == 2  # each worker warmed
    assert files(tmp_path / "tasks") == files(ref_dir / "tasks")
    assert (tmp_path / "summary.json").read_bytes() == (ref_dir / "summary.json").read_bytes()
    failed = {p.name for p in (tmp_path / "failed").glob("*.json")}
    assert failed == set(files(ref_dir / "failed"))
    assert (tmp_path / "curves.png").stat().st_size > 0

    again = run_campaign(campaign, tmp_path, "none", bar=False)  # finished tasks are skipped; failed retried
    assert again.skipped == 4 and again.ran == 4 and len(again.failed) == 4


def test_sigkill_mid_campaign_loses_nothing_and_repeats_nothing(reference, tmp_path):
    path, campaign, ref, ref_dir = reference
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", "campaign", "run", str(path), "--out", str(out),
                             "--scheduler", "local:2"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 180
        while not files(out / "tasks") and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.01)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        # the client is gone; its LocalCluster's worker processes notice and exit by themselves
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                os.killpg(proc.pid, 0)
            except ProcessLookupError:
                break
            time.sleep(0.2)
        else:
            pytest.fail("the killed run's Dask worker processes outlived it")
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # only this test's process group, if anything is left
        except ProcessLookupError:
            pass
    survived = files(out / "tasks")
    assert 1 <= len(survived) < 4, "the run was killed after its first result and before its last"
    reference_files = files(ref_dir / "tasks")
    assert all(reference_files[n] == b for n, b in survived.items())  # complete and exact
    stamps = {n: (out / "tasks" / n).stat().st_mtime_ns for n in survived}

    report = run_campaign(campaign, out, "none", bar=False)
    assert not list((out / "tasks").glob(".*"))  # a write the kill cut short left only its temp file: gone
    assert report.skipped == len(survived) and report.ran == 8 - len(survived)
    assert {n: (out / "tasks" / n).stat().st_mtime_ns for n in survived} == stamps  # not written again
    assert files(out / "tasks") == reference_files
    assert (out / "summary.json").read_bytes() == (ref_dir / "summary.json").read_bytes()


def test_a_worker_killed_under_a_task_loses_nothing_and_writes_each_result_once(reference, tmp_path, monkeypatch):
    path, campaign, ref, ref_dir = reference
    ok_tasks = [t for t in kind_tasks(campaign) if "force=0.2" in t.label]
    marked = ok_tasks[1]  # a task that succeeds: its first attempt computes, then its worker dies
    mark = tmp_path / "died"
    monkeypatch.setenv("TELEOP_TEST_DIE_ONCE_TASK", marked.id)
    monkeypatch.setenv("TELEOP_TEST_DIE_ONCE_MARK", str(mark))
    saved = []
    real_save = ResultStore.save
    monkeypatch.setattr(ResultStore, "save", lambda self, task, result: (saved.append(task.id),
                                                                         real_save(self, task, result)))
    preload = str(Path(__file__).with_name("die_once_preload.py"))
    with dask.config.set({"distributed.worker.preload": [preload]}):
        report = run_campaign(campaign, tmp_path / "out", "local:2", bar=False)
    died = int(mark.read_text())  # the first attempt ran and its worker process is gone
    assert not psutil.pid_exists(died) or psutil.Process(died).status() == psutil.STATUS_ZOMBIE
    assert report.ran == 8 and {t.id for t, _ in report.failed} == {t.id for t, _ in ref.failed}
    assert sorted(saved) == sorted(t.id for t in ok_tasks)  # each finished task written once, the marked one too
    assert files(tmp_path / "out" / "tasks") == files(ref_dir / "tasks")
    assert (tmp_path / "out" / "summary.json").read_bytes() == (ref_dir / "summary.json").read_bytes()


def kind_tasks(campaign):
    from teleop.apps.campaign.spec import kind_module

    return kind_module(campaign.kind).tasks(campaign)
