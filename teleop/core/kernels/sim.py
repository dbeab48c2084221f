"""Kernels of the simulated robot's per-reading physics (scenes.sim_robot): the geometry terms at a pose and
the cable chain tip tensions -> FSR-side tensions, built from the shared kernels (one definition each).

    pose_terms: structure matrix A (eq 8), wraps Theta_i = |theta_i| (eq 6) + theta0, tool offset R tip
    cable_sensor: tension distribution at A (A t + f = 0, one-dimensional null space closest to the
        sheath's pretension), then per cable the sheath's law (sheath.motor_forces) at the motor position
        x = -length
    reading: one reading after the physics steps (contact wrench, motor steps, cable_sensor) in one call:
        every kernel call pays for its argument handling, and several per reading added up in the
        closed-loop simulation's tick
    reading_tips: reading up to the tip tensions (balance_tensions), for a cable other than the lumped sheath
    reading_counts: reading and, with nothing between the cable and its FSR, the FSRs' ADC counts
        (sensor.fsr_counts) in the same call
"""

from __future__ import annotations


import numpy as np

from teleop.core.kernels import sheath as SH
from teleop.core.kernels.geometry import cable, forward_kinematics, lengths_outside, platform_offsets, rotation_zyx, \
    structure_column, wrap_angle
from teleop.core.kernels.jit import njit, structure
from teleop.core.kernels.sensor import conductance_loop, fsr_counts  # noqa: F401 (conductance_loop: KS.conductance_loop)
from teleop.core.kernels.tension import OK, null1_terms, null1_tensions


@njit
def pose_terms(q, r, B, v, theta0, tip, off, A, theta, tip_off):
    """At pose q (6,): A (6, n), theta (n,) [rad], tip_off (3,) = R tip [m]; off (n, 6) scratch."""
    platform_offsets(q[3], q[4], q[5], r, B, off)
    for i in range(r.shape[0]):
        _, ux, uy, uz = cable(q[0], q[1], q[2], off, i)
        A[0, i], A[1, i], A[2, i], A[3, i], A[4, i], A[5, i] = structure_column(ux, uy, uz, off[i, 3], off[i, 4],
                                                                                off[i, 5])
        theta[i] = wrap_angle(ux, uy, uz, v[0], v[1], v[2], theta0)
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = rotation_zyx(q[3], q[4], q[5])
    tip_off[0] = R00 * tip[0] + R01 * tip[1] + R02 * tip[2]
    tip_off[1] = R10 * tip[0] + R11 * tip[1] + R12 * tip[2]
    tip_off[2] = R20 * tip[0] + R21 * tip[1] + R22 * tip[2]


@njit
def pose_terms_loop(q, r, B, v, theta0, tip, A, theta, tip_off):
    """pose_terms for poses q (m, 6): A (m, 6, n), theta (m, n), tip_off (m, 3)."""
    off = np.empty((r.shape[0], 6))
    for k in range(q.shape[0]):
        pose_terms(q[k], r, B, v, theta0, tip, off, A[k], theta[k], tip_off[k])


@njit
def forward_kinematics_batch(L, q0, free, r, B, tol, max_iter, out):
    """out (m, 6): poses for lengths L (m, n), each solved from the previous one (the first from q0);
    returns the largest residual [m]."""
    q = q0.copy()
    worst = 0.0
    for k in range(L.shape[0]):
        worst = max(worst, forward_kinematics(L[k], q, free, r, B, tol, max_iter))
        out[k] = q
    return worst


@njit
def cable_sensor(f, A, theta, x, t_min, t_max, c, cap, t_tip, t_fsr):
    """One reading: tip tensions t_tip (n,) [N] balancing the wrench f (6,) at A, then the FSR-side tensions
    t_fsr (n,) [N] through each cable's sheath (wrap theta (n,) [rad]) at motor positions x (n,) [m]; c the
    sheath's constants (at the head of the array), cap (sheath.N_STATE, n) its state. Returns tension.OK, or
    the tension kernel's status (-1: A is not of rank n - 1), and then changes nothing."""
    status = balance_tensions(f, A, t_min, t_max, c[SH.PRETENSION], t_tip)
    if status != OK:
        return status
    SH.motor_forces(cap, x, t_tip, theta, c, t_fsr)
    return OK


@njit
def balance_tensions(f, A, t_min, t_max, pretension, t_tip):
    """Tip tensions t_tip (n,) [N] balancing the wrench f (6,) at A (A t + f = 0, the one-dimensional null
    space closest to `pretension` [N], within [t_min, t_max] [N]). Returns tension.OK, or the tension kernel's
    status (-1: A is not of rank n - 1)."""
    LU, p, q, nv, ok = null1_terms(A)
    if not ok:
        return -1
    return null1_tensions(LU, p, q, A, nv, f, t_min, t_max, pretension, t_tip)[0]


@njit
def contact_moment(o, F, out):
    """out (6,) = (F, o x F): the contact force at the tool tip and its moment about p (tip offset o); returns
    nothing (the caller holds out)."""
    out[0], out[1], out[2] = F[0], F[1], F[2]
    out[3] = o[1] * F[2] - o[2] * F[1]
    out[4] = o[2] * F[0] - o[0] * F[2]
    out[5] = o[0] * F[1] - o[1] * F[0]




@njit
def series_spring_force(pos, v, target, r, KDM, dtm, fc, implicit):
    """(3,) force [N] of the series spring-damper pulling the contact sphere (centre pos (3,) [m], velocity v
    (3,) [m/s]) towards the centre target tgt = target - (0, 0, r), target (3,) the touching point's [m], r
    the sphere's radius [m]. KDM (3, 3, 3): the stiffness K [N/m], the damping D [N s/m] and Mi [-].
    Explicit f = -K e - D v (D the damping C), e = pos - tgt; implicit (stiff springs,
    scenes.world.implicit_spring) f = Mi (-K e - D v'), v' = v + dtm fc, with the contact force fc (3,) [N] of
    the last step, D = dt K + C, Mi = (I + D dt/m)^-1 and dtm = dt/m [s/kg]."""
    K, D, Mi = KDM[0], KDM[1], KDM[2]
    e0, e1, e2 = pos[0] - target[0], pos[1] - target[1], pos[2] - (target[2] - r)
    if implicit:
        w0, w1, w2 = v[0] + dtm * fc[0], v[1] + dtm * fc[1], v[2] + dtm * fc[2]
    else:
        w0, w1, w2 = v[0], v[1], v[2]
    g0 = -(K[0, 0] * e0 + K[0, 1] * e1 + K[0, 2] * e2) - (D[0, 0] * w0 + D[0, 1] * w1 + D[0, 2] * w2)
    g1 = -(K[1, 0] * e0 + K[1, 1] * e1 + K[1, 2] * e2) - (D[1, 0] * w0 + D[1, 1] * w1 + D[1, 2] * w2)
    g2 = -(K[2, 0] * e0 + K[2, 1] * e1 + K[2, 2] * e2) - (D[2, 0] * w0 + D[2, 1] * w1 + D[2, 2] * w2)
    if not implicit:
        return g0, g1, g2
    return (Mi[0, 0] * g0 + Mi[0, 1] * g1 + Mi[0, 2] * g2, Mi[1, 0] * g0 + Mi[1, 1] * g1 + Mi[1, 2] * g2,
            Mi[2, 0] * g0 + Mi[2, 1] * g1 + Mi[2, 2] * g2)


@njit
def position_steps(L_home, L, steps_per_m, out):
    """out (n,) int64: the motors' positions [microsteps] relative to home for cable lengths L (n,) [m],
    rint((L_home - L) steps_per_m) (hauling in is +); returns nothing (the caller holds out)."""
    for i in range(L.shape[0]):
        out[i] = int(np.rint((L_home[i] - L[i]) * steps_per_m))


# constants of `reading` (scenes.sim_robot.SimRobot): the sheath's (sheath.N_CONST), then the tension range
# [N] and the motor steps per metre
T_MIN, T_MAX, STEPS_PER_M, N_READING_CONST = range(SH.N_CONST, SH.N_CONST + 4)


@njit
def reading(o, F, A, theta, x, L_home, L, c, cap, f, t_tip, t_fsr, steps):
    """The simulated robot's reading after its physics steps, one call (scenes.sim_robot.SimRobot.read):
    f (6,) the contact wrench (contact_moment of the contact force F (3,) [N] at the tool offset o (3,) [m]),
    steps (n,) the motors' positions (position_steps of the commanded lengths L against L_home), then the
    cable chain (cable_sensor: t_tip, t_fsr (n,) [N] at A, wraps theta, motor positions x, sheath state
    cap). c (N_READING_CONST,): the constants named above. Returns cable_sensor's status (f and steps are
    written whatever it is)."""
    status = reading_tips(o, F, A, L_home, L, c, f, t_tip, steps)
    if status != OK:
        return status
    SH.motor_forces(cap, x, t_tip, theta, c, t_fsr)
    return OK


@njit
def reading_tips(o, F, A, L_home, L, c, f, t_tip, steps):
    """`reading` up to the tip tensions (f, steps, t_tip; no sheath): for a robot whose cable is another
    model than the lumped sheath (scenes.sim_robot_kernels.reading_cables). Returns balance_tensions' status
    (f and steps are written whatever it is)."""
    contact_moment(o, F, f)
    position_steps(L_home, L, c[STEPS_PER_M], steps)
    return balance_tensions(f, A, c[T_MIN], c[T_MAX], c[SH.PRETENSION], t_tip)


@njit
def pose_target(q, r, B, v, theta0, tip, off, A, theta, tip_off, target):
    """pose_terms at pose q, and target (3,) = p + R tip [m], where the tool tip is commanded."""
    pose_terms(q, r, B, v, theta0, tip, off, A, theta, tip_off)
    for j in range(3):
        target[j] = q[j] + tip_off[j]


@njit
def follow_pose(L, l_min, l_max, q, free, r, B, tol, max_iter, max_residual, v, theta0, tip, off, A, theta, tip_off,
                target):
    """The simulated robot's command (scenes.sim_robot.SimRobot.command_lengths) in one call: the lengths L
    (n,) [m] checked against [l_min, l_max] (geometry.lengths_outside), forward kinematics from the pose q (6,)
    (updated in place) to them, then, if q moved and the lengths are met within max_residual [m], pose_target
    at the new pose (else the terms are left as they were). Returns (the largest length residual [m], whether
    q moved, the first length outside its limits or not finite (-1: none; then nothing else is done))."""
    bad = lengths_outside(L, l_min, l_max)
    if bad >= 0:
        return np.nan, False, bad
    q0, q1, q2, q3, q4, q5 = q[0], q[1], q[2], q[3], q[4], q[5]
    worst = forward_kinematics(L, q, free, r, B, tol, max_iter)
    moved = q[0] != q0 or q[1] != q1 or q[2] != q2 or q[3] != q3 or q[4] != q4 or q[5] != q5
    if moved and worst <= max_residual:
        pose_target(q, r, B, v, theta0, tip, off, A, theta, tip_off, target)
    return worst, moved, bad


#: follow_pose's arguments after the lengths, by name: the same objects (and values) command after command
FOLLOW_FIXED = ("l_min", "l_max", "q", "free", "r", "B", "tol", "max_iter", "max_residual", "v", "theta0", "tip", "off",
                "A", "theta", "tip_off", "target")
# follow_pose's fixed arguments held together (jit.structure; the type bound here for numba's cache)
FixedFollow = structure(__name__, "FixedFollow", FOLLOW_FIXED)
FixedFollowType = getattr(FixedFollow, "numba_type", None)


@njit
def fixed_follow(l_min, l_max, q, free, r, B, tol, max_iter, max_residual, v, theta0, tip, off, A, theta, tip_off,
                 target):
    """A FixedFollow holding follow_pose's arguments after the lengths (the same arrays, not copies), for
    follow_pose_fixed; built by a compiled (cached) call."""
    return FixedFollow(l_min, l_max, q, free, r, B, tol, max_iter, max_residual, v, theta0, tip, off, A, theta, tip_off,
                       target)


@njit
def follow_pose_fixed(L, a):
    """follow_pose of the lengths L (n,) [m] with its other arguments in `a` (fixed_follow): two arguments for
    eighteen (a kernel call unboxes each array argument; the simulated robot commands every tick)."""
    return follow_pose(L, a.l_min, a.l_max, a.q, a.free, a.r, a.B, a.tol, a.max_iter, a.max_residual, a.v, a.theta0,
                       a.tip, a.off, a.A, a.theta, a.tip_off, a.target)


@njit
def reading_counts(o, F, A, theta, x, L_home, L, c, cap, f, t_tip, t_fsr, steps, fsr, u, grid, gap, coefs, r_divider,
                   adc_max, noise, i, counts):
    """`reading`, then, when `fsr` and it is OK, the FSRs' counts (n,) int64 of its t_fsr (sensor.fsr_counts with
    the branch lag's state u and its constants grid, gap, coefs, r_divider, adc_max, and the ADC noise row i of
    noise (m, n) [counts]): the simulated robot's whole reading in one call when no effect acts between the
    cable and its FSR. Returns reading's status (counts left unwritten unless fsr and OK)."""
    status = reading(o, F, A, theta, x, L_home, L, c, cap, f, t_tip, t_fsr, steps)
    if fsr and status == OK:
        fsr_counts(t_fsr, u, grid, gap, coefs, r_divider, adc_max, noise[i], counts)
    return status
