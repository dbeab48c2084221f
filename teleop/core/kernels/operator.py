"""Kernels of the simulated operator (devices.simulated): the scripted hand target and the hand + stylus mass
integrated with semi-implicit Euler,

    m a = k (p_target(t) - p) - b v + F_cmd + F_tremor(t)

(the hand off: the stylus alone, (F_cmd - 20 v) / 0.05), the tremor an Ornstein-Uhlenbeck force.

    script_offset     the target's displacement along the script axis [m] at time t [s] (hold, sine, pokes)
    operator_steps    n integration steps, then the workspace clip (one compiled call per stylus read)
"""

from __future__ import annotations

import math

from teleop.core.kernels.jit import njit

HOLD, SINE, POKES, RECORDED = range(4)  # script kinds (devices.simulated.SCRIPTS order)
# operator_steps' constants c (21,): step, mass, stiffness, damping, OU factor exp(-h / 0.05), OU scale [N],
# the script (kind, amplitude [m], period [s], duty, centre (3,) [m], axis (3,)), workspace lo (3,), hi (3,) [m]
H, M, K, B, A_OU, S_OU, KIND, AMP, PERIOD, DUTY, CENTER, AXIS, LO, HI = 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 13, 16, 19
N_CONST = 22


@njit
def script_offset(kind, t, amplitude, period, duty):
    """Displacement [m] of the hand target along the script axis at time t [s]: 0 (hold), a sine of
    `amplitude` and `period`, or pokes (a raised-cosine press of depth `amplitude` during the first `duty`
    fraction of each `period`)."""
    if kind == SINE:
        return amplitude * math.sin(2 * math.pi * t / period)
    if kind == POKES:
        phase = (t / period) % 1.0
        return amplitude * (0.5 - 0.5 * math.cos(2 * math.pi * phase / duty)) if phase < duty else 0.0
    return 0.0


@njit
def operator_steps(x, fx, fy, fz, step0, n, c, noise, i0, tremor, targets, absent):
    """Advance the operator n steps of c[H] from step `step0` (step j ends at time (j + 1) h).

    x (9,): position p (3,) [m], velocity v (3,) [m/s], tremor force r (3,) [N], updated in place; fx, fy, fz:
    the commanded stylus force [N] (three floats: no array to fill per read); noise (k, 3): standard normal draws, rows i0 .. i0 + n - 1 used when
    `tremor`; targets (n, 3): the hand targets [m] for a recorded script (else unused); absent (a, 2): the
    [t0, t1) intervals [s] with the hand off. After the steps p is clipped to the workspace [lo, hi] and v
    zeroed along the clipped axes."""
    h, m, k, b, a_ou, s_ou = c[H], c[M], c[K], c[B], c[A_OU], c[S_OU]
    kind = int(c[KIND])
    px, py, pz, vx, vy, vz, rx, ry, rz = x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8]
    for i in range(n):
        t = (step0 + i + 1) * h
        if tremor:
            j = i0 + i
            rx, ry, rz = (a_ou * rx + s_ou * noise[j, 0], a_ou * ry + s_ou * noise[j, 1],
                          a_ou * rz + s_ou * noise[j, 2])
        off = False
        for q in range(absent.shape[0]):
            if absent[q, 0] <= t < absent[q, 1]:
                off = True
                break
        if not off:
            if kind == RECORDED:
                tx, ty, tz = targets[i, 0], targets[i, 1], targets[i, 2]
            else:
                s = script_offset(kind, t, c[AMP], c[PERIOD], c[DUTY])
                tx, ty, tz = c[CENTER] + c[AXIS] * s, c[CENTER + 1] + c[AXIS + 1] * s, c[CENTER + 2] + c[AXIS + 2] * s
            ax = (k * (tx - px) - b * vx + fx + rx) / m
            ay = (k * (ty - py) - b * vy + fy + ry) / m
            az = (k * (tz - pz) - b * vz + fz + rz) / m
        else:  # hand off: the stylus alone (light, heavily damped by the device's friction)
            ax, ay, az = (fx - 20.0 * vx) / 0.05, (fy - 20.0 * vy) / 0.05, (fz - 20.0 * vz) / 0.05
        vx, vy, vz = vx + h * ax, vy + h * ay, vz + h * az
        px, py, pz = px + h * vx, py + h * vy, pz + h * vz
    x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8] = px, py, pz, vx, vy, vz, rx, ry, rz
    for a in range(3):
        p, lo, hi = x[a], c[LO + a], c[HI + a]
        q = lo if p < lo else p  # np.minimum(np.maximum(p, lo), hi), NaN kept
        q = hi if q > hi else q
        if q != p:
            x[a], x[3 + a] = q, 0.0
