"""`teleop campaign run|summary FILE --out DIR`: a campaign file (a grid of simulated blind studies, or
recordings to diagnose) run in this process, on a Dask LocalCluster or on a Dask cluster; resumable."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from teleop.apps.campaign.runner import run_campaign, summarise, summary_text
from teleop.apps.campaign.scheduler import FORMS, parse_scheduler
from teleop.apps.campaign.spec import load_campaign
from teleop.apps.campaign.store import ResultStore
from teleop.core.errors import InputError
from teleop.io.outputs import check_output, output_problem, write_json


def _scheduler(text: str) -> str:
    try:
        parse_scheduler(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).replace("--scheduler ", "", 1)) from None
    return text


def add_scheduler_option(p) -> None:
    """--scheduler, shared by every command that runs tasks through teleop.apps.campaign."""
    p.add_argument("--scheduler", type=_scheduler, default="none", metavar="WHERE",
                   help=f"where tasks run: {FORMS}; default none (in this process)")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "campaign", help="run a campaign file (grid of simulated blind studies, or recordings to diagnose) on Dask",
        description="Each finished task is written to --out as it completes; the same command run again skips "
                    "what is done. Results do not depend on --scheduler.")
    sub = p.add_subparsers(dest="campaign_command", metavar="ACTION")
    for name, help_text in (("run", "run what the campaign still needs, then summarise"),
                            ("summary", "summarise what --out holds (tables, plots), run nothing")):
        q = sub.add_parser(name, help=help_text)
        q.add_argument("file", metavar="FILE", help="campaign file (TOML; see examples/jnd_grid.toml)")
        q.add_argument("--out", required=True, metavar="DIR", help="result directory (created if missing)")
        q.add_argument("--seed", type=int, default=None, help="replaces the campaign file's seed")
        q.add_argument("--json", metavar="PATH", help="also write the summary JSON here")
        if name == "run":
            add_scheduler_option(q)
        q.set_defaults(func=run)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])


def run(args) -> int:
    problem = output_problem(args.out, directory=True)
    if problem:
        raise InputError(f"--out {args.out}: {problem}")
    if args.json:
        check_output(args.json, "--json")
    campaign = load_campaign(args.file, args.seed)
    if args.campaign_command == "run":
        report = run_campaign(campaign, args.out, args.scheduler)
        summary = report.summary
        if report.ran:
            secs = report.task_seconds
            print(f"campaign: ran {report.ran} tasks in {report.wall_s:.1f} s on {args.scheduler} (start "
                  f"{report.start_s:.1f} s, set-up {report.warm_s:.1f} s; {sum(secs) / len(secs):.2f} s per task "
                  "where it ran)", file=sys.stderr)
    else:
        if not (Path(args.out) / "tasks").is_dir():
            raise InputError(f"--out {args.out}: holds no campaign results (run `teleop campaign run` first)")
        with ResultStore(args.out) as store:
            summary = summarise(campaign, store)
    print(summary_text(campaign, summary))
    print(f"results: {args.out} (summary.json, summary.txt and plots)", file=sys.stderr)
    if args.json:
        write_json(args.json, summary, sort_keys=True)
    return 1 if summary["tasks"]["failed"] else 0
