"""The narrow interface between a participant and the rig: one poke in, one force-displacement trace out.

A participant never learns which material sits under a zone: the coordinator (the study driver) turns the
zone into a pad slot, and the participant receives only what the stylus felt during its own push.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class Poke:
    """What the stylus felt during one poke.

    Attributes:
        t: (n,) time since the push started [s].
        x: (n,) stylus displacement along the push direction from where the push started [m].
        f: (n,) force rendered on the stylus against the push direction [N] (positive resists the push).
    """

    t: np.ndarray
    x: np.ndarray
    f: np.ndarray


@dataclass(frozen=True)
class PokeRequest:
    """How a participant means to push along the push direction: the hand moves at `speed` [m/s] until the
    force felt on the stylus reaches `force` [N] (the pressure exploratory procedure: press to a comfortable
    force, Lederman & Klatzky 1987), or the hand has travelled `depth` [m]; force None: depth only."""

    depth: float
    speed: float
    force: float | None = None


class PressAborted(Exception):
    """The rig stopped during a press: the robot faulted (a cable tension left its range) and the stylus
    went limp. The rig is reset for the next poke; what was felt is lost."""


class Prober(Protocol):
    """A rig that can poke pad slot `slot` (index into the pad layout) as a participant asks."""

    def poke(self, slot: int, request: PokeRequest) -> Poke: ...
