"""Backlash (play, dead band) between the motor and the tip: the play operator.

The tip position y follows the motor position x only once the play of total width w is taken up:
y_k = clamp(y_k-1, x_k - w/2, x_k + w/2), starting centred (y_0 = x_0). While x moves inside the dead
band y stays put; while x drives, y = x -/+ w/2 (lagging behind the motion).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from teleop.physics.base import Effect, ParamSpec, Signals, Step, register
from teleop.physics.scan import clamp_step, play


def backlash(x: np.ndarray, width: float, y0: float | None = None) -> np.ndarray:
    """(n,) tip position [m or rad] from motor position x (n,) with play of total width [same unit]."""
    x = np.asarray(x, dtype=float)
    return play(float(x[0]) if y0 is None else float(y0), x, 0.5 * width)


def _simulate(signals: Signals, p: Mapping[str, float]) -> np.ndarray:
    return backlash(signals.x, p["width"])


def _guess(signals: Signals, y: np.ndarray) -> dict:
    # while driving, x - y = +/- w/2: the spread of x - y is the full width
    e = signals.x - y
    return {"width": float(np.percentile(e, 98) - np.percentile(e, 2))}


PARAMS = (ParamSpec("width", "m", 1e-8, 100.0, 5e-4, "total play (dead band) width; rad for a rotary joint (a tendon-sheath joint can lose radians)",
                    log=True),)


class BacklashStep(Step):
    """Per-sample backlash: step(x) -> tip position."""

    effect_name = "backlash"

    def reset(self) -> None:
        self.y = None

    def step(self, x: float) -> float:
        r = 0.5 * self.params["width"]
        self.y = x if self.y is None else clamp_step(self.y, x - r, x + r)
        return float(self.y)


BACKLASH = register(Effect(
    name="backlash",
    link="position",
    doc="play operator: tip = clamp(tip_prev, motor - width/2, motor + width/2)",
    params=PARAMS,
    inputs=("x",),
    output="x",
    simulate=_simulate,
    guess=_guess,
    step_class=BacklashStep,
))
