"""Cable compliance: the cable stretches under load, so the tip lags the motor by load / k.

tip = x - load / k, with x the motor position [m] (cable hauled in) and load the tip tension [N]. The one
home of the physics is the closed form `cable_stretch` (vectorised numpy, several times faster than a
compiled loop over a step kernel); the Step calls it on one sample.

General form (`wrap` > 0): the load is read at the motor, beyond a sheath whose friction holds the tip
tension while the motor force crosses its band at a reversal (teleop.core.physics.capstan, flat
transitions): the tension the cable stretches under is the capstan's tip estimate from the reading,
clamp(T, load e^-wrap, load e^+wrap), wrap = mu Theta. A recording without a tip force sensor offers the
motor force as the load; its e^(+-mu Theta) switch at each reversal is no stretch of the cable.
"""

from __future__ import annotations

import numpy as np

from teleop.core.physics.base import Effect, ParamSpec, Rules, Signals, Step, register
from teleop.core.physics.capstan import CapstanCompensator, motor2tip_transitions


def cable_stretch(x: np.ndarray, load: np.ndarray, k: float) -> np.ndarray:
    """(n,) tip position [m]: x - load / k, with k the cable (and sheath) axial stiffness [N/m]."""
    return np.asarray(x, dtype=float) - np.asarray(load, dtype=float) / k


def stretched_by(load: np.ndarray, wrap: float) -> np.ndarray:
    """(n,) the tension [N] the cable stretches under: the load itself (wrap 0), or the capstan's tip
    estimate from a load read at the motor beyond a sheath of friction wrap = mu Theta (flat transitions,
    capstan.motor2tip_transitions)."""
    return np.asarray(load, dtype=float) if wrap <= 0 else motor2tip_transitions(load, wrap, 1.0)


def _simulate(s: Signals, p) -> np.ndarray:
    return cable_stretch(s.x, stretched_by(s.load, p["wrap"]), p["k"])


class ComplianceStep(Step):
    """Per-sample cable_compliance: step(x, load) -> tip position [m], the closed form on one sample (the
    general form's tip tension from the capstan compensator's state)."""

    effect_name = "cable_compliance"

    def reset(self) -> None:
        wrap = self.params["wrap"]
        self._tip = CapstanCompensator(wrap, 1.0) if wrap > 0 else None

    def step(self, x: float, load: float) -> float:
        tension = self._tip.step(load) if self._tip is not None else load
        return float(cable_stretch(x, tension, self.params["k"]))


def _guess(signals: Signals, y: np.ndarray) -> dict:
    # x - y = load / k  ->  1/k by least squares through the origin
    e = signals.x - y
    c = float(np.dot(signals.load, e) / max(np.dot(signals.load, signals.load), 1e-300))
    return {"k": 1.0 / c if c > 0 else PARAMS[0].default}


PARAMS = (ParamSpec("k", "N/m", 1.0, 1e9, 2e4, "axial stiffness of the cable between motor and tip",
                    log=True, positive=True),
          ParamSpec("wrap", "1", 0.0, 2.0, 0.0, "mu Theta of a sheath between the load's sensor and the tip "
                    "(the load read at the motor: the cable stretches under the capstan's tip tension; "
                    "general form; 0: the load is the tip's)", shape=True))


CABLE_COMPLIANCE = register(Effect(
    name="cable_compliance",
    link="position",
    doc="load-dependent stretch: tip = motor - load / k",
    params=PARAMS,
    inputs=("x", "load"),
    output="x",
    simulate=_simulate,
    guess=_guess,
    step_class=ComplianceStep,
    # where the load is read at the motor the plain form's stretch switches with the capstan at each
    # reversal and cannot pay: the general form is a candidate of its own
    rules=Rules(channel="tip_pos", primary=("k",), general_candidate=True,
                draw=lambda rng, s: {"k": s.load_span / (rng.uniform(0.04, 0.12) * 2 * s.travel)}),
))
