"""`teleop bench blind-jnd`: share of simulated participants ranking the four areas correctly, against the
stiffness JND, through the whole simulated chain (default 100 participants per point).

A one-point campaign (teleop.apps.campaign.blind, which documents the seeding): every participant is run at
every JND on the same pad layout, presentation order and pushes (common random numbers), in blocks of
--participants-per-task, in this process or on Dask (--scheduler); --out keeps the finished blocks, so the
same command run again resumes.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile

from teleop.apps.argtypes import positive_int
from teleop.apps.campaign.blind import KIND, PER_TASK, BlindStudy, curve_table, jnd_values, make_point
from teleop.apps.campaign.plots import jnd_curves_figure
from teleop.apps.campaign.runner import run_campaign
from teleop.apps.campaign.spec import Campaign
from teleop.apps.commands.blind_test import add_rig_options, participant_params, rig_options
from teleop.apps.commands.campaign import add_scheduler_option
from teleop.apps.protocols.blind.rig import SimRig, rig_dict
from teleop.core.errors import InputError
from teleop.io.outputs import check_output, output_problem, save_figure, write_json

DEFAULT_JNDS = "0.05,0.1,0.15,0.23,0.3,0.4,0.6,0.8"


def register(subparsers) -> None:
    p = subparsers.add_parser("blind-jnd", help="correct-ranking share vs stiffness JND (blind test, simulated)")
    p.add_argument("--participants", type=positive_int, default=100, metavar="N", help="participants per point")
    p.add_argument("--jnd", default=DEFAULT_JNDS, metavar="J1,J2,...",
                   help=f"JNDs as Weber fractions (default {DEFAULT_JNDS})")
    p.add_argument("--seed", type=int, default=0)
    add_rig_options(p)
    add_scheduler_option(p)
    p.add_argument("--participants-per-task", type=positive_int, default=PER_TASK, metavar="K",
                   help=f"participants per task (default {PER_TASK})")
    p.add_argument("--out", metavar="DIR", help="keep each finished task here (resumable); default: a temporary "
                                                "directory")
    p.add_argument("--json", metavar="PATH", help="write the curve as JSON")
    p.add_argument("--plot", metavar="PATH", help="write the curve as a PNG")
    p.set_defaults(func=run, jnd_list=None)


def parse_jnds(text: str) -> list:
    """'0.4, 23%,0.1' -> [0.1, 0.23, 0.4] (sorted, distinct)."""
    return jnd_values([s.strip() for s in str(text).split(",") if s.strip()], f"--jnd '{text}'")


def run(args) -> int:
    jnds = parse_jnds(args.jnd)
    args.jnd = None
    base = participant_params(args)
    options = rig_options(args)
    for flag, path in (("--json", args.json), ("--plot", args.plot)):
        if path:
            check_output(path, flag)
    if args.out and output_problem(args.out, directory=True):
        raise InputError(f"--out {args.out}: {output_problem(args.out, directory=True)}")
    point = make_point({}, {k: v for k, v in rig_dict(options).items() if k != "seed"},
                       {k: v for k, v in dataclasses.asdict(base).items() if k != "jnd"}, "teleop bench blind-jnd")
    study = BlindStudy(participants=args.participants, per_task=args.participants_per_task, jnds=tuple(jnds),
                       points=(point,))
    campaign = Campaign(source="teleop bench blind-jnd", kind=KIND, seed=args.seed, study=study)
    with tempfile.TemporaryDirectory(prefix="blind-jnd-") as tmp:
        report = run_campaign(campaign, args.out or tmp, args.scheduler)
    summary = report.summary
    points = summary["points"][0]["curve"]
    print(curve_table(points))
    for f in summary["tasks"]["failed"]:
        print(f"teleop bench blind-jnd: task failed: {f['label']}: {f['error']}", file=sys.stderr)
    if args.json:
        write_json(args.json, {"participants": args.participants, "seed": args.seed,
                               "complete": summary["points"][0]["complete"], "points": points,
                               "participant_params": dataclasses.asdict(base),
                               "rig": SimRig(options).describe(), "scheduler": args.scheduler})
    if args.plot and points:
        title = (f"teleop bench blind-jnd: blind stiffness ranking against the JND, simulated robot\n"
                 f"plant {options.plant}, sensor {options.sensor}, {args.participants} simulated participants per "
                 f"point, seed {args.seed}" + ("" if options.compensation else " (no compensation)"))
        save_figure(jnd_curves_figure([("", points)], title), args.plot)
    return 1 if summary["tasks"]["failed"] else 0
