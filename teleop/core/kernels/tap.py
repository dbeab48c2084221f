"""Kernel of the recorder's tap (teleop.loop.tap.RowTap): one tick's numbers copied into the preallocated row
in one compiled call (instead of a numpy store per signal, whose overhead a 4 kHz tick cannot afford).
`sim_log_row` does the same for `teleop bench sim`'s trajectory log (instead of seven numpy row stores).

`o` holds the first column of each signal (indices below, from the session layout); blocks whose source is
absent this tick (no stylus sample, no command, no reading) keep their previous values, as before.
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.jit import njit, structure

# the signals' order in `o` (teleop.loop.tap.COLUMNS names them)
(TICK, T, STATE, LATENESS, TICK_US, STAGES, T_DEVICE, CP, CV, ORIENT, BUTTONS, PRESENT, COMMANDED, SETPOINT, JP, NEW,
 T_ROBOT, SEQ, FSR, STEPS, LENGTHS, STATUS, BOOT, WRENCH, TENSIONS, CF, FORCE_RAW, RAMP, SERVO_CF) = range(29)


@njit
def _put(row, o, w, c, a):
    """row[o[c]:o[c] + w[c]] = a; False (nothing written) when a is not w[c] long."""
    if a.shape[0] != w[c]:
        return False
    for i in range(a.shape[0]):
        row[o[c] + i] = a[i]
    return True


@njit
def tap_row(row, o, w, k, t, state, lateness_ns, tick_ns, stage_ns, has_sample, t_device, cp, cv, R, buttons, present,
            commanded, pose, L, has_reading, t_robot, seq, counts, steps, lengths, status, boot_id, has_wrench,
            wrench_truth, tensions, wrench, fx, fy, fz, ramp, F):
    """Fill `row` (times in [us] from [ns]; booleans as 0/1; the wrench truth NaN when the reading has none);
    w holds each signal's width. Returns -1, or the index of the first signal whose array has another length
    (the signals after it are not written)."""
    if stage_ns.shape[0] != w[STAGES]:
        return STAGES
    if R.shape[0] * R.shape[1] != w[ORIENT]:
        return ORIENT
    if pose.shape[0] < w[SETPOINT]:
        return SETPOINT
    row[o[TICK]] = k
    row[o[T]] = t
    row[o[STATE]] = state
    row[o[LATENESS]] = lateness_ns * 1e-3
    row[o[TICK_US]] = tick_ns * 1e-3
    for i in range(stage_ns.shape[0]):
        row[o[STAGES] + i] = stage_ns[i] * 1e-3
    if has_sample:
        row[o[T_DEVICE]] = t_device
        if not _put(row, o, w, CP, cp):
            return CP
        if not _put(row, o, w, CV, cv):
            return CV
        for i in range(R.shape[0]):
            for j in range(R.shape[1]):
                row[o[ORIENT] + i * R.shape[1] + j] = R[i, j]
        row[o[BUTTONS]] = buttons
        row[o[PRESENT]] = 1.0 if present else 0.0
    row[o[COMMANDED]] = 1.0 if commanded else 0.0
    for i in range(w[SETPOINT]):
        row[o[SETPOINT] + i] = pose[i]
    if commanded:
        if not _put(row, o, w, JP, L):
            return JP
    row[o[NEW]] = 1.0 if has_reading else 0.0
    if has_reading:
        row[o[T_ROBOT]] = t_robot
        row[o[SEQ]] = seq
        if not _put(row, o, w, FSR, counts):
            return FSR
        if not _put(row, o, w, STEPS, steps):
            return STEPS
        if not _put(row, o, w, LENGTHS, lengths):
            return LENGTHS
        row[o[STATUS]] = status
        row[o[BOOT]] = boot_id
        if has_wrench:
            if not _put(row, o, w, WRENCH, wrench_truth):
                return WRENCH
        else:
            for i in range(w[WRENCH]):
                row[o[WRENCH] + i] = np.nan
    if not _put(row, o, w, TENSIONS, tensions):
        return TENSIONS
    if not _put(row, o, w, CF, wrench):
        return CF
    row[o[FORCE_RAW]], row[o[FORCE_RAW] + 1], row[o[FORCE_RAW] + 2] = fx, fy, fz
    row[o[RAMP]] = ramp
    if not _put(row, o, w, SERVO_CF, F):
        return SERVO_CF
    return -1


@njit
def sim_log_row(k, tick_ns, stage_ns, sub0, sub1, sub2, sub3, ns_log, p, F, pF_log, j, L, counts, wrench, Lf_log,
                counts_log):
    """teleop bench sim's log of tick k, its timers [ns] and trajectory: ns_log[k] = (stage_ns (s,), sub0, sub1,
    sub2, sub3 (the robot's cumulative timers), tick_ns), pF_log[k] = (p (3,), F (3,)); when j >= 0 (a reading
    this tick, its row j): Lf_log[j] = (L (n,), -wrench[2] (the contact force along -z [N])), counts_log[j] =
    counts (n,). One array per kind and dtype: every array argument costs the call its type check."""
    s = stage_ns.shape[0]
    for i in range(s):
        ns_log[k, i] = stage_ns[i]
    ns_log[k, s], ns_log[k, s + 1], ns_log[k, s + 2], ns_log[k, s + 3], ns_log[k, s + 4] = sub0, sub1, sub2, sub3, \
        tick_ns
    for i in range(3):
        pF_log[k, i] = p[i]
        pF_log[k, 3 + i] = F[i]
    if j >= 0:
        n = L.shape[0]
        for i in range(n):
            Lf_log[j, i] = L[i]
            counts_log[j, i] = counts[i]
        Lf_log[j, n] = -wrench[2]


#: sim_log_row's arguments that stay the same arrays tick after tick, by name: the tick's stage timers, the logs
SIM_LOG_FIXED = ("stage_ns", "ns_log", "pF_log", "Lf_log", "counts_log")
# sim_log_row's fixed arguments held together (jit.structure; the type bound here for numba's cache)
SimLog = structure(__name__, "SimLog", SIM_LOG_FIXED)
SimLogType = getattr(SimLog, "numba_type", None)


@njit
def sim_log(stage_ns, ns_log, pF_log, Lf_log, counts_log):
    """A SimLog holding sim_log_row's fixed arguments (the same arrays, not copies), for sim_log_row_fixed; built by
    a compiled (cached) call."""
    return SimLog(stage_ns, ns_log, pF_log, Lf_log, counts_log)


@njit
def sim_log_row_fixed(k, tick_ns, a, sub0, sub1, sub2, sub3, p, F, j, L, counts, wrench):
    """sim_log_row with its fixed arguments in `a` (sim_log): one argument for five."""
    sim_log_row(k, tick_ns, a.stage_ns, sub0, sub1, sub2, sub3, a.ns_log, p, F, a.pF_log, j, L, counts, wrench,
                a.Lf_log, a.counts_log)
