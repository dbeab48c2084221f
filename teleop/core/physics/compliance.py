"""Cable compliance: the cable stretches under load, so the tip lags the motor by load / k.

tip = x - load / k, with x the motor position [m] (cable hauled in) and load the tip tension [N]. The one
home of the physics is the closed form `cable_stretch` (vectorised numpy, several times faster than a
compiled loop over a step kernel); the Step calls it on one sample.
"""

from __future__ import annotations

import numpy as np

from teleop.core.physics.base import Effect, ParamSpec, Rules, Signals, Step, register


def cable_stretch(x: np.ndarray, load: np.ndarray, k: float) -> np.ndarray:
    """(n,) tip position [m]: x - load / k, with k the cable (and sheath) axial stiffness [N/m]."""
    return np.asarray(x, dtype=float) - np.asarray(load, dtype=float) / k


class ComplianceStep(Step):
    """Per-sample cable_compliance: step(x, load) -> tip position [m], the closed form on one sample."""

    effect_name = "cable_compliance"

    def reset(self) -> None:
        pass

    def step(self, x: float, load: float) -> float:
        return float(cable_stretch(x, load, self.params["k"]))


def _guess(signals: Signals, y: np.ndarray) -> dict:
    # x - y = load / k  ->  1/k by least squares through the origin
    e = signals.x - y
    c = float(np.dot(signals.load, e) / max(np.dot(signals.load, signals.load), 1e-300))
    return {"k": 1.0 / c if c > 0 else PARAMS[0].default}


PARAMS = (ParamSpec("k", "N/m", 1.0, 1e9, 2e4, "axial stiffness of the cable between motor and tip",
                    log=True, positive=True),)


CABLE_COMPLIANCE = register(Effect(
    name="cable_compliance",
    link="position",
    doc="load-dependent stretch: tip = motor - load / k",
    params=PARAMS,
    inputs=("x", "load"),
    output="x",
    simulate=lambda s, p: cable_stretch(s.x, s.load, p["k"]),
    guess=_guess,
    step_class=ComplianceStep,
    rules=Rules(channel="tip_pos", primary=("k",),
                draw=lambda rng, s: {"k": s.load_span / (rng.uniform(0.04, 0.12) * 2 * s.travel)}),
))
