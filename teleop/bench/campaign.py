"""`teleop bench campaign FILE`: the same campaign run from scratch on each scheduler in one process, one
after the other (wall times, speed-up, results compared byte for byte), the scheduler's own cost per task
measured with empty tasks, and from these, on paper, the wall time of a large grid on a bigger cluster:

    T(W workers, N tasks) = start + c * N / W + o * N

c: one task's own CPU time (mean over the in-process run: what a dedicated core takes, whatever else runs
on this machine), o: wall time per empty task through the scheduler and the store (the client writes every
result: a serial cost), start: starting the scheduler. The estimate assumes the tasks outnumber the workers
many times over and a scheduler that keeps up. "cores used" (the tasks' CPU seconds over the wall time)
says how much of the machine a run got: on a machine shared with other work a speed-up needs free cores.
"""

from __future__ import annotations

import sys

DEFAULT_SCHEDULERS = "none,local:2"


def register(subparsers) -> None:
    from teleop.argtypes import positive_int

    p = subparsers.add_parser("campaign", help="campaign wall time per scheduler, overhead per task, cluster estimate")
    p.add_argument("file", metavar="FILE", help="campaign file (e.g. examples/jnd_grid.toml)")
    p.add_argument("--schedulers", default=DEFAULT_SCHEDULERS, metavar="S1,S2",
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
    from pathlib import Path

    def files(root):
        d = Path(root) / "tasks"
        return {p.name: p.read_bytes() for p in d.glob("*.json") if not p.name.startswith(".")}

    return files(a) == files(b) and (Path(a) / "summary.json").read_bytes() == (Path(b) / "summary.json").read_bytes()


def run(args) -> int:
    import os
    import tempfile

    from teleop.campaign.runner import run_campaign
    from teleop.campaign.scheduler import parse_scheduler
    from teleop.campaign.spec import Campaign, load_campaign
    from teleop.errors import InputError
    from teleop.outputs import check_output, write_json

    schedulers = [s.strip() for s in args.schedulers.split(",") if s.strip()]
    for s in schedulers:
        parse_scheduler(s)
    if len(schedulers) < 1:
        raise InputError(f"--schedulers '{args.schedulers}': expected a comma-separated list such as none,local:2")
    if args.json:
        check_output(args.json, "--json")
    campaign = load_campaign(args.file, args.seed)
    runs = []
    with tempfile.TemporaryDirectory(prefix="bench-campaign-") as tmp:
        for i, s in enumerate(schedulers):
            print(f"bench campaign: {s}", file=sys.stderr)
            load0 = os.getloadavg()[0]
            rep = run_campaign(campaign, f"{tmp}/{i}", s, bar=False, interval=10.0)
            secs = rep.task_seconds
            runs.append({"scheduler": s, "workers": rep.workers, "tasks": rep.ran, "failed": len(rep.failed),
                         "load_1min": [load0, os.getloadavg()[0]],
                         "wall_s": rep.wall_s, "start_s": rep.start_s, "task_s_mean": sum(secs) / len(secs),
                         "task_s_sum": sum(secs),
                         "task_cpu_s_mean": sum(rep.task_cpu_seconds) / len(rep.task_cpu_seconds),
                         # cores the tasks got on average: what the machine gave (its other users take the rest)
                         "cores_used": sum(rep.task_cpu_seconds) / rep.wall_s,
                         "identical_to_first": _same_results(f"{tmp}/0", f"{tmp}/{i}")})
        noop = Campaign(source="empty tasks", kind="noop", seed=0, study=args.overhead_tasks)
        print(f"bench campaign: {args.overhead_tasks} empty tasks on {schedulers[-1]}", file=sys.stderr)
        rep = run_campaign(noop, f"{tmp}/noop", schedulers[-1], bar=False, interval=10.0)
    overhead = {"scheduler": schedulers[-1], "tasks": rep.ran, "wall_s": rep.wall_s, "start_s": rep.start_s,
                "per_task_s": (rep.wall_s - rep.start_s) / rep.ran}
    ref = runs[0]
    for r in runs:
        r["speedup"] = ref["wall_s"] / r["wall_s"]
    c = ref["task_cpu_s_mean"]  # a dedicated core's time per task (the wall time here depends on the load)
    per_task = _participants_per_task(campaign)
    n_tasks = args.estimate_curves * -(-args.estimate_participants // per_task) if per_task else None
    estimate = None
    if n_tasks:
        w, o = args.estimate_workers, overhead["per_task_s"]
        compute, sched = c * n_tasks / w, o * n_tasks
        estimate = {"workers": w, "curves": args.estimate_curves, "participants": args.estimate_participants,
                    "participants_per_task": per_task, "tasks": n_tasks, "task_s": c, "overhead_per_task_s": o,
                    "start_s": overhead["start_s"], "compute_s": compute, "scheduler_s": sched,
                    "total_s": overhead["start_s"] + compute + sched}
    print(f"{'scheduler':>12} {'workers':>7} {'tasks':>5} {'wall s':>8} {'start s':>7} {'task s':>7} "
          f"{'task CPU s':>10} {'cores used':>10} {'speed-up':>8}  identical  load (1 min, before/after)")
    for r in runs:
        print(f"{r['scheduler']:>12} {r['workers']:>7} {r['tasks']:>5} {r['wall_s']:8.1f} {r['start_s']:7.1f} "
              f"{r['task_s_mean']:7.2f} {r['task_cpu_s_mean']:10.2f} {r['cores_used']:10.2f} {r['speedup']:8.2f}  "
              f"{'yes' if r['identical_to_first'] else 'NO':9}  {r['load_1min'][0]:.1f} / {r['load_1min'][1]:.1f}")
    print(f"scheduler cost per task ({overhead['tasks']} empty tasks on {overhead['scheduler']}): "
          f"{overhead['per_task_s'] * 1e3:.1f} ms; start {overhead['start_s']:.1f} s")
    if estimate:
        e = estimate
        print(f"estimate: {e['curves']} curves x {e['participants']} participants ({e['tasks']} tasks of "
              f"{e['participants_per_task']}) on {e['workers']} workers = {e['start_s']:.0f} s start + "
              f"{e['task_s']:.2f} s CPU x {e['tasks']} / {e['workers']} + {e['overhead_per_task_s'] * 1e3:.1f} ms x "
              f"{e['tasks']} = {e['total_s'] / 3600:.2f} h")
    if args.json:
        write_json(args.json, {"campaign": args.file, "runs": runs, "overhead": overhead, "estimate": estimate})
    return 0 if all(r["identical_to_first"] for r in runs) else 1


def _participants_per_task(campaign) -> int | None:
    """Participants per task of a blind-jnd campaign (None for other kinds)."""
    return getattr(campaign.study, "per_task", None)
