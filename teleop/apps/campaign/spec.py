"""The campaign file (TOML): which study kind, its seed, and what to run.

    [campaign]
    kind = "blind-jnd"     # or "diagnose" (or "noop": empty tasks, to measure the overhead per task)
    seed = 0               # every task's random streams derive from it (and the task's identity)

The other tables belong to the kind: `teleop.apps.campaign.blind` (a grid of simulated blind studies),
`teleop.apps.campaign.recordings` (recordings to diagnose) and `teleop.apps.campaign.noop` document theirs. Unknown
tables and keys raise, with the file and key named; relative paths are relative to the campaign file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from teleop.apps.campaign import blind, noop, recordings
from teleop.apps.campaign.values import get_int
from teleop.core.config import check_keys, load_toml
from teleop.core.errors import InputError

# kind name -> module with parse(doc, where, base_dir), tasks(campaign), execute(task), summarise(...),
# table(summary), write_outputs(summary, dir) and, optionally, warm() (its once-per-process set-up)
KINDS = {blind.KIND: blind, recordings.KIND: recordings, noop.KIND: noop}


@dataclass(frozen=True)
class Campaign:
    """A parsed campaign: `source` (file name, for messages), `kind`, `seed` and the kind's `study`."""

    source: str
    kind: str
    seed: int
    study: object


def kind_module(name: str):
    return KINDS[name]


def load_campaign(path: str | Path, seed: int | None = None) -> Campaign:
    """Read and check the campaign file `path`; `seed` (if given) replaces the file's."""
    doc = load_toml(path)
    where = str(path)
    top = doc.get("campaign")
    if not isinstance(top, dict):
        raise InputError(f"{where}: missing table [campaign] (expected kind = one of: {', '.join(KINDS)})")
    check_keys(top, ("kind", "seed"), f"{where} [campaign]")
    kind = top.get("kind")
    if kind not in KINDS:
        raise InputError(f"{where} [campaign]: kind {kind!r}: expected one of: {', '.join(KINDS)}")
    file_seed = get_int(top, "seed", f"{where} [campaign]", default=0, minimum=0)
    body = {k: v for k, v in doc.items() if k != "campaign"}
    study = kind_module(kind).parse(body, where, Path(path).absolute().parent)
    return Campaign(source=where, kind=kind, seed=file_seed if seed is None else int(seed), study=study)
