"""Kernels of the loop's safety monitors (teleop.loop.safety: the monitors' rules live here, their messages
and state holders there). State arrays are float64; NaN stands for "no time yet" (the condition does not hold).

    all_finite        every element of an array finite (all_finite3: three arrays and a time)
    tension_range     over-range / slack tension persisting longer than a window (TensionRange)
    stuck_cable       a paying-out cable whose filtered tension keeps rising (StuckCable)
    tension_monitors  tension_range then stuck_cable, as the loop runs them each estimate (one call)
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels.jit import njit

TF, T0, TMIN, COUNT = range(4)  # rows of StuckCable's state (4, n)
T_PREV, HAS_TF = range(2)       # its scalar state (2,)


@njit
def all_finite(a):
    """True when every element of `a` (any shape; ints are always finite) is finite."""
    for v in a.ravel():
        if not np.isfinite(v):
            return False
    return True


@njit
def all_finite2(a, b):
    """all_finite of both arrays (the loop's estimated tensions and wrench in one call)."""
    return all_finite(a) and all_finite(b)


@njit
def all_finite3(a, b, c, t):
    """all_finite of the three arrays and the float t (a reading's or a sample's numbers in one call)."""
    return np.isfinite(t) and all_finite(a) and all_finite(b) and all_finite(c)


@njit
def tension_range(now, t, t_max, t_slack, window, since):
    """Update the start times since (2, n) [s] (row 0 over-range t > t_max, row 1 slack t < t_slack; NaN
    while the condition does not hold) with tensions t (n,) [N] at host time now [s]. Returns -1, or the
    first condition that has held longer than `window` [s]: row * n + cable (the rest is left as it was)."""
    n = t.shape[0]
    for row in range(2):
        for i in range(n):
            if (t[i] > t_max) if row == 0 else (t[i] < t_slack):
                if since[row, i] != since[row, i]:
                    since[row, i] = now
                elif now - since[row, i] > window:
                    return row * n + i
            else:
                since[row, i] = np.nan
    return -1


@njit
def stuck_cable(now, t, dL, st, sc, tau, eps, window, rise, confirm):
    """StuckCable's update with tensions t (n,) [N] and length steps dL (n,) [m] at host time now [s].

    st (4, n): low-passed tension tf (time constant tau [s]) [N], start of the pay-out streak t0 [s] (NaN:
    none), lowest tf of the streak [N], consecutive rises; sc (2,): previous update time [s], tf valid (1.0).
    A streak runs while dL > eps; once it has lasted `window` [s], tf more than `rise` [N] above its lowest,
    on `confirm` consecutive updates, is a stuck cable. Returns the first stuck cable's index, or -1."""
    n = t.shape[0]
    if sc[HAS_TF] != 1.0:
        for i in range(n):
            st[TF, i] = t[i]
        sc[HAS_TF] = 1.0
    else:  # tf += a (t - tf), a = 1 - exp(-dt / tau)
        a = 1.0 - math.exp(-max(now - sc[T_PREV], 0.0) / tau)
        for i in range(n):
            f = st[TF, i]
            st[TF, i] = f + a * (t[i] - f)
    sc[T_PREV] = now
    bad = -1
    for i in range(n):
        ti = st[TF, i]
        if not dL[i] > eps:  # not paying out: the streak ends
            st[T0, i] = np.nan
            st[COUNT, i] = 0.0
            continue
        if st[T0, i] != st[T0, i]:
            st[T0, i], st[TMIN, i] = now, ti
        elif ti < st[TMIN, i]:
            st[TMIN, i] = ti
        if now - st[T0, i] >= window and ti - st[TMIN, i] > rise:
            st[COUNT, i] += 1.0
            if st[COUNT, i] >= confirm and bad < 0:
                bad = i
        else:
            st[COUNT, i] = 0.0
    return bad


@njit
def tension_monitors(now, t, dL, check_range, since, t_max, t_slack, window_range, st, sc, tau, eps, window, rise,
                     confirm):
    """The loop's two tension monitors on one estimate, in one call: tension_range (when check_range) and, unless
    it tripped, stuck_cable (arguments as theirs; window_range the range's window [s]). Returns -1, a
    tension_range code (< 2 n), or 2 n + the stuck cable's index."""
    if check_range:
        k = tension_range(now, t, t_max, t_slack, window_range, since)
        if k >= 0:
            return k
    bad = stuck_cable(now, t, dL, st, sc, tau, eps, window, rise, confirm)
    return -1 if bad < 0 else 2 * t.shape[0] + bad
