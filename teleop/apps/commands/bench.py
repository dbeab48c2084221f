"""`teleop bench KIND`: benchmarks (tick, loop, diagnose, ...), one module each in `teleop.apps.bench`."""

from __future__ import annotations

from teleop.apps.cli import discover


def register(subparsers) -> None:
    p = subparsers.add_parser("bench", help="benchmarks: timing and accuracy numbers a script can check")
    sub = p.add_subparsers(dest="bench", metavar="KIND")
    discover("teleop.apps.bench", sub)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])
