"""Kernel of the per-tick mapping (teleop.core.mapping.Follower): stylus -> robot target -> cable lengths.

c (19,): s R_reg (9, rows), workspace min (3,) and max (3,) [m], dmax = v_max dt [m], dmax_hard [m],
l_min, l_max [m]; off (n, 3): R r_i - B_i at the held orientation [m] (lengths = |p + off_i|).
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels.jit import njit

DMAX, DMAX_HARD, L_MIN, L_MAX = 15, 16, 17, 18


@njit
def position_lengths(x, y, z, off, out):
    """out (n,): cable lengths [m] at position (x, y, z) [m] for the held orientation's offsets."""
    for i in range(off.shape[0]):
        vx, vy, vz = off[i, 0] + x, off[i, 1] + y, off[i, 2] + z
        out[i] = math.sqrt(vx * vx + vy * vy + vz * vz)
    return out


@njit
def follow_step(p, anchor, c, off, pos, L):
    """One tick: target = anchor_robot + s R_reg (p - anchor_stylus) clamped to the workspace box; if some
    cable would move more than dmax, the target moves along the straight line from the previous target only
    as far as that allows; lengths clipped to [l_min, l_max], and a (second-order) residue of the line step
    above dmax hard-limited (teleop.core.mapping.limit_lengths). p (3,) stylus position [m]; anchor (6,): stylus
    anchor and robot anchor [m]; pos (3,) previous target, L (n,) previous lengths [m]: both updated."""
    dx, dy, dz = p[0] - anchor[0], p[1] - anchor[1], p[2] - anchor[2]
    x = anchor[3] + (c[0] * dx + c[1] * dy + c[2] * dz)
    y = anchor[4] + (c[3] * dx + c[4] * dy + c[5] * dz)
    z = anchor[5] + (c[6] * dx + c[7] * dy + c[8] * dz)
    x = c[12] if x > c[12] else (c[9] if x < c[9] else x)  # np.minimum(np.maximum(p, lo), hi)
    y = c[13] if y > c[13] else (c[10] if y < c[10] else y)
    z = c[14] if z > c[14] else (c[11] if z < c[11] else z)
    dmax, l_min, l_max = c[DMAX], c[L_MIN], c[L_MAX]
    n = off.shape[0]
    Ln = np.empty(n)
    position_lengths(x, y, z, off, Ln)
    step, step_c = 0.0, 0.0
    for i in range(n):  # the largest step, then the clipped lengths and their largest step
        step = max(step, abs(Ln[i] - L[i]))
        Ln[i] = l_max if Ln[i] > l_max else (l_min if Ln[i] < l_min else Ln[i])
        step_c = max(step_c, abs(Ln[i] - L[i]))
    if step > dmax:  # move along the straight line as far as the cable speed allows this tick
        f = dmax / step
        x, y, z = pos[0] + (x - pos[0]) * f, pos[1] + (y - pos[1]) * f, pos[2] + (z - pos[2]) * f
        position_lengths(x, y, z, off, Ln)
        step_c = 0.0
        for i in range(n):
            Ln[i] = l_max if Ln[i] > l_max else (l_min if Ln[i] < l_min else Ln[i])
            step_c = max(step_c, abs(Ln[i] - L[i]))
    if step_c > dmax:  # second-order residue of the line step: limit_lengths' hard limit
        f = c[DMAX_HARD] / step_c if step_c > c[DMAX_HARD] else 1.0
        for i in range(n):
            v = L[i] + (Ln[i] - L[i]) * f
            Ln[i] = l_max if v > l_max else (l_min if v < l_min else v)
    pos[0], pos[1], pos[2] = x, y, z
    for i in range(n):
        L[i] = Ln[i]
