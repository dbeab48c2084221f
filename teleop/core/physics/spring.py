"""A spring beside the transmission: the motor carries a position-dependent force the tip sensor never sees.

motor force = load + k dx + g dx^2 / 2, dx = x - x_ref, with x the motor position [m; rad on a rotary drive],
k the stiffness at x_ref [N/m; N m/rad] and g its gradient along the travel [N/m^2; N m/rad^2] (the general
form; 0 is a linear spring): the local stiffness is k + g dx. Both are signed: a force that falls as the drive
advances (k < 0: gravity on a rotary joint past its horizontal pose, an over-centre element) is as much a
force of the position as a spring. The force is conservative: the same in both directions of motion, a
function of where the drive is, not of where it has been. g is the half of the shape that no baseline gain
can take: wherever the load follows the drive position, the gain absorbs k and the curvature remains, and g
is the same about any reference position (k is not: it is the stiffness at x_ref).

Where it comes from: anything elastic that the drive deforms in parallel with the cable path to the tip
sensor: a return spring, the other cable pairs of a wrist that the drive's pulley stretches, a flexure or a
cable harness between the drive and the frame. On the MRDLab da Vinci instrument the spindle's torque carries
the same restoring torque over the stroke at 10 % and 40 % reaction torque (the band centres of the two load
levels differ by the jaw torque difference at every spindle angle); at 40 %, where the jaw torque follows
the angle and the gain takes the linear part, its curvature shows, and it grows with the load, which a
spring's would not (docs/diagnosis.md).
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.effects import parallel_spring_run, parallel_spring_step
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, kernel_call, register

KERNEL = Kernel(parallel_spring_step, parallel_spring_run, state=())


def spring_force(x, k: float, g: float, x_ref: float):
    """Force [N] of the parallel spring at motor position x [m] (array or scalar): k dx + g dx^2 / 2
    (the step kernel on a zero load)."""
    return kernel_call(KERNEL, (k, g, x_ref), x, 0.0)


def _guess(signals: Signals, y: np.ndarray) -> dict:
    # what the load leaves, least squares in dx and dx^2 about the mean position
    x_ref = float(np.mean(signals.x))
    dx = signals.x - x_ref
    A = np.column_stack([dx, dx * dx, np.ones_like(dx)])
    (a, b, _), *_ = np.linalg.lstsq(A, y - signals.load, rcond=None)
    return {"k": float(PARAMS[0].clip(a)), "g": float(PARAMS[1].clip(2.0 * b)), "x_ref": x_ref}


PARAMS = (ParamSpec("k", "N/m", -1e9, 1e9, 100.0, "stiffness at x_ref (N m/rad on a rotary drive; < 0: a force "
                    "that falls as the drive advances)", log=True, tiny=1e-6),
          ParamSpec("g", "N/m^2", -1e12, 1e12, 0.0, "change of stiffness per unit travel (N m/rad^2 on a rotary "
                    "drive; general form, 0: a linear spring)", log=True, tiny=1e-6, shape=True),
          ParamSpec("x_ref", "m", -1e6, 1e6, 0.0, "position where the spring's force is counted from (fits hold "
                    "it at the record's mean drive position; the offset takes the force there)"))


def _hold(rec, known, direction) -> dict:
    """Counted from the record's mean drive position."""
    return {"x_ref": direction * float(np.mean(rec.x))} if rec.x is not None else {}


PARALLEL_SPRING = register(Effect(
    name="parallel_spring",
    link="force",
    doc="conservative, position-dependent: load + k dx + g dx^2 / 2, dx = x - x_ref",
    params=PARAMS,
    inputs=("x", "load"),
    output="load",
    guess=_guess,
    kernel=KERNEL,
    rules=Rules(channel="motor_force", primary=("k",), position_only=True, hold=_hold),
))
