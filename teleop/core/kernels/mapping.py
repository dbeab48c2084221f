"""Kernels of the mapping (teleop.core.mapping): stylus -> robot target -> cable lengths, the one definition.

- `target_position`: anchor_robot + s R_reg (p - anchor_stylus), clamped to the workspace box.
- `clip_lengths`: lengths clipped to [l_min, l_max], and their largest step.
- `limit_step`: the step from the previous lengths scaled so no cable moves more than dmax, then clipped.
- `follow_step`: one tick of the loop's mapping, from these three.

c (19,): s R_reg (9, rows), workspace min (3,) and max (3,) [m], dmax = v_max dt [m], dmax_hard [m],
l_min, l_max [m]; off (n, 6): geometry.platform_offsets at the held orientation [m] (lengths = |p + off_i|).
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.geometry import lengths_at
from teleop.core.kernels.jit import njit

DMAX, DMAX_HARD, L_MIN, L_MAX = 15, 16, 17, 18


@njit
def target_position(p, anchor, c):
    """(x, y, z) [m]: anchor_robot + s R_reg (p - anchor_stylus) clamped to the workspace box. p (3,) stylus
    position [m]; anchor (6,): stylus anchor and robot anchor [m]; c: the constants (module docstring)."""
    dx, dy, dz = p[0] - anchor[0], p[1] - anchor[1], p[2] - anchor[2]
    x = anchor[3] + (c[0] * dx + c[1] * dy + c[2] * dz)
    y = anchor[4] + (c[3] * dx + c[4] * dy + c[5] * dz)
    z = anchor[5] + (c[6] * dx + c[7] * dy + c[8] * dz)
    x = c[12] if x > c[12] else (c[9] if x < c[9] else x)
    y = c[13] if y > c[13] else (c[10] if y < c[10] else y)
    z = c[14] if z > c[14] else (c[11] if z < c[11] else z)
    return x, y, z


@njit
def clip_lengths(Ln, L, l_min, l_max):
    """Ln (n,) [m] clipped into [l_min, l_max] in place; returns the largest |Ln_i - L_i| after clipping [m]."""
    step = 0.0
    for i in range(Ln.shape[0]):
        Ln[i] = l_max if Ln[i] > l_max else (l_min if Ln[i] < l_min else Ln[i])
        step = max(step, abs(Ln[i] - L[i]))
    return step


@njit
def limit_step(L, Ln, dmax, l_min, l_max):
    """Ln (n,) [m], in place: L + (Ln - L) f clipped into [l_min, l_max], f = dmax / max|Ln - L| when that
    step exceeds dmax [m] (the cables keep moving together), else 1."""
    step = 0.0
    for i in range(Ln.shape[0]):
        step = max(step, abs(Ln[i] - L[i]))
    f = dmax / step if step > dmax else 1.0
    for i in range(Ln.shape[0]):
        v = L[i] + (Ln[i] - L[i]) * f
        Ln[i] = l_max if v > l_max else (l_min if v < l_min else v)
    return Ln


@njit
def follow_step(p, anchor, c, off, pos, L):
    """One tick: target_position; if some cable would move more than dmax, the target moves along the
    straight line from the previous target only as far as that allows; lengths clipped to [l_min, l_max],
    and a (second-order) residue of the line step above dmax hard-limited (limit_step with dmax_hard).
    p (3,) stylus position [m]; anchor (6,): stylus anchor and robot anchor [m]; pos (3,) previous target,
    L (n,) previous lengths [m]: both updated."""
    x, y, z = target_position(p, anchor, c)
    dmax, l_min, l_max = c[DMAX], c[L_MIN], c[L_MAX]
    n = off.shape[0]
    Ln = np.empty(n)
    lengths_at(x, y, z, off, Ln)
    step = 0.0
    for i in range(n):  # the largest step before clipping
        step = max(step, abs(Ln[i] - L[i]))
    step_c = clip_lengths(Ln, L, l_min, l_max)
    if step > dmax:  # move along the straight line as far as the cable speed allows this tick
        f = dmax / step
        x, y, z = pos[0] + (x - pos[0]) * f, pos[1] + (y - pos[1]) * f, pos[2] + (z - pos[2]) * f
        lengths_at(x, y, z, off, Ln)
        step_c = clip_lengths(Ln, L, l_min, l_max)
    if step_c > dmax:  # second-order residue of the line step: the hard limit
        limit_step(L, Ln, c[DMAX_HARD], l_min, l_max)
    pos[0], pos[1], pos[2] = x, y, z
    for i in range(n):
        L[i] = Ln[i]
