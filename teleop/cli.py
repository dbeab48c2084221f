"""The `teleop` command. Subcommands live one per module in `teleop.commands` (discovered, not listed),
each exposing ``register(subparsers)`` that adds its parser and sets ``func(args) -> int``.

Bad input anywhere (an InputError) ends with one line on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from teleop import __version__
from teleop.errors import InputError


def discover(package: str, subparsers) -> None:
    """Import every module of `package` and let it register its subcommand(s)."""
    pkg = importlib.import_module(package)
    for info in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{package}.{info.name}")
        register = getattr(module, "register", None)
        if register is not None:
            register(subparsers)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="teleop", description="Teleoperation and haptic rendering for a cable-driven surgical robot.")
    parser.add_argument("--version", action="version", version=f"cdpr-teleop {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    discover("teleop.commands", sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"teleop: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("teleop: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
