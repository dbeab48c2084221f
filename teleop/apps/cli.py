"""The `teleop` command. Subcommands live one per module in `teleop.apps.commands` (discovered, not listed),
each exposing ``register(subparsers)`` that adds its parser and sets ``func(args) -> int``.

Bad input anywhere (an InputError, or an argument argparse rejects in any subcommand) ends with one line
on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import re
import signal
import sys
import threading

from devices.base import DeviceError
from teleop import __version__
from teleop.apps.argtypes import OUTPUT_OPTIONS, OUTPUT_TYPES, seed_int
from teleop.core.errors import InputError
from teleop.io.outputs import same_file
from teleop.io.stop_signals import STOP, exit_code


_TYPE_NAMES = {"int": "an integer", "float": "a number"}


def _expected_form(action: argparse.Action) -> str:
    """How `action` is written on the command line, e.g. ``--test {stiffness,z}`` or ``REC``."""
    if action.metavar is not None:
        metavar = action.metavar if isinstance(action.metavar, str) else " ".join(action.metavar)
    elif action.choices is not None:
        metavar = "{" + ",".join(str(c) for c in action.choices) + "}"
    else:
        metavar = action.dest.upper()
    if not action.option_strings:
        return metavar
    if action.nargs == 0:
        return action.option_strings[0]
    return f"{action.option_strings[0]} {metavar}"


class TeleopArgumentParser(argparse.ArgumentParser):
    """An ArgumentParser whose every error is one line on stderr and exit code 2:
    ``<prog>: error: <what was wrong; what was expected> (see <prog> --help)``.

    `add_subparsers` hands its class to the subcommands' parsers (argparse's default ``parser_class``
    is ``type(self)``), so every parser under `build_parser` (``teleop bench tick`` too) behaves so.
    An argument no parser knows is reported by the deepest subcommand that received it. A ``--seed``
    declared with ``type=int`` is checked as `seed_int` (numpy rejects negative seeds with a traceback);
    an output option (``--json``, ``--plot``, ... see `teleop.apps.argtypes.OUTPUT_OPTIONS`) declared without a
    type is checked as a writable path while the arguments are parsed, before any work starts.
    """

    def add_argument(self, *args, **kwargs):
        if "--seed" in args and kwargs.get("type") is int:
            kwargs["type"] = seed_int
        for name in args:
            if name in OUTPUT_OPTIONS and kwargs.get("type") is None and kwargs.get("action") in (None, "store"):
                kwargs["type"] = OUTPUT_OPTIONS[name]
        return super().add_argument(*args, **kwargs)

    def parse_known_args(self, args=None, namespace=None):
        """Parse like argparse, but leftovers are an error of this parser (not a list returned):
        a subcommand's parser runs first on its arguments, so the message names ``teleop <sub>``."""
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(f"unrecognized argument{'s' if len(extras) > 1 else ''}: {' '.join(extras)}; "
                       f"expected only the arguments of {self.prog}")
        self._refuse_output_on_input(namespace)
        return namespace, extras

    def _refuse_output_on_input(self, namespace) -> None:
        """Exit 2 naming both arguments when an output of this parser is the same file as one of its inputs
        (the same path, a symbolic or a hard link): an output never overwrites an input. Outputs are the
        options of OUTPUT_TYPES or OUTPUT_OPTIONS; every other path-valued argument naming a file is an input."""
        outputs, inputs = [], []
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction) or action.choices is not None:
                continue
            value = getattr(namespace, action.dest, None)
            paths = [v for v in (value if isinstance(value, list) else [value]) if isinstance(v, str) and v]
            is_output = action.type in OUTPUT_TYPES or any(n in OUTPUT_OPTIONS for n in action.option_strings)
            (outputs if is_output else inputs).extend((argparse._get_action_name(action), v) for v in paths)
        for out_name, out in outputs:
            for in_name, source in inputs:
                if same_file(out, source):
                    self.error(f"argument {out_name}: '{out}' is the input {in_name} '{source}' (the same file); "
                               f"expected an output that does not overwrite an input")

    def error(self, message: str):
        """Print ``<prog>: error: <message> (see <prog> --help)`` on one line and exit 2."""
        self.exit(2, f"{self.prog}: error: {self._explain(message)} (see {self.prog} --help)\n")

    def _explain(self, message: str) -> str:
        """argparse's message with what was expected added where argparse leaves it out; one line."""
        message = " ".join(str(message).split())
        bad_type = re.fullmatch(r"argument (\S+): invalid (\w+) value: (.*)", message)
        if bad_type:
            name, type_name, value = bad_type.groups()
            expected = _TYPE_NAMES.get(type_name, f"a valid {type_name} value")
            return f"argument {name}: expected {expected}, got {value}"
        missing = re.fullmatch(r"the following arguments are required: (.*)", message)
        if missing:
            names = {n.strip() for n in missing.group(1).split(",")}
            forms = [_expected_form(a) for a in self._actions
                     if argparse._get_action_name(a) in names]
            if forms:
                return f"missing required argument{'s' if len(forms) > 1 else ''}: {missing.group(1)}; " \
                       f"expected {' '.join(forms)}"
        return message


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


def build_parser() -> TeleopArgumentParser:
    parser = TeleopArgumentParser(
        prog="teleop", description="Teleoperation and haptic rendering for a cable-driven surgical robot.")
    parser.add_argument("--version", action="version", version=f"cdpr-teleop {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    discover("teleop.apps.commands", sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the `teleop` command on `argv` (default: sys.argv[1:]); return the exit code.

    0 on success (also for --help and --version), 2 on bad input (one line on stderr), 128 + the signal's
    number when SIGINT (Ctrl-C: 130), SIGTERM (143) or SIGHUP (129) stopped it (teleop.io.stop_signals).
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or an argument error already printed as one line
        return exc.code if isinstance(exc.code, int) else 2
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    main_thread = threading.current_thread() is threading.main_thread()
    if main_thread:  # the one handler of SIGINT, SIGTERM and SIGHUP (teleop.io.stop_signals)
        STOP.install()
    try:
        code = int(args.func(args) or 0)
        return exit_code(STOP.signum) if STOP.signum else code  # a polling command wrote its partial results
    except InputError as exc:
        print(f"teleop: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        signum = STOP.signum or signal.SIGINT
        print(f"teleop: interrupted ({signal.Signals(signum).name})", file=sys.stderr)
        return exit_code(signum)
    except OSError as exc:
        if STOP.signum:  # stopped, and the output failed on the way out (SIGHUP: the terminal is gone)
            return exit_code(STOP.signum)
        if exc.filename is None:
            raise
        # a file the command was given (or its directory) failed under it: name it, no traceback
        names = " -> ".join(str(f) for f in (exc.filename, exc.filename2) if f is not None)
        print(f"teleop: error: {names}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except Exception as exc:
        message = _device_error(exc)
        if message is None:
            raise
        print(f"teleop: error: {message}", file=sys.stderr)
        return 2
    finally:
        if main_thread:
            STOP.uninstall(ignore=bool(STOP.signum))  # stopped: a repeat must not kill the shutdown


def _device_error(exc: Exception) -> str | None:
    """One line for a device that failed (devices.base.DeviceError: a port that will not open, a lost
    link, an SDK error), or None for any other exception (a bug, shown with its traceback)."""
    return " ".join(str(exc).split()) if isinstance(exc, DeviceError) else None


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
