"""Kernels of the force rendering (teleop.core.rendering): frame map, engage rule, ramp-in, passivity, clamp.

The renderer's state lives in rs (5,) = [state, small_ticks, ramp, energy [J], fault]; state codes DISABLED,
WAITING, RAMPING, ENGAGED below. Its settings in rp (7,) = [max_force [N], scale, zero_negative_z (0/1),
engage_N [N], engage_ticks, ramp_s [s], alpha_max [N s/m]]; R (3, 3) the frame map R_dev_B.
"""

from __future__ import annotations

import math

from teleop.core.kernels.jit import njit

DISABLED, WAITING, RAMPING, ENGAGED = 0.0, 1.0, 2.0, 3.0
STATE, SMALL, RAMP, ENERGY, FAULT = range(5)
MAX_FORCE, SCALE, ZERO_NEG_Z, ENGAGE_N, ENGAGE_TICKS, RAMP_S, ALPHA_MAX = range(7)
TRIP_NONE, TRIP_FORCE, TRIP_VELOCITY = 0, 1, 2


@njit
def is_finite3(x, y, z):
    """True when all three numbers are finite."""
    return math.isfinite(x) and math.isfinite(y) and math.isfinite(z)


@njit
def frame_map(R, scale, x, y, z):
    """scale * R (x, y, z) with R (3, 3) (rows)."""
    return (scale * (R[0][0] * x + R[0][1] * y + R[0][2] * z),
            scale * (R[1][0] * x + R[1][1] * y + R[1][2] * z),
            scale * (R[2][0] * x + R[2][1] * y + R[2][2] * z))


@njit
def is_small(x, y, z, limit):
    """True when |(x, y, z)| < limit (the engage test); huge or non-finite components give False."""
    m = max(abs(x), abs(y), abs(z))  # m < limit first: no overflow in the squares
    return m < limit and math.sqrt(x * x + y * y + z * z) < limit


@njit
def engage_count(n, x, y, z, limit):
    """The engage rule (CHAI3D: 0.2 N for 3 ticks): consecutive ticks, this one included, whose force
    (x, y, z) [N] stayed below `limit`; force may engage once the count reaches the required ticks."""
    return n + 1 if is_small(x, y, z, limit) else 0


@njit
def clamp_norm(x, y, z, limit):
    """(x, y, z) scaled down to norm <= limit (direction kept); non-finite input gives (0, 0, 0)."""
    if x * 0.0 + y * 0.0 + z * 0.0 != 0.0:  # any nan/inf
        return 0.0, 0.0, 0.0
    m = max(abs(x), abs(y), abs(z))
    if m == 0.0:
        return 0.0, 0.0, 0.0
    n = m * math.sqrt((x / m) ** 2 + (y / m) ** 2 + (z / m) ** 2)  # no overflow for huge components
    if n <= limit:
        return x, y, z
    k = limit / n
    return x * k, y * k, z * k


@njit
def render_step(rs, rp, R, fx, fy, fz, dt, vx, vy, vz, out):
    """One tick of teleop.core.rendering.Renderer.render_xyz: out (6,) = stylus force (3,) [N] in the device frame
    and the mapped force (3,) before ramp, passivity and clamp. Returns a TRIP_* code (the force is zero and
    the fault latched when it is not TRIP_NONE)."""
    # finite * 0 == 0 exactly; inf * 0 and nan * 0 are nan: one test for all three, no overflow
    if fx * 0.0 + fy * 0.0 + fz * 0.0 != 0.0 or vx * 0.0 + vy * 0.0 + vz * 0.0 + dt * 0.0 != 0.0:
        for j in range(6):
            out[j] = 0.0
        rs[FAULT], rs[STATE] = 1.0, DISABLED
        return TRIP_FORCE if fx * 0.0 + fy * 0.0 + fz * 0.0 != 0.0 else TRIP_VELOCITY
    x, y, z = frame_map(R, rp[SCALE], fx, fy, fz)
    if rp[ZERO_NEG_Z] != 0.0 and z < 0.0:
        z = 0.0
    out[3], out[4], out[5] = x, y, z
    state = rs[STATE]
    if state == DISABLED or rs[FAULT] != 0.0:
        out[0], out[1], out[2] = 0.0, 0.0, 0.0
        return TRIP_NONE
    if state != ENGAGED:
        if state == WAITING:
            rs[SMALL] = engage_count(rs[SMALL], x, y, z, rp[ENGAGE_N])
            if rs[SMALL] < rp[ENGAGE_TICKS]:
                out[0], out[1], out[2] = 0.0, 0.0, 0.0
                return TRIP_NONE
            rs[STATE], rs[RAMP] = RAMPING, 0.0
        rs[RAMP] = min(1.0, rs[RAMP] + (dt / rp[RAMP_S] if rp[RAMP_S] > 0 else 1.0))
        if rs[RAMP] >= 1.0:
            rs[STATE] = ENGAGED
        x, y, z = x * rs[RAMP], y * rs[RAMP], z * rs[RAMP]
    limit = rp[MAX_FORCE]
    n2 = x * x + y * y + z * z
    if not n2 <= limit * limit:  # also catches an overflowed n2
        x, y, z = clamp_norm(x, y, z, limit)
    if rp[ALPHA_MAX] > 0.0 and dt > 0.0:
        v2 = vx * vx + vy * vy + vz * vz
        e_next = rs[ENERGY] - (x * vx + y * vy + z * vz) * dt
        if e_next < 0.0 and v2 > 0.0:
            # passivity controller: damper -alpha v that returns the observed energy to >= 0
            alpha = min(-e_next / (v2 * dt), rp[ALPHA_MAX])
            x, y, z = clamp_norm(x - alpha * vx, y - alpha * vy, z - alpha * vz, limit)
            if rp[ZERO_NEG_Z] != 0.0 and z < 0.0:  # the damper may not pull toward the pad either
                z = 0.0
            e_next = rs[ENERGY] - (x * vx + y * vy + z * vz) * dt
        rs[ENERGY] = e_next if e_next * 0.0 == 0.0 else 0.0
    out[0], out[1], out[2] = x, y, z
    return TRIP_NONE
