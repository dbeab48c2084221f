"""A task's identity and its random streams.

A task is identified by everything its result depends on (a plain dict of JSON values: parameters,
campaign seed, the participants or recording it covers); its id is a digest of that dict's canonical JSON.
Its random streams come from the campaign seed and a key taken from that identity, through numpy's
SeedSequence: `stream(seed, *key)` is the child `SeedSequence(seed).spawn` hands out at position `key`
(its `spawn_key`), addressed by identity instead of by the order children are spawned, so where and in
which order tasks run never changes a draw.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

import numpy as np

from teleop import __version__


def canonical_json(obj) -> str:
    """Compact JSON with sorted keys (floats as Python's shortest round-trip repr): the text that is hashed."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


@dataclass(frozen=True)
class Task:
    """One unit of work: `kind` (the campaign kind that executes it), `identity` (what its result depends
    on, JSON values only) and `label` (its parameters in a line, for progress and failure reports)."""

    kind: str
    identity: dict
    label: str

    @property
    def id(self) -> str:
        """`<kind>-<first 20 hex digits of sha256 of the canonical kind, package version and identity>`: a file
        name, stable across runs of one version (a new version of the package computes its results afresh;
        while the simulation's code is being edited within a version, use a fresh result directory)."""
        key = {"kind": self.kind, "teleop_version": __version__, **self.identity}
        return f"{self.kind}-{hashlib.sha256(canonical_json(key).encode()).hexdigest()[:20]}"


def stream(seed: int, *key: int) -> np.random.SeedSequence:
    """The random stream of `key` (non-negative ints from a task's identity) in a campaign seeded `seed`:
    the same as ``SeedSequence(seed).spawn(k + 1)[k]`` for a one-element key (k,)."""
    return np.random.SeedSequence(int(seed), spawn_key=tuple(int(k) for k in key))


def seeds(seed: int, *key: int, n: int = 2) -> tuple:
    """`n` integer seeds (0 <= s < 2**32) drawn from `stream(seed, *key)`."""
    return tuple(int(s) for s in stream(seed, *key).generate_state(n))
