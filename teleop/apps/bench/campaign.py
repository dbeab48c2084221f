"""`teleop bench campaign FILE`: the same campaign run from scratch on each scheduler in one process, one
after the other (wall times, speed-up, results compared byte for byte), the scheduler's own cost per task
measured with empty tasks, and from these, on paper, the wall time of a large grid on a bigger cluster:

    T(W workers, N tasks) = start + warm + c * N / W + o * N

c: one task's CPU time on a worker of the last scheduler (its thread's and its worker process's other
threads', mean: what a dedicated core takes, whatever else runs on this machine), o: wall time per empty
task through that scheduler and the store (the client writes every result: a serial cost), start: starting
that scheduler, warm: the kind's once-per-process set-up in its run (imports, compiled kernels; all workers
at once; a stale numba cache compiles in the first run's warm-up, not in later ones). The estimate assumes the tasks outnumber the workers many times
over and a scheduler that keeps up.

Where a run's wall time went: start, warm, then the tasks ("tasks s": wall from the first task to the last
result). "speed-up" compares whole runs, "tasks speed-up" the task phases alone (what the one-off start and
warm-up of the workers do not dilute: it is what a long campaign approaches). Per task: its thread's CPU
time ("task CPU s") and the rest of its worker process's CPU meanwhile ("worker CPU s": Dask's event loop,
heartbeats), "client CPU s" this process's CPU per task over the task phase (scheduler, nannies, result
files; with `none` the tasks' own CPU left out), "tail s" the time the worker that ran out of tasks first waited for the last
result, "cores used" the tasks' CPU seconds over the task phase (what the machine gave: on a machine
shared with other work a speed-up needs free cores). For such a machine the bench also says, on paper,
what each run would take on as many free cores as it had worker processes: start + warm + (the tasks' and
the client's CPU seconds) / cores + tail, the fixed parts as measured.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from teleop.apps.argtypes import positive_int
from teleop.apps.campaign.runner import run_campaign
from teleop.apps.campaign.scheduler import parse_scheduler
from teleop.apps.campaign.spec import Campaign, load_campaign
from teleop.core.errors import InputError
from teleop.io.outputs import check_output, write_json

DEFAULT_SCHEDULERS = "none,local:2"


def scheduler_list(text: str) -> list:
    """'none,local:2' -> ["none", "local:2"]: schedulers as `--scheduler` takes them (argparse type)."""
    schedulers = [s.strip() for s in str(text).split(",") if s.strip()]
    if not schedulers:
        raise argparse.ArgumentTypeError(f"expected a comma-separated list such as none,local:2, got '{text}'")
    for s in schedulers:
        try:
            parse_scheduler(s)
        except InputError as exc:
            raise argparse.ArgumentTypeError(f"'{text}': {str(exc).replace('--scheduler ', '', 1)}") from None
    return schedulers


def register(subparsers) -> None:
    p = subparsers.add_parser("campaign", help="campaign wall time per scheduler, overhead per task, cluster estimate")
    p.add_argument("file", metavar="FILE", help="campaign file (e.g. examples/jnd_grid.toml)")
    p.add_argument("--schedulers", type=scheduler_list, default=DEFAULT_SCHEDULERS, metavar="S1,S2",
                   help=f"schedulers to compare, the first is the reference (default {DEFAULT_SCHEDULERS})")
    p.add_argument("--overhead-tasks", type=positive_int, default=400, metavar="N",
                   help="empty tasks run through the last scheduler to measure its cost per task (400)")
    p.add_argument("--estimate-workers", type=positive_int, default=64, metavar="W")
    p.add_argument("--estimate-curves", type=positive_int, default=1000, metavar="C",
                   help="grid points of the estimated campaign (1000)")
    p.add_argument("--estimate-participants", type=positive_int, default=100, metavar="P",
                   help="participants per grid point of the estimated campaign (100)")
    p.add_argument("--seed", type=int, default=None, help="replaces the campaign file's seed")
    p.add_argument("--json", metavar="PATH", help="write the numbers as JSON")
    p.set_defaults(func=run)


def _same_results(a, b) -> bool:
    def files(root):
        d = Path(root) / "tasks"
        return {p.name: p.read_bytes() for p in d.glob("*.json") if not p.name.startswith(".")}

    return files(a) == files(b) and (Path(a) / "summary.json").read_bytes() == (Path(b) / "summary.json").read_bytes()


def run(args) -> int:
    schedulers = args.schedulers
    if args.json:
        check_output(args.json, "--json")
    campaign = load_campaign(args.file, args.seed)
    runs = []
    with tempfile.TemporaryDirectory(prefix="bench-campaign-") as tmp:
        for i, s in enumerate(schedulers):
            print(f"bench campaign: {s}", file=sys.stderr)
            load0 = os.getloadavg()[0]
            rep = run_campaign(campaign, f"{tmp}/{i}", s, bar=False, interval=10.0)
            runs.append({"scheduler": s, "workers": rep.workers, "tasks": rep.ran, "failed": len(rep.failed),
                         "load_1min": [load0, os.getloadavg()[0]], **run_breakdown(rep, in_process=s == "none"),
                         "identical_to_first": _same_results(f"{tmp}/0", f"{tmp}/{i}")})
        noop = Campaign(source="empty tasks", kind="noop", seed=0, study=args.overhead_tasks)
        print(f"bench campaign: {args.overhead_tasks} empty tasks on {schedulers[-1]}", file=sys.stderr)
        rep = run_campaign(noop, f"{tmp}/noop", schedulers[-1], bar=False, interval=10.0)
    overhead = {"scheduler": schedulers[-1], "tasks": rep.ran, "wall_s": rep.wall_s, "start_s": rep.start_s,
                "per_task_s": (rep.wall_s - rep.start_s - rep.warm_s) / rep.ran}
    ref = runs[0]
    for r in runs:
        r["speedup"] = ref["wall_s"] / r["wall_s"]
        r["tasks_speedup"] = ref["tasks_wall_s"] / r["tasks_wall_s"]
    # a dedicated core's time per task on a Dask worker (its thread's and its worker's other threads' CPU:
    # the wall time here depends on the load), and the warm-up of the workers of that run
    c, warm = runs[-1]["task_cpu_s_mean"], runs[-1]["warm_s"]
    per_task = _participants_per_task(campaign)
    n_tasks = args.estimate_curves * -(-args.estimate_participants // per_task) if per_task else None
    estimate = None
    if n_tasks:
        w, o = args.estimate_workers, overhead["per_task_s"]
        compute, sched = c * n_tasks / w, o * n_tasks
        estimate = {"workers": w, "curves": args.estimate_curves, "participants": args.estimate_participants,
                    "participants_per_task": per_task, "tasks": n_tasks, "task_s": c, "overhead_per_task_s": o,
                    "start_s": overhead["start_s"], "warm_s": warm, "compute_s": compute, "scheduler_s": sched,
                    "total_s": overhead["start_s"] + warm + compute + sched}
    print(f"{'scheduler':>12} {'workers':>7} {'tasks':>5} {'wall s':>7} {'start s':>7} {'warm s':>6} {'tasks s':>7} "
          f"{'task CPU s':>10} {'worker CPU s':>12} {'client CPU s':>12} {'tail s':>6} {'cores used':>10} "
          f"{'speed-up':>8} {'tasks speed-up':>14}  identical  load (1 min, before/after)")
    for r in runs:
        print(f"{r['scheduler']:>12} {r['workers']:>7} {r['tasks']:>5} {r['wall_s']:7.1f} {r['start_s']:7.1f} "
              f"{r['warm_s']:6.1f} {r['tasks_wall_s']:7.1f} {r['task_thread_cpu_s_mean']:10.2f} "
              f"{r['worker_cpu_s_per_task']:12.3f} {r['client_cpu_s_per_task']:12.3f} {r['tail_s']:6.1f} "
              f"{r['cores_used']:10.2f} {r['speedup']:8.2f} {r['tasks_speedup']:14.2f}  "
              f"{'yes' if r['identical_to_first'] else 'NO':9}  {r['load_1min'][0]:.1f} / {r['load_1min'][1]:.1f}")
    for r in runs:
        r["free_cores_speedup"] = ref["free_cores_wall_s"] / r["free_cores_wall_s"]
        print(f"on {r['worker_processes']} free core(s), from the CPU accounting: {r['scheduler']} "
              f"{r['free_cores_wall_s']:.1f} s (start, warm and tail as measured), speed-up "
              f"{r['free_cores_speedup']:.2f}")
    print(f"scheduler cost per task ({overhead['tasks']} empty tasks on {overhead['scheduler']}): "
          f"{overhead['per_task_s'] * 1e3:.1f} ms; start {overhead['start_s']:.1f} s")
    if estimate:
        e = estimate
        print(f"estimate: {e['curves']} curves x {e['participants']} participants ({e['tasks']} tasks of "
              f"{e['participants_per_task']}) on {e['workers']} workers = {e['start_s']:.0f} s start + "
              f"{e['warm_s']:.0f} s warm + {e['task_s']:.2f} s CPU x {e['tasks']} / {e['workers']} + "
              f"{e['overhead_per_task_s'] * 1e3:.1f} ms x {e['tasks']} = {e['total_s'] / 3600:.2f} h")
    if args.json:
        write_json(args.json, {"campaign": args.file, "runs": runs, "overhead": overhead, "estimate": estimate})
    return 0 if all(r["identical_to_first"] for r in runs) else 1


def run_breakdown(rep, in_process: bool) -> dict:
    """Where one run's wall time and CPU went (module docstring), from its RunReport [s]."""
    outs = rep.outcomes
    n = len(outs)
    tasks_wall = rep.wall_s - rep.start_s - rep.warm_s
    cpu = sum(o.cpu_seconds for o in outs)
    thread = sum(o.thread_cpu_seconds for o in outs)
    client = rep.client_cpu_s - (cpu if in_process else 0.0)
    last = {}
    for o in outs:
        last[o.worker] = max(last.get(o.worker, 0.0), o.ended)
    tail = max(last.values()) - min(last.values()) if last else 0.0
    return {"wall_s": rep.wall_s, "start_s": rep.start_s, "warm_s": rep.warm_s, "warm_seconds": rep.warm_seconds,
            "tasks_wall_s": tasks_wall, "task_s_mean": sum(o.seconds for o in outs) / n,
            "task_cpu_s_mean": cpu / n, "task_thread_cpu_s_mean": thread / n,
            "worker_cpu_s_per_task": (cpu - thread) / n, "client_cpu_s_per_task": client / n,
            "tail_s": tail, "worker_processes": len(last), "cores_used": cpu / tasks_wall,
            # on as many free cores as worker processes: the fixed parts as measured, the tasks' and the
            # client's CPU shared out over the cores (what this run would take with no other users)
            "free_cores_wall_s": rep.start_s + rep.warm_s + (cpu + max(client, 0.0)) / max(len(last), 1) + tail}


def _participants_per_task(campaign) -> int | None:
    """Participants per task of a blind-jnd campaign (None for other kinds)."""
    return getattr(campaign.study, "per_task", None)
