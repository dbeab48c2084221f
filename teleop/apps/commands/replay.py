"""`teleop replay FILE`: play a recorded session back through the loop and check it reproduces."""

from __future__ import annotations

import sys
from dataclasses import asdict

from teleop.apps.argtypes import input_file
from teleop.io.outputs import write_json
from teleop.loop.replay import replay_session


def register(subparsers) -> None:
    p = subparsers.add_parser("replay", help="replay a recorded session through the loop; exit 1 if it differs")
    p.add_argument("file", type=input_file, help="session recording (.mcap)")
    p.add_argument("--json", metavar="F", help="write the replay report as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    rep = replay_session(args.file)
    if rep.damage:
        print(f"teleop: warning: {args.file}: {rep.damage}; replaying the intact prefix", file=sys.stderr)
    print(f"replayed {rep.ticks} ticks: {rep.force_mismatches} force, {rep.command_mismatches} command, "
          f"{rep.state_mismatches} state, {rep.estimate_mismatches} estimate mismatches "
          f"(max |dF| {rep.max_force_diff:.3g} N, max |dW| {rep.max_wrench_diff:.3g} N, "
          f"max |dL| {rep.max_length_diff:.3g} m) -> {'reproduced' if rep.reproduced else 'DIFFERS'}")
    if args.json:
        write_json(args.json, {**asdict(rep), "reproduced": rep.reproduced})
    return 0 if rep.reproduced else 1
