"""Compiled kernels of the FSR alone (scenes.fsr_sensor): the loading branch, the Prandtl-Ishlinskii plays on ln G
and, for the simulated robot, the divider and ADC. The one home of the sensor's hysteresis formula
(scenes.fsr_sensor's module docstring); FsrSensor and scenes.sim_robot call them."""

from __future__ import annotations

import math

from teleop.core.kernels.jit import njit
from teleop.core.kernels.sensor import adc_round, conductance2counts, loading_conductance

G_FLOOR = 1e-12  # [S] the smallest conductance whose log is taken (an unloaded FSR)


@njit
def _log_g(c, t):
    """ln G [ln S] on the loading branch (coefficients c, lowest first) at tension t [N] (below 0: 0)."""
    return math.log(max(loading_conductance(c, max(t, 0.0)), G_FLOOR))


@njit
def _plays(x, y, w, j):
    """Step the plays y[:, j] (widths w) to input x; returns their mean (the sensor's ln G)."""
    k = y.shape[0]
    s = 0.0
    for i in range(k):
        v = min(max(y[i, j], x), x + w[i])
        y[i, j] = v
        s += v
    return s / k


@njit
def log_conductance_rows(T, c, y, w, first, out):
    """out (m, n) = ln G [ln S] the sensors read for tensions T (m, n) [N]: the loading branch, then the plays
    y (k, n) (written in place; `first`: set to the first row's input, the loading branch)."""
    for row in range(T.shape[0]):
        for j in range(T.shape[1]):
            x = _log_g(c, T[row, j])
            if first and row == 0:
                for i in range(y.shape[0]):
                    y[i, j] = x
            out[row, j] = _plays(x, y, w, j)


@njit
def counts_row(t, c, y, w, first, r_divider, adc_max, noise, counts):
    """counts (n,) int64 = adc_round(conductance2counts(exp(ln G)) + noise) for one row of tensions t (n,) [N], ln G
    the loading branch then the plays y (k, n) (written in place; `first`: set to this row's input), noise (n,)
    [counts]. The row of counts_rows; the simulated robot's fused reading (scenes.sim_robot_kernels) calls it."""
    for j in range(t.shape[0]):
        x = _log_g(c, t[j])
        if first:
            for i in range(y.shape[0]):
                y[i, j] = x
        g = math.exp(_plays(x, y, w, j))
        counts[j] = int(adc_round(conductance2counts(g, r_divider, adc_max) + noise[j], adc_max))


@njit
def counts_rows(T, c, y, w, first, r_divider, adc_max, noise, counts):
    """counts (m, n) int64 = adc_round(conductance2counts(exp(ln G)) + noise) for tensions T (m, n) [N], ln G as
    log_conductance_rows (y written in place), noise (m, n) [counts]: counts_row row by row."""
    for row in range(T.shape[0]):
        counts_row(T[row], c, y, w, first and row == 0, r_divider, adc_max, noise[row], counts[row])
