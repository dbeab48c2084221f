"""Compiled reading of the simulated robot with the distributed tendon-sheath cable (scenes.sim_robot
SimRobot.read with DistributedCables): the reading's kernel up to the tip tensions (teleop.core.kernels.sim
reading_tips: contact wrench, motor steps, tip tensions; no lumped sheath), the cables' tick
(scenes.tendon_sheath_kernels.step: all cables and sub-steps, the sensor taps) and the FSRs' counts from the
tension at their tap (teleop.core.kernels.sensor.fsr_counts, or with the FSR alone scenes.fsr_sensor_kernels
.counts_row: reading_cables_fsr), one call a reading. It calls those kernels, so its
compiled code holds them: its cache is stamped with every kernel source (teleop.core.kernels.jit.OUTER_KERNELS).
The batch path (SimRobot.run) calls the same cable step (tendon_sheath_kernels.run).
"""

from __future__ import annotations

from scenes import tendon_sheath_kernels as TK
from scenes.fsr_sensor_kernels import counts_row
from teleop.core.kernels.jit import njit, structure
from teleop.core.kernels.sensor import fsr_counts
from teleop.core.kernels.sim import reading_tips
from teleop.core.kernels.tension import OK


@njit
def reading_cables(o, F, A, theta, L_home, L, c, f, t_tip, steps, Lc, S, cab, p, T, out, tap, u, grid, gap, coefs,
                   r_divider, adc_max, noise, i, counts):
    """One reading, one call: `reading_tips` (the wrench f (6,), the motor steps (n,), the tip tensions t_tip
    (n,) [N] of the commanded lengths L and the contact force F at tool offset o), then, when it is OK, the
    cables' tick (tendon_sheath_kernels.step: motor input the cable lengths Lc (n,) [m], tip input t_tip,
    kinematic input the wraps theta; state S, cab, parameters p, element tensions T, the tick's output out) and
    the FSRs' counts (n,) int64 of the tension at output row `tap` (fsr_counts with the branch lag's state u and
    constants, ADC noise row i of noise (m, n) [counts]). Returns reading_tips' status (when not OK only f and
    steps are written: the caller decides the tensions)."""
    status = reading_tips(o, F, A, L_home, L, c, f, t_tip, steps)
    if status == OK:
        TK.step(S, cab, p, Lc, t_tip, theta, T, out)
        fsr_counts(out[tap], u, grid, gap, coefs, r_divider, adc_max, noise[i], counts)
    return status


@njit
def reading_cables_fsr(o, A, theta, L_home, c, S, cab, p, T, tap, fc, y, w, fresh, r_divider, adc_max, F, L, Lc, noise,
                       i, f, t_tip, steps, out, counts):
    """reading_cables with the FSR alone (scenes.fsr_sensor.FsrSensor.kernel_args: loading coefficients fc, plays
    y (k, n) written in place, widths w, fresh (1,) bool: set the plays at this reading, then cleared; divider and
    ADC): when OK the counts (n,) int64 of the tension at output row `tap` with ADC noise row i of noise (m, n)
    [counts] (fsr_sensor_kernels.counts_row). The arguments that stay the same objects reading after reading
    come first (the caller builds them once), those of the reading after F. Returns reading_tips' status (when
    not OK only f and steps are written and the sensor's state is untouched)."""
    status = reading_tips(o, F, A, L_home, L, c, f, t_tip, steps)
    if status == OK:
        TK.step(S, cab, p, Lc, t_tip, theta, T, out)
        counts_row(out[tap], fc, y, w, fresh[0], r_divider, adc_max, noise[i], counts)
        fresh[0] = False
    return status


#: reading_cables_fsr's arguments that stay the same objects reading after reading (its first 16), by name
FIXED_FSR = ("o", "A", "theta", "L_home", "c", "S", "cab", "p", "T", "tap", "fc", "y", "w", "fresh", "r_divider",
             "adc_max")

# reading_cables_fsr's fixed arguments held together (jit.structure; the type bound here for numba's cache)
FixedFsr = structure(__name__, "FixedFsr", FIXED_FSR)
FixedFsrType = getattr(FixedFsr, "numba_type", None)


@njit
def fixed_fsr(o, A, theta, L_home, c, S, cab, p, T, tap, fc, y, w, fresh, r_divider, adc_max):
    """A FixedFsr holding reading_cables_fsr's fixed arguments (the same arrays, not copies), for
    reading_cables_fsr_fixed; built by a compiled (cached) call."""
    return FixedFsr(o, A, theta, L_home, c, S, cab, p, T, tap, fc, y, w, fresh, r_divider, adc_max)


@njit
def reading_cables_fsr_fixed(a, F, L, Lc, noise, i, f, t_tip, steps, out, counts):
    """reading_cables_fsr with its fixed arguments in `a` (fixed_fsr): one argument for sixteen (a kernel call
    unboxes each array argument, ~0.05 us each; the simulated robot's reading makes this call every tick)."""
    return reading_cables_fsr(a.o, a.A, a.theta, a.L_home, a.c, a.S, a.cab, a.p, a.T, a.tap, a.fc, a.y, a.w, a.fresh,
                              a.r_divider, a.adc_max, F, L, Lc, noise, i, f, t_tip, steps, out, counts)
