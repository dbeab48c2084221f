"""A spring beside the transmission: the motor carries a position-dependent force the tip sensor never sees.

motor force = load + k dx (1 + c dx), dx = x - x_ref, with x the motor position [m; rad on a rotary drive],
k the spring's stiffness at x_ref [N/m; N m/rad] and c its change of stiffness with position [1/m; 1/rad]
(the general form: 0 is a linear spring). The force is conservative: the same in both directions of motion,
a function of where the drive is, not of where it has been.

Where it comes from: anything elastic that the drive deforms in parallel with the cable path to the tip
sensor: a return spring, the other cable pairs of a wrist that the drive's pulley stretches, a flexure or a
cable harness between the drive and the frame. On the MRDLab da Vinci instrument the spindle's torque carries
the same restoring torque over the stroke at 10 % and 40 % reaction torque (the band centres of the two load
levels differ by 1.04 x the jaw torque at every spindle angle), about 16 mN m/rad.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from teleop.physics.base import Effect, ParamSpec, Signals, Step, register


def spring_force(x, k: float, c: float, x_ref: float):
    """Force [N] of the parallel spring at motor position x [m] (array or scalar): k dx (1 + c dx)."""
    dx = np.asarray(x, dtype=float) - x_ref
    return k * dx * (1.0 + c * dx)


def _simulate(signals: Signals, p: Mapping[str, float]) -> np.ndarray:
    return signals.load + spring_force(signals.x, p["k"], p.get("c", 0.0), p["x_ref"])


def _guess(signals: Signals, y: np.ndarray) -> dict:
    # what the load leaves, least squares in dx and dx^2 about the mean position
    x_ref = float(np.mean(signals.x))
    dx = signals.x - x_ref
    A = np.column_stack([dx, dx * dx, np.ones_like(dx)])
    (a, b, _), *_ = np.linalg.lstsq(A, y - signals.load, rcond=None)
    k = float(a) if a > 0 else PARAMS[0].default
    c = float(np.clip(b / k, PARAMS[1].lower, PARAMS[1].upper)) if a > 0 else 0.0
    return {"k": k, "c": c, "x_ref": x_ref}


PARAMS = (ParamSpec("k", "N/m", 1e-6, 1e9, 100.0, "stiffness at x_ref (N m/rad on a rotary drive)",
                    log=True, positive=True),
          ParamSpec("c", "1/m", -1e4, 1e4, 0.0, "relative change of stiffness per unit travel (general form; "
                    "0: a linear spring)", shape=True),
          ParamSpec("x_ref", "m", -1e6, 1e6, 0.0, "position where the spring's force is counted from (fits hold "
                    "it at the record's mean drive position; the offset takes the force there)"))


class SpringStep(Step):
    """Per-sample parallel_spring: step(x, load) -> motor force [N]."""

    effect_name = "parallel_spring"

    def reset(self) -> None:
        pass

    def step(self, x: float, load: float) -> float:
        p = self.params
        return float(load + spring_force(x, p["k"], p.get("c", 0.0), p["x_ref"]))


PARALLEL_SPRING = register(Effect(
    name="parallel_spring",
    link="force",
    doc="conservative, position-dependent: load + k dx (1 + c dx), dx = x - x_ref",
    params=PARAMS,
    inputs=("x", "load"),
    output="load",
    simulate=_simulate,
    guess=_guess,
    step_class=SpringStep,
))
