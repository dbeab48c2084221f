"""Kernels of the FSR's reading chain (teleop.core.sensors; the simulated robot's per-reading sensor side):

    branch_lag        the FSR hysteresis as play between its branches: u = clip(u_prev, t, t + G(t))
                      (teleop.core.sensors.FsrBranchLag; G tabulated on a grid, linear interpolation as np.interp:
                      linalg.interp1)
    loading_conductance   the loading branch's conductance [S]: max(sum_j c_j u^j, 0)
    conductance2counts    the divider and ADC: adc_max G R / (1 + G R) [counts, unrounded]
    counts2conductance    its inverse: G = c / ((adc_max - c) R), c clipped to [0, adc_max - 0.5]
    adc_round         rounded, clipped counts: clip(rint(c), 0, adc_max)
    polynomial_loop, conductance_loop, adc_round_loop   element-wise forms (FsrCalibration, the simulated robot)
    fsr_counts        one reading of n FSRs: tensions at the FSRs -> lag -> conductance -> counts + noise
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.friction import clamp
from teleop.core.kernels.jit import njit
from teleop.core.kernels.linalg import horner, interp1


@njit
def branch_lag(u, t, grid, gap):
    """Equivalent tension [N] after tension t [N] from u [N]: clip(u, t, t + G(t)), G the branch gap
    tabulated at `grid` [N] (gap (k,) [N], >= 0, linear interpolation, constant beyond the ends)."""
    return clamp(u, t, t + interp1(t, grid, gap))


@njit
def loading_conductance(c, u):
    """An FSR's loading-branch conductance [S] at equivalent tension u [N]: max(sum_j c_j u^j, 0), c the
    calibration's power-series coefficients (lowest first)."""
    return max(horner(c, u), 0.0)


@njit
def conductance2counts(g, r_divider, adc_max):
    """ADC counts (float, unrounded) for conductance g [S] through the divider r_divider [ohm]:
    adc_max G R / (1 + G R), G clipped at 0."""
    gr = max(g, 0.0) * r_divider
    return adc_max * gr / (1.0 + gr)


@njit
def counts2conductance(c, r_divider, adc_max):
    """Conductance [S] from ADC counts c through the divider r_divider [ohm]: G = c / ((adc_max - c) R), c
    clipped to [0, adc_max - 0.5] (the inverse of conductance2counts)."""
    top = adc_max - 0.5
    c = 0.0 if c < 0.0 else (top if c > top else c)
    return c / ((adc_max - c) * r_divider)


@njit
def adc_round(c, adc_max):
    """Counts c rounded half to even and clipped to [0, adc_max] (the ADC's integer reading, as a float)."""
    return min(max(np.rint(c), 0.0), adc_max)


@njit
def polynomial_loop(u, c, out):
    """out (m,) = sum_j c_j u_j^j (linalg.horner; numpy's polyval's order of operations) for u (m,)."""
    for k in range(u.shape[0]):
        out[k] = horner(c, u[k])
    return out


@njit
def conductance_loop(u, c, out):
    """out (m,): max(sum_j c_j u^j, 0) for equivalent tensions u (m,) [N]: an FSR branch's conductance [S]
    from the calibration's power-series coefficients c (loading_conductance element-wise)."""
    for k in range(u.shape[0]):
        out[k] = loading_conductance(c, u[k])
    return out


@njit
def adc_round_loop(c, adc_max, out):
    """adc_round element-wise (1-D arrays of one length, jit.broadcast_call)."""
    for k in range(out.shape[0]):
        out[k] = adc_round(c[k], adc_max[k])
    return out


@njit
def conductance2counts_loop(g, r_divider, adc_max, out):
    """conductance2counts element-wise (1-D arrays of one length, jit.broadcast_call)."""
    for k in range(g.shape[0]):
        out[k] = conductance2counts(g[k], r_divider[k], adc_max[k])
    return out


@njit
def counts2conductance_loop(c, r_divider, adc_max, out):
    """counts2conductance element-wise (1-D arrays of one length, jit.broadcast_call)."""
    for k in range(c.shape[0]):
        out[k] = counts2conductance(c[k], r_divider[k], adc_max[k])
    return out


@njit
def branch_lag_loop(u, T, grid, gap, out):
    """branch_lag along the rows of T (m, n) from u (n,) (updated in place to the last row; NaN: a cable's first
    reading, which starts on the loading branch, u = t): out (m, n)."""
    for i in range(T.shape[1]):
        ui = u[i]
        if ui != ui and T.shape[0] > 0:
            ui = T[0, i]
        for k in range(T.shape[0]):
            ui = branch_lag(ui, T[k, i], grid, gap)
            out[k, i] = ui
        u[i] = ui
    return out


@njit
def fsr_counts(t_fsr, u, grid, gap, c, r_divider, adc_max, noise, counts):
    """One reading of n FSRs: equivalent tensions u (n,) [N] after the tensions t_fsr (n,) [N] at the FSRs
    (u = t_fsr where u is NaN, a first reading: the loading branch), then counts (n,) int64 =
    adc_round(conductance2counts(loading_conductance(u)) + noise) with noise (n,) [counts]. Returns nothing
    (a returned array would be boxed again on every call)."""
    for i in range(t_fsr.shape[0]):
        ui = t_fsr[i] if u[i] != u[i] else branch_lag(u[i], t_fsr[i], grid, gap)
        u[i] = ui
        k = conductance2counts(loading_conductance(c, ui), r_divider, adc_max) + noise[i]
        counts[i] = int(adc_round(k, adc_max))


# ---------------------------------------------------------------------------------------------------------
# FBG kinds (seed 001; teleop.core.sensors, teleop.core.estimation.sensor_reading)
# ---------------------------------------------------------------------------------------------------------

@njit
def fbg_force(dl1, dl2, r, S):
    """Force [N] of a dual-FBG sensor from the Bragg shifts of FBG1 (temperature) and FBG2 (force and
    temperature) [pm]: (dl2 - r dl1) / S (seed 001 eq 3), r the temperature ratio, S [pm/N]."""
    return (dl2 - r * dl1) / S


@njit
def fbg_force_loop(dl1, dl2, r, S, out):
    """fbg_force element-wise (1-D arrays of one length, jit.broadcast_call)."""
    for k in range(dl1.shape[0]):
        out[k] = fbg_force(dl1[k], dl2[k], r[k], S[k])
    return out


@njit
def eq7_step(fd, fp, Kp, Kr, bp, br):
    """Distal tension [N] after proximal tension fp [N] from the previous fd [N] (seed 001 eq 7): flat
    between the pulling line Kp fp + bp and the releasing line Kr fp + br, on whichever it is pushed to."""
    a = Kp * fp + bp
    b = Kr * fp + br
    return clamp(fd, a, b) if a <= b else clamp(fd, b, a)


@njit
def eq7_start(fp, Kp, Kr, bp, br):
    """Distal tension [N] of a first reading at proximal tension fp [N] (seed 001 eq 7): on the lower line."""
    return min(Kp * fp + bp, Kr * fp + br)


@njit
def eq7_run(fp, fd0, Kp, Kr, bp, br, out):
    """out (n,): eq7_step along the proximal tensions fp (n,) [N] from the distal tension fd0 [N] (NaN:
    eq7_start at fp[0])."""
    fd = fd0
    for k in range(fp.shape[0]):
        if fd != fd:
            fd = eq7_start(fp[k], Kp, Kr, bp, br)
        fd = eq7_step(fd, fp[k], Kp, Kr, bp, br)
        out[k] = fd
    return out


@njit
def fbg_row(dl, r, S, out):
    """out (n,) [N] = fbg_force of each column of dl (2, n) [pm] (NaN where a cable has no FBG)."""
    for i in range(dl.shape[1]):
        out[i] = fbg_force(dl[0, i], dl[1, i], r, S)


@njit
def one_sensor_row(fp, fd, Kp, Kr, bp, br, dl, cable, r, S, out):
    """One reading of the one-sensor kind: out (n,) [N] distal tensions = eq7_step of each cable's proximal
    tension fp (n,) [N] from its state fd (n,) (updated; NaN: start on the lower line), the instrumented
    `cable` its own FBG's fbg_force of dl (2, n) [pm]."""
    for i in range(fp.shape[0]):
        if fd[i] != fd[i]:
            fd[i] = eq7_start(fp[i], Kp, Kr, bp, br)
        else:
            fd[i] = eq7_step(fd[i], fp[i], Kp, Kr, bp, br)
        out[i] = fd[i]
    out[cable] = fbg_force(dl[0, cable], dl[1, cable], r, S)
