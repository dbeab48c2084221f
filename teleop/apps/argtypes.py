"""argparse types for the command line: each rejects a bad value with what was expected, which
teleop.apps.cli turns into one line on stderr and exit code 2."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from teleop.core.config import input_problem
from teleop.core.geometry import Geometry, load_geometry
from teleop.io.outputs import FIGURE_FORMATS, output_problem


def _number(text: str, kind):
    try:
        v = kind(text)
    except ValueError:
        what = "a whole number" if kind is int else "a number"
        raise argparse.ArgumentTypeError(f"expected {what}, got '{text}'") from None
    if kind is float and not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got '{text}'")
    return v


def _checked(text: str, kind: type, ok, expected: str, shown=None):
    """`text` as a `kind` number for which ok(v) holds; else 'expected <expected>, got <shown or v>'."""
    v = _number(text, kind)
    if not ok(v):
        raise argparse.ArgumentTypeError(f"expected {expected}, got {v if shown is None else shown}")
    return v


def positive_int(text: str) -> int:
    """A whole number >= 1 (counts: participants, trials, round trips)."""
    return _checked(text, int, lambda v: v >= 1, "a whole number >= 1")


def seed_int(text: str) -> int:
    """A whole number >= 0 (what numpy's random generators accept)."""
    return _checked(text, int, lambda v: v >= 0, "a whole number >= 0 (a random generator seed)")


def finite_float(text: str) -> float:
    """A finite number (no nan or inf)."""
    return _number(text, float)


def positive_float(text: str) -> float:
    """A finite number > 0 (durations [s], rates [Hz])."""
    return _checked(text, float, lambda v: v > 0, "a number > 0", text)


def float_in(lo: float, hi: float, unit: str = ""):
    """An argparse type: a finite number in [lo, hi] (`unit` is shown in the message)."""
    def check(text: str) -> float:
        return _checked(text, float, lambda v: lo <= v <= hi, f"a number from {lo:g} to {hi:g}{unit}", text)

    check.__name__ = f"float_in_{lo:g}_{hi:g}"
    return check


# The loop and robot-link rates the estimator's Kalman filter is designed for (a steady-state gain
# exists for frame periods of 0.1 to 20 ms) and a haptic loop can keep.
LOOP_RATE_HZ = float_in(100.0, 10_000.0, " Hz")
ROBOT_RATE_HZ = float_in(50.0, 10_000.0, " Hz")
# A session's length: the timing log holds 80 bytes per tick (4 h at 1 kHz: 1.2 GB).
SESSION_SECONDS = float_in(0.001, 4 * 3600.0, " s")


def nonnegative_float(text: str) -> float:
    """A finite number >= 0."""
    return _checked(text, float, lambda v: v >= 0, "a number >= 0", text)


def rt_priority(text: str) -> int:
    """A SCHED_FIFO priority 1-99, or 0 for time-sharing."""
    return _checked(text, int, lambda v: 0 <= v <= 99, "0 (time-sharing) or a SCHED_FIFO priority 1-99")


# A person's stiffness JND as a Weber fraction: a participant who cannot tell two stiffnesses 2x apart
# (above 100 %) or who tells 1 % apart is not a person; values outside are a typo (`--jnd 5` for 5 %).
JND_RANGE = (0.01, 1.0)


def jnd_fraction(text: str) -> float:
    """'0.23' or '23%' -> 0.23 (argparse type for --jnd), within JND_RANGE."""
    s = str(text).strip()
    try:
        v = float(s[:-1]) / 100.0 if s.endswith("%") else float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a fraction like 0.23 or a percentage like 23%, got '{text}'")
    lo, hi = JND_RANGE
    if not (math.isfinite(v) and lo <= v <= hi):
        hint = f"; for {s} % write {s}%" if math.isfinite(v) and v > hi and not s.endswith("%") else ""
        raise argparse.ArgumentTypeError(
            f"expected a stiffness JND a person can have, {lo:g} to {hi:g} as a Weber fraction "
            f"({lo:.0%} to {hi:.0%}; Jones & Hunter 1990: 0.23), got '{text}'{hint}")
    return v


def input_file(text: str) -> str:
    """A path to an existing, readable file (not a directory)."""
    problem = input_problem(text)
    if problem:
        raise argparse.ArgumentTypeError(f"'{text}': {problem}")
    return text


def add_geometry_option(p) -> None:
    """--geometry TOML on every command that builds the robot (read with `geometry_of`)."""
    p.add_argument("--geometry", type=input_file, default=None, metavar="TOML",
                   help="the robot's geometry: anchors, tip, sheath bend and friction, tension, length and speed "
                        "limits (a [geometry] table, docs/formats.md; default: the seed robot, written out in "
                        "examples/geometry.toml)")


def geometry_of(args) -> Geometry | None:
    """The geometry `--geometry` names (teleop.core.geometry.load_geometry: a bad file or key is an InputError
    naming both), or None when the option is absent or not given: the callee's default, the seed robot (a
    device that takes no geometry, a stylus or a replayed robot, is then not handed one)."""
    path = getattr(args, "geometry", None)
    return load_geometry(path) if path else None


def output_file(text: str) -> str:
    """A path a result file can be written to (checked before any work starts; nothing is created yet)."""
    problem = output_problem(text)
    if problem:
        raise argparse.ArgumentTypeError(f"'{text}' {problem}")
    return text


def output_figure(text: str) -> str:
    """A path a figure can be written to, its suffix naming a format `save_figure` writes (.png, .pdf, .svg)."""
    suffix = Path(text).suffix
    if suffix.lower() not in FIGURE_FORMATS:
        raise argparse.ArgumentTypeError(f"'{text}': expected a figure file name ending in "
                                         f"{', '.join(s for s in FIGURE_FORMATS if s)}, got '{suffix}'")
    return output_file(text)


def output_dir(text: str) -> str:
    """A path that is, or can be made, a writable directory."""
    problem = output_problem(text, directory=True)
    if problem:
        raise argparse.ArgumentTypeError(f"'{text}' {problem}")
    return text


# Options that name a result file or directory: every parser of the `teleop` command checks them with
# these types when declared without one (teleop.apps.cli.TeleopArgumentParser), so each output is checked
# before the work starts.
OUTPUT_OPTIONS = {"--json": output_file, "--plot": output_figure, "--csv": output_file, "--save-model": output_file,
                  "--record": output_file, "--state": output_file, "--build-dir": output_dir}
# The types of an argument that names a result (teleop.apps.cli refuses one that is also an input).
OUTPUT_TYPES = (output_file, output_figure, output_dir)
