"""Running a campaign: the tasks not yet in the store go to the scheduler; each result is written to the
store as it arrives; then the summary, its table and the plots are made from what the store holds."""

from __future__ import annotations

import dataclasses
import sys
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from teleop.apps.campaign.scheduler import open_scheduler
from teleop.apps.campaign.spec import Campaign, kind_module
from teleop.apps.campaign.store import ResultStore
from teleop.apps.campaign.task_progress import TaskProgress
from teleop.io.outputs import atomic_write, write_json


def execute_task(task):
    """What a worker runs: the task's kind executes its identity."""
    return kind_module(task.kind).execute(task.identity)


@dataclass
class RunReport:
    """What a run did: tasks in the campaign, skipped (already done), ran here, failed [(Task, error)],
    wall time [s] (of which start_s starting or connecting to the scheduler and warm_s the kind's set-up in
    every worker process, each worker's time in warm_seconds), each task's own wall and CPU time where it
    ran [s], the Outcome of each task (where and when it ran), the CPU time of this process over the tasks
    [s] (the client; a LocalCluster's scheduler and nannies run in it too; `none` runs the tasks in it), worker threads at the end, and
    the summary of everything stored."""

    total: int
    skipped: int
    ran: int
    failed: list = field(default_factory=list)
    wall_s: float = 0.0
    start_s: float = 0.0
    warm_s: float = 0.0
    warm_seconds: list = field(default_factory=list)
    workers: int = 0
    task_seconds: list = field(default_factory=list)
    task_cpu_seconds: list = field(default_factory=list)
    outcomes: list = field(default_factory=list)
    client_cpu_s: float = 0.0
    summary: dict = field(default_factory=dict)


def run_campaign(campaign: Campaign, out_dir: str | Path, scheduler: str = "none", stream=None,
                 bar: bool | None = None, interval: float = 5.0) -> RunReport:
    """Run what `campaign` still needs into `out_dir` on `scheduler`, then summarise (see summarise)."""
    stream = sys.stderr if stream is None else stream
    kind = kind_module(campaign.kind)
    tasks = kind.tasks(campaign)
    store = ResultStore(out_dir)
    with store:
        done = store.done_ids()
        todo = [t for t in tasks if t.id not in done]
        report = RunReport(total=len(tasks), skipped=len(tasks) - len(todo), ran=0)
        print(f"campaign {campaign.source}: {len(tasks)} tasks, {report.skipped} already done, "
              f"{len(todo)} to run on {scheduler}", file=stream, flush=True)
        started = datetime.now(timezone.utc).isoformat(timespec="seconds")
        t0, c0 = time.perf_counter(), time.process_time()
        if todo:
            with open_scheduler(scheduler) as sched:
                report.start_s = time.perf_counter() - t0
                if hasattr(kind, "warm"):
                    where = "this process" if sched.name == "none" else f"the workers of {sched.name}"
                    print(f"campaign: setting up {where} (imports, compiled kernels; after the kernels changed "
                          "they compile here first, about a minute)", file=stream, flush=True)
                    report.warm_seconds = sched.warm(kind.warm)
                report.warm_s = time.perf_counter() - t0 - report.start_s
                c0 = time.process_time()
                with TaskProgress(len(todo), "campaign", stream, bar=bar, interval=interval) as progress:
                    for task, outcome in sched.run(execute_task, todo):
                        if outcome.ok:
                            store.save(task, outcome.value)
                        else:
                            store.save_failure(task, outcome.error, outcome.traceback)
                            report.failed.append((task, outcome.error))
                            progress.note(f"task failed: {task.label}: {shorten(outcome.error)}")
                        report.ran += 1
                        report.task_seconds.append(outcome.seconds)
                        report.task_cpu_seconds.append(outcome.cpu_seconds)
                        report.outcomes.append(dataclasses.replace(outcome, value=None))
                        progress.update(outcome.ok)
                report.workers = sched.workers
        report.wall_s = time.perf_counter() - t0
        report.client_cpu_s = time.process_time() - c0
        secs, cpu = report.task_seconds, report.task_cpu_seconds
        store.log_run({"started_utc": started, "scheduler": scheduler, "workers": report.workers,
                       "start_s": round(report.start_s, 3), "warm_s": round(report.warm_s, 3),
                       "tasks": report.total, "skipped": report.skipped, "ran": report.ran,
                       "failed": len(report.failed), "wall_s": round(report.wall_s, 3),
                       "task_s_sum": round(sum(secs), 3),
                       "task_s_mean": round(sum(secs) / len(secs), 4) if secs else None,
                       "task_cpu_s_mean": round(sum(cpu) / len(cpu), 4) if cpu else None})
        report.summary = summarise(campaign, store, stream)
    return report


def summarise(campaign: Campaign, store: ResultStore, stream=None) -> dict:
    """The kind's summary of the stored results plus the task counts and failures; written to
    DIR/summary.json (sorted keys) and DIR/summary.txt, with the kind's plots and tables, and returned."""
    stream = sys.stderr if stream is None else stream
    kind = kind_module(campaign.kind)
    tasks = kind.tasks(campaign)
    done = store.done_ids()
    unreadable = []

    def load(task):
        if task.id not in done:
            return None
        result = store.load(task)
        if result is None:
            unreadable.append(task)
            store.forget(task)
        return result

    summary = kind.summarise(campaign, load)
    finished = sum(t.id in done for t in tasks) - len(unreadable)
    failed = [{"task": t.id, "label": t.label, "error": err} for t in tasks
              if t.id not in done and (err := store.failure(t)) is not None]
    for t in unreadable:
        print(f"campaign: the stored result of {t.label} did not load; it will run again", file=stream)
    summary["tasks"] = {"total": len(tasks), "done": finished, "failed": failed}
    root = Path(store.root)
    write_json(root / "summary.json", summary, sort_keys=True)
    text = summary_text(campaign, summary)
    atomic_write(root / "summary.txt", lambda tmp: tmp.write_text(text + "\n", encoding="utf-8"))
    kind.write_outputs(summary, root)
    return summary


SHOWN_FAILURES = 10  # failed tasks listed under the table (all of them are in DIR/failed/)


def shorten(text: str, width: int = 200) -> str:
    """`text` cut to `width` characters (the whole error and traceback are in DIR/failed/<task>.json)."""
    return text if len(text) <= width else text[:width - 3] + "..."


def summary_text(campaign: Campaign, summary: dict) -> str:
    """The kind's table with the task counts and the first failures (parameters and error) under it."""
    t = summary["tasks"]
    failed = t["failed"]
    lines = [kind_module(campaign.kind).table(summary), "",
             f"tasks: {t['done']} of {t['total']} done, {len(failed)} failed"
             + (" (each with its parameters, error and traceback in DIR/failed/)" if failed else "")]
    lines += [f"  failed: {f['label']}: {shorten(f['error'])}" for f in failed[:SHOWN_FAILURES]]
    if len(failed) > SHOWN_FAILURES:
        lines.append(f"  ... and {len(failed) - SHOWN_FAILURES} more")
    return "\n".join(lines)
