"""The per-tick estimation kernels: cable geometry -> compensation -> f = -A t (eq 8) -> turn correction ->
steady-state Kalman, one compiled call per tick, one kernel per estimator (each differs only in its
compensation step; everything else is the shared kernels of teleop.core.kernels.geometry / friction / kalman).

Arrays (all float64), held by estimation.tick.TickComputer:
    pose (6,) [m, rad]; t_in (6,) sensor tensions [N]; dt [s]
    cab (n, 12): r_i (0:3), B_i (3:6) [m] and the orientation cache (R r_i - B_i, R r_i) (6:12)
    c (N_CONST,): constants, the sheath's first (teleop.core.kernels.sheath: mu, theta0, stick k [N/m]),
        then those named below (v the base-plane normal, the length dead band [m], and the `dynamic`
        friction parameters b [N s/m], Dahl Fc [N] and sigma [N/m], v_smooth [s])
    st (N_ROWS, n): per-cable state rows, the sheath's first (its motor position x = -length [m], NaN: none
        yet, and friction state phi), then direction, extreme, velocity [m/s], Dahl force [N], and the
        cached orientation (a, b, g, valid)
    kf (5, 6): Kalman filter array (teleop.core.kernels.kalman), (5, 0) for none
    turn (k, 6): per fitted axis [axis, duration [s], dead band [m], direction, extreme [m], tau [s]]
    coefs (k, 2, 6, deg+1): forward / backward power-series coefficients in s = tau / duration
    out (3, n): lengths [m], wrench [N, N m] (first 6) and compensated tip-side tensions [N] of this tick
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels import sheath as SH
from teleop.core.kernels.friction import dahl_step, direction_step
from teleop.core.kernels.geometry import cable, platform_offsets, wrap_angle
from teleop.core.kernels.jit import njit, structure
from teleop.core.kernels.kalman import kalman_update
from teleop.core.kernels.linalg import horner

VX, VY, VZ, DEADBAND, B_VISC, DAHL_FC, DAHL_SIGMA, V_SMOOTH, N_CONST = range(SH.N_CONST, SH.N_CONST + 9)
DIR, EXT, VEL, F_DAHL, ORIENT, N_ROWS = range(SH.N_STATE, SH.N_STATE + 6)


@njit
def _orient(pose, cab, st):
    """Refresh the orientation cache when the orientation changed (the loop holds it: R is built once)."""
    a, b, g = pose[3], pose[4], pose[5]
    if not (st[ORIENT, 3] == 1.0 and st[ORIENT, 0] == a and st[ORIENT, 1] == b and st[ORIENT, 2] == g):
        platform_offsets(a, b, g, cab[:, 0:3], cab[:, 3:6], cab[:, 6:12])
        st[ORIENT, 0], st[ORIENT, 1], st[ORIENT, 2], st[ORIENT, 3] = a, b, g, 1.0


@njit
def _add_cable(w, t, ux, uy, uz, qx, qy, qz):
    """w += -A_i t: f = -A t (eq 8), column i of A is [-u; -(R r_i) x u]."""
    w[0] += t * ux
    w[1] += t * uy
    w[2] += t * uz
    w[3] += t * (qy * uz - qz * uy)
    w[4] += t * (qz * ux - qx * uz)
    w[5] += t * (qx * uy - qy * ux)


@njit
def turn_correct(w, x, y, z, dt, turn, coefs):
    """Subtract the step-3 turn corrections (estimation.turn) from w in place; turn/coefs as above."""
    for k in range(turn.shape[0]):
        ax = int(turn[k, 0])
        p = x if ax == 0 else (y if ax == 1 else z)
        d, e, flipped = direction_step(turn[k, 3], turn[k, 4], p, turn[k, 2])
        tau = 0.0 if flipped else turn[k, 5] + dt
        turn[k, 3], turn[k, 4], turn[k, 5] = d, e, tau
        dur = turn[k, 1]
        if d != 0.0 and 0.0 <= tau < dur:
            s = tau / dur
            cf = coefs[k, 0 if d > 0.0 else 1]
            for j in range(w.shape[0]):
                w[j] -= horner(cf[j], s)


@njit
def _start(pose, cab, st, out):
    """Orientation cache, wrench zeroed: the common start of a tick."""
    _orient(pose, cab, st)
    out[1, :6] = 0.0


@njit
def _cable(pose, cab, c, out, i):
    """Cable i at the pose: its length stored in out[0, i]; (L, ux, uy, uz, its wrap Theta [rad])."""
    L, ux, uy, uz = cable(pose[0], pose[1], pose[2], cab[:, 6:12], i)
    out[0, i] = L
    return L, ux, uy, uz, wrap_angle(ux, uy, uz, c[VX], c[VY], c[VZ], c[SH.THETA0])


@njit
def _put(out, cab, i, t, ux, uy, uz):
    """Cable i's compensated tension t [N] into out[2, i] and its share of f = -A t into the wrench."""
    out[2, i] = t
    _add_cable(out[1, :6], t, ux, uy, uz, cab[i, 9], cab[i, 10], cab[i, 11])


@njit
def _finish(pose, dt, st, kf, turn, coefs, out):
    """Motor positions kept; turn correction and Kalman filter on the wrench: the common end of a tick."""
    for i in range(st.shape[1]):
        st[SH.X, i] = -out[0, i]
    w = out[1, :6]
    if turn.shape[0] > 0:
        turn_correct(w, pose[0], pose[1], pose[2], dt, turn, coefs)
    if kf.shape[1] > 0:
        kalman_update(kf, w)


@njit
def estimate_non_compensated(pose, t_in, dt, cab, c, st, kf, turn, coefs, out):
    """f = -A t_fsr: no compensation."""
    _start(pose, cab, st, out)
    for i in range(st.shape[1]):
        _, ux, uy, uz, _ = _cable(pose, cab, c, out, i)
        _put(out, cab, i, t_in[i], ux, uy, uz)
    _finish(pose, dt, st, kf, turn, coefs, out)


@njit
def estimate_capstan(pose, t_in, dt, cab, c, st, kf, turn, coefs, out):
    """`single` (and `double` with turn fits): capstan compensation per cable with the direction of the
    cable length change (Schmitt trigger with the length dead band; shortening or unmoved = pulling)."""
    _start(pose, cab, st, out)
    for i in range(st.shape[1]):
        L, ux, uy, uz, theta = _cable(pose, cab, c, out, i)
        d, e, _ = direction_step(st[DIR, i], st[EXT, i], L, c[DEADBAND])
        st[DIR, i], st[EXT, i] = d, e
        _put(out, cab, i, SH.hold_tension(t_in[i], d <= 0.0, theta, c), ux, uy, uz)
    _finish(pose, dt, st, kf, turn, coefs, out)


@njit
def estimate_dynamic(pose, t_in, dt, cab, c, st, kf, turn, coefs, out):
    """`dynamic`: per cable, the viscous force b v (v: the motor velocity, low-passed with v_smooth) and the
    Dahl state along the cable's own travel are removed, then the sheath's law is inverted through its
    friction state (sheath.tip_tension); no direction rule: the state follows the travel."""
    _start(pose, cab, st, out)
    first = st[SH.X, 0] != st[SH.X, 0]
    Fc, sigma = c[DAHL_FC], c[DAHL_SIGMA]
    dahl = Fc > 0.0 and not first
    a_v = dt / (c[V_SMOOTH] + dt) if dt > 0 else 0.0
    inv_dt = 1.0 / dt if dt > 0 else 0.0
    for i in range(st.shape[1]):
        L, ux, uy, uz, theta = _cable(pose, cab, c, out, i)
        dx = 0.0 if first else -L - st[SH.X, i]  # motor travel, + while pulling
        v = st[VEL, i]
        v += a_v * (dx * inv_dt - v)
        st[VEL, i] = v
        t = t_in[i] - c[B_VISC] * v  # viscous friction b v
        if dahl:
            Fd = dahl_step(st[F_DAHL, i], dx, sigma, Fc)
            st[F_DAHL, i] = Fd
            t -= Fd
        _put(out, cab, i, SH.tip_tension(st, i, dx, t, theta, c), ux, uy, uz)
    _finish(pose, dt, st, kf, turn, coefs, out)


@njit
def direction_update(d, e, flipped, values, deadband):
    """direction_step for every channel of `values` (n,): d, e (n,) state, flipped (n,) bool output."""
    for i in range(values.shape[0]):
        d[i], e[i], flipped[i] = direction_step(d[i], e[i], values[i], deadband)


@njit
def counts_tensions(counts, st, deadband, table, out):
    """FSR tensions [N] (out (n,)) from raw counts (n,): the Schmitt trigger on the counts (st (2, n):
    direction, extreme) picks the branch (falling: unloading, row 1 of `table`; else loading, row 0), and
    an integer count in the table's range looks its tension up. Other counts are left NaN for the caller's
    per-float conversion; returns how many."""
    missing = 0
    n_tab = table.shape[1]
    for i in range(counts.shape[0]):
        v = counts[i]
        d, e, _ = direction_step(st[0, i], st[1, i], v, deadband)
        st[0, i], st[1, i] = d, e
        if 0.0 <= v < n_tab and v == math.floor(v):
            out[i] = table[1 if d < 0.0 else 0, int(v)]
        else:
            out[i] = np.nan
            missing += 1
    return missing


@njit
def counts_dynamic(counts, fsr, deadband, table, t, pose, dt, cab, c, st, kf, turn, coefs, out):
    """One tick of the `dynamic` estimator (the loop's) from raw FSR counts in one compiled call: counts_tensions
    (counts, its state fsr, dead band, table -> t), then estimate_dynamic (one call instead of two: every
    kernel call pays for its argument handling). Counts may be int64 (a
    robot's ADC) or float64. Returns counts_tensions' count of tensions left NaN (then nothing is estimated: the
    caller converts those counts and calls estimate_dynamic itself)."""
    missing = counts_tensions(counts, fsr, deadband, table, t)
    if missing == 0:
        estimate_dynamic(pose, t, dt, cab, c, st, kf, turn, coefs, out)
    return missing


#: counts_dynamic's arguments but the counts, the pose and dt, by name: the estimator's state, tables and buffers
DYNAMIC_FIXED = ("fsr", "deadband", "table", "t", "cab", "c", "state", "kf", "turn", "coefs", "out")  # state: st
# counts_dynamic's fixed arguments held together (jit.structure; the type bound here for numba's cache)
FixedDynamic = structure(__name__, "FixedDynamic", DYNAMIC_FIXED)
FixedDynamicType = getattr(FixedDynamic, "numba_type", None)


@njit
def fixed_dynamic(fsr, deadband, table, t, cab, c, st, kf, turn, coefs, out):
    """A FixedDynamic holding counts_dynamic's arguments but the counts, the pose and dt (the same arrays, not
    copies), for counts_dynamic_fixed; built by a compiled (cached) call."""
    return FixedDynamic(fsr, deadband, table, t, cab, c, st, kf, turn, coefs, out)


@njit
def counts_dynamic_fixed(counts, a, pose, dt):
    """counts_dynamic of the counts, the pose and dt with its other arguments in `a` (fixed_dynamic): four
    arguments for fourteen (a kernel call unboxes each array argument; the loop estimates every robot frame)."""
    return counts_dynamic(counts, a.fsr, a.deadband, a.table, a.t, pose, dt, a.cab, a.c, a.state, a.kf, a.turn,
                          a.coefs, a.out)
