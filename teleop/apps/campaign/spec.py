"""The campaign file (TOML): which study kind, its seed, and what to run.

    [campaign]
    kind = "blind-jnd"     # or "diagnose" (or "noop": empty tasks, to measure the overhead per task)
    seed = 0               # every task's random streams derive from it (and the task's identity)

The other tables belong to the kind: `teleop.apps.campaign.blind` (a grid of simulated blind studies),
`teleop.apps.campaign.recordings` (recordings to diagnose) and `teleop.apps.campaign.noop` document theirs. Unknown
tables and keys raise, with the file and key named; relative paths are relative to the campaign file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from teleop.core.config import check_keys, load_toml
from teleop.core.errors import InputError


@dataclass(frozen=True)
class Campaign:
    """A parsed campaign: `source` (file name, for messages), `kind`, `seed` and the kind's `study`."""

    source: str
    kind: str
    seed: int
    study: object


def kinds() -> dict:
    """kind name -> module with parse(doc, where, base_dir), tasks(campaign), execute(task), summarise(...),
    table(summary), write_outputs(summary, dir) and, optionally, warm() (its once-per-process set-up)."""
    from teleop.apps.campaign import blind, noop, recordings

    return {blind.KIND: blind, recordings.KIND: recordings, noop.KIND: noop}


def kind_module(name: str):
    return kinds()[name]


def load_campaign(path: str | Path, seed: int | None = None) -> Campaign:
    """Read and check the campaign file `path`; `seed` (if given) replaces the file's."""
    doc = load_toml(path)
    where = str(path)
    top = doc.get("campaign")
    if not isinstance(top, dict):
        raise InputError(f"{where}: missing table [campaign] (expected kind = one of: {', '.join(kinds())})")
    check_keys(top, ("kind", "seed"), f"{where} [campaign]")
    kind = top.get("kind")
    if kind not in kinds():
        raise InputError(f"{where} [campaign]: kind {kind!r}: expected one of: {', '.join(kinds())}")
    file_seed = get_int(top, "seed", f"{where} [campaign]", default=0, minimum=0)
    body = {k: v for k, v in doc.items() if k != "campaign"}
    study = kind_module(kind).parse(body, where, Path(path).absolute().parent)
    return Campaign(source=where, kind=kind, seed=file_seed if seed is None else int(seed), study=study)


def get_int(table: dict, key: str, where: str, default: int | None = None, minimum: int | None = None) -> int:
    """A whole number from `table[key]` (or `default`), at least `minimum`, with the file and key named."""
    if key not in table:
        if default is None:
            raise InputError(f"{where}: missing key '{key}' (expected a whole number)")
        return int(default)
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, int):
        raise InputError(f"{where}: key '{key}' must be a whole number, got {v!r}")
    if minimum is not None and v < minimum:
        raise InputError(f"{where}: key '{key}' must be >= {minimum}, got {v}")
    return int(v)


def coerce(kind: str, value, where: str):
    """`value` checked against a dataclass field type written as text ('float', 'int', 'bool', 'str',
    'float | None'); ints are accepted for floats. Returns the value as that type."""
    base = kind.replace(" | None", "").strip()
    if base == "bool":
        if not isinstance(value, bool):
            raise InputError(f"{where}: expected true or false, got {value!r}")
        return value
    if base == "str":
        if not isinstance(value, str):
            raise InputError(f"{where}: expected a string, got {value!r}")
        return value
    if base == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(f"{where}: expected a whole number, got {value!r}")
        return int(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{where}: expected a number, got {value!r}")
    if not math.isfinite(value):
        raise InputError(f"{where}: expected a finite number, got {value!r}")
    return float(value)
