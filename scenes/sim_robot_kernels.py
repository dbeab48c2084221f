"""Compiled reading of the simulated robot with the distributed tendon-sheath cable (scenes.sim_robot
SimRobot.read with DistributedCables): the reading's kernel (teleop.core.kernels.sim.reading: contact wrench,
motor steps, tip tensions), the cables' tick (scenes.tendon_sheath_kernels.step: all cables and sub-steps, the
sensor taps) and the FSRs' counts from the tension at their tap (teleop.core.kernels.sensor.fsr_counts), one
call a reading. It calls those kernels, so its compiled code holds them: its cache is stamped with every kernel
source (teleop.core.kernels.jit.OUTER_KERNELS). The batch path (SimRobot.run) calls the same cable step
(tendon_sheath_kernels.run).
"""

from __future__ import annotations

from scenes import tendon_sheath_kernels as TK
from teleop.core.kernels.jit import njit
from teleop.core.kernels.sensor import fsr_counts
from teleop.core.kernels.sim import reading
from teleop.core.kernels.tension import OK


@njit
def reading_cables(o, F, A, theta, x, L_home, L, c, cap, f, t_tip, t_lumped, steps, Lc, S, cab, p, T, out, tap,
                   u, grid, gap, coefs, r_divider, adc_max, noise, i, counts):
    """One reading, one call: `reading` (the wrench f (6,), the motor steps (n,), the tip tensions t_tip (n,)
    [N] of the commanded lengths L and the contact force F at tool offset o; its lumped sheath's tensions go to
    t_lumped, unused), then, when it is OK, the cables' tick (tendon_sheath_kernels.step: motor input the
    cable lengths Lc (n,) [m], tip input t_tip, kinematic input the wraps theta; state S, cab, parameters p,
    element tensions T, the tick's output out) and the FSRs' counts (n,) int64 of the tension at output row
    `tap` (fsr_counts with the branch lag's state u and constants, ADC noise row i of noise (m, n) [counts]).
    Returns reading's status (when not OK only f and steps are written: the caller decides the tensions)."""
    status = reading(o, F, A, theta, x, L_home, L, c, cap, f, t_tip, t_lumped, steps)
    if status == OK:
        TK.step(S, cab, p, Lc, t_tip, theta, T, out)
        fsr_counts(out[tap], u, grid, gap, coefs, r_divider, adc_max, noise[i], counts)
    return status
