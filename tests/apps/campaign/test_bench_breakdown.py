"""`teleop bench campaign`'s account of one run, from a RunReport whose times are set by hand."""

import pytest

from teleop.apps.bench.campaign import run_breakdown
from teleop.apps.campaign.runner import RunReport
from teleop.apps.campaign.scheduler import Outcome


def outcome(worker, started, ended, cpu, thread):
    return Outcome(True, seconds=ended - started, cpu_seconds=cpu, thread_cpu_seconds=thread, worker=worker,
                   started=started, ended=ended)


def test_breakdown_of_a_two_worker_run():
    outs = [outcome("h:1", 100.0, 102.0, 2.2, 2.0), outcome("h:2", 100.0, 103.0, 3.3, 3.0),
            outcome("h:1", 102.0, 104.0, 2.2, 2.0), outcome("h:2", 103.0, 105.5, 2.75, 2.5)]
    rep = RunReport(total=4, skipped=0, ran=4, wall_s=9.0, start_s=1.0, warm_s=2.0, warm_seconds=[1.9, 2.0],
                    outcomes=outs, client_cpu_s=0.4)
    b = run_breakdown(rep, in_process=False)
    assert b["tasks_wall_s"] == pytest.approx(6.0)  # 9 s less start and warm
    assert b["task_thread_cpu_s_mean"] == pytest.approx(9.5 / 4)
    assert b["worker_cpu_s_per_task"] == pytest.approx((10.45 - 9.5) / 4)
    assert b["client_cpu_s_per_task"] == pytest.approx(0.1)
    assert b["tail_s"] == pytest.approx(1.5)  # worker h:1 done at 104, the last result at 105.5
    assert b["worker_processes"] == 2
    assert b["cores_used"] == pytest.approx(10.45 / 6.0)
    assert b["free_cores_wall_s"] == pytest.approx(1.0 + 2.0 + (10.45 + 0.4) / 2 + 1.5)


def test_in_process_client_cpu_leaves_the_tasks_out():
    outs = [outcome("h:1", 0.0, 1.0, 1.0, 1.0), outcome("h:1", 1.0, 2.0, 1.0, 1.0)]
    rep = RunReport(total=2, skipped=0, ran=2, wall_s=2.5, warm_s=0.5, outcomes=outs, client_cpu_s=2.2)
    b = run_breakdown(rep, in_process=True)
    assert b["client_cpu_s_per_task"] == pytest.approx(0.1) and b["tail_s"] == 0.0
    assert b["free_cores_wall_s"] == pytest.approx(0.5 + 2.0 + 0.2)
