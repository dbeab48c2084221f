"""Strict TOML loading: unknown keys raise, values are checked with the file and key named."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path
from typing import Any, Iterable

from teleop.core.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib


def input_problem(path: str | Path) -> str | None:
    """Why `path` cannot be read as an input file (empty, missing, a directory, unreadable), or None."""
    if str(path) == "":
        return "expected a file name"
    path = Path(path)
    if not path.exists():
        return "file not found"
    if path.is_dir():
        return "is a directory, expected a file"
    if not os.access(path, os.R_OK):
        return "is not readable (permission denied)"
    return None


def check_input(path: str | Path) -> Path:
    """`path` if it is a readable file, else an InputError naming it (call before the work starts)."""
    problem = input_problem(path)
    if problem:
        raise InputError(f"{str(path) or repr('')}: {problem}")
    return Path(path)


def load_toml(path: str | Path) -> dict:
    """Read a TOML file; a missing, unreadable or non-UTF-8 file or a syntax error is an InputError naming it."""
    path = check_input(path)
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not UTF-8 text ({exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: invalid TOML ({exc})") from None


def load_toml_table(path: str | Path, table: str) -> tuple[dict, str]:
    """The table `table` of a TOML file and the place to name in errors ("FILE [table]"); a file `load_toml`
    refuses, or one without that table, is an InputError naming it."""
    data = load_toml(path)
    if table not in data or not isinstance(data[table], dict):
        raise InputError(f"{path}: no [{table}] table")
    return data[table], f"{path} [{table}]"


def check_keys(table: dict, allowed: Iterable[str], where: str) -> None:
    """Raise if `table` has a key outside `allowed` (python-control style: unknown keys raise)."""
    allowed = set(allowed)
    for key in table:
        if key not in allowed:
            raise InputError(f"{where}: unknown key '{key}' (expected one of: {', '.join(sorted(allowed))})")


def get_number(table: dict, key: str, where: str, default: Any = None, *, positive: bool = False,
               nonnegative: bool = False) -> float:
    """A finite float from `table[key]` (or `default`), with the file and key named on error."""
    if key not in table:
        if default is None:
            raise InputError(f"{where}: missing key '{key}' (expected a number)")
        return float(default)
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"{where}: key '{key}' must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise InputError(f"{where}: key '{key}' must be > 0, got {value!r}")
    if nonnegative and value < 0:
        raise InputError(f"{where}: key '{key}' must be >= 0, got {value!r}")
    return float(value)


def get_integer(table: dict, key: str, where: str) -> int:
    """An int from `table[key]` (a TOML integer, not a bool or float), with the file and key named on error."""
    value = table.get(key)
    if not isinstance(value, int) or isinstance(value, bool):
        raise InputError(f"{where}: key '{key}' must be an integer, got {value!r}")
    return value


def get_vectors(table: dict, key: str, where: str, n: int, dim: int = 3) -> list[list[float]]:
    """An n x dim list of finite numbers from `table[key]`."""
    if key not in table:
        raise InputError(f"{where}: missing key '{key}' (expected {n} vectors of {dim} numbers)")
    rows = table[key]
    ok = isinstance(rows, list) and len(rows) == n and all(
        isinstance(r, list) and len(r) == dim and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in r)
        for r in rows)
    if not ok:
        raise InputError(f"{where}: key '{key}' must be {n} vectors of {dim} finite numbers")
    return [[float(v) for v in r] for r in rows]
