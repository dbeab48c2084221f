"""Kernels of the CDPR geometry (seed 000 eqs 4-6, 8) on floats: the one definition of each formula.

- `rotation_zyx`: R = Rz(alpha) Ry(beta) Rx(gamma) (eq 5), as 9 floats row by row.
- `platform_offsets`: per cable (R r_i - B_i, R r_i) for one orientation, (n, 6) [m].
- `cable`: length L_i = |p + R r_i - B_i| and unit vector u_i (eq 4).
- `wrap_angle`: total capstan wrap Theta_i = |theta_i| (eq 6, bending at the scaffold exit) + theta0 [rad].
- `pose2lengths_into` / `poses2lengths_batch`: inverse kinematics of one pose / of (n, 6) poses.
- `structure_column`: column i of A (eq 8), [-u_i; -(R r_i) x u_i].
- `forward_kinematics`: the pose whose cable lengths match (Gauss-Newton from a guess, forward-difference
  Jacobian over the free coordinates).
Geometry arrays: r (n, 3) platform anchors in {P}, B (n, 3) base anchors in {B} [m].
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels.jit import njit
from teleop.core.kernels.linalg import solve_into


@njit
def rotation_zyx(a, b, g):
    """R = Rz(a) Ry(b) Rx(g) (angles [rad]) as (R00, R01, R02, R10, R11, R12, R20, R21, R22)."""
    ca, sa, cb, sb, cg, sg = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(g), math.sin(g)
    return (ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg,
            sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg,
            -sb, cb * sg, cb * cg)


@njit
def platform_offsets(a, b, g, r, B, out):
    """out (n, 6): per cable (R r_i - B_i, R r_i) [m] for orientation (a, b, g) [rad]; returns out."""
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = rotation_zyx(a, b, g)
    for i in range(r.shape[0]):
        rx, ry, rz = r[i, 0], r[i, 1], r[i, 2]
        qx = R00 * rx + R01 * ry + R02 * rz
        qy = R10 * rx + R11 * ry + R12 * rz
        qz = R20 * rx + R21 * ry + R22 * rz
        out[i, 0], out[i, 1], out[i, 2] = qx - B[i, 0], qy - B[i, 1], qz - B[i, 2]
        out[i, 3], out[i, 4], out[i, 5] = qx, qy, qz
    return out


@njit
def cable(x, y, z, off, i):
    """(L [m], ux, uy, uz) of cable i at position (x, y, z) [m]: l_i = p + (R r_i - B_i) (eq 4)."""
    lx = x + off[i, 0]
    ly = y + off[i, 1]
    lz = z + off[i, 2]
    L = math.sqrt(lx * lx + ly * ly + lz * lz)
    return L, lx / L, ly / L, lz / L


@njit
def wrap_angle(ux, uy, uz, vx, vy, vz, theta0):
    """Theta = |theta| + theta0 [rad]: theta = asin(v . u) the cable's bend at the scaffold exit (eq 6,
    90 deg - angle to the base-plane normal v; a magnitude: the sheath bends the same either way)."""
    s = ux * vx + uy * vy + uz * vz
    s = 1.0 if s > 1.0 else (-1.0 if s < -1.0 else s)
    return abs(math.asin(s)) + theta0


@njit
def structure_column(ux, uy, uz, qx, qy, qz):
    """Column of A (eq 8) for unit vector u and R r_i = q: (-u, -(q x u))."""
    return (-ux, -uy, -uz, -(qy * uz - qz * uy), -(qz * ux - qx * uz), -(qx * uy - qy * ux))


@njit
def pose2lengths_into(q, r, B, off, out):
    """out (n,): cable lengths [m] at pose q (6,) [m, rad]; off (n, 6) scratch. Returns out."""
    platform_offsets(q[3], q[4], q[5], r, B, off)
    for i in range(r.shape[0]):
        out[i] = cable(q[0], q[1], q[2], off, i)[0]
    return out


@njit
def lengths_at(x, y, z, off, out):
    """out (n,): cable lengths [m] at position (x, y, z) [m] for the orientation whose platform_offsets are off
    (n, 6). Returns out."""
    for i in range(off.shape[0]):
        out[i] = cable(x, y, z, off, i)[0]
    return out


@njit
def poses2lengths_batch(q, r, B, out):
    """out (m, n): cable lengths [m] for poses q (m, 6). Returns out."""
    off = np.empty((r.shape[0], 6))
    for k in range(q.shape[0]):
        pose2lengths_into(q[k], r, B, off, out[k])
    return out


@njit
def forward_kinematics(L, q, free, r, B, tol, max_iter):
    """Pose q (6,) [m, rad], updated in place from its value as the guess, whose cable lengths match L (n,)
    [m]; only the coordinates listed in `free` move (an axial geometry fixes the roll alpha). Gauss-Newton
    with a forward-difference Jacobian (h = 1e-7) and step halving while the residual grows. Stops when the
    largest length residual is below tol [m], or when the Gauss-Newton step is (every coordinate below tol,
    [m] and [rad]): lengths that no pose has exactly (the loop's per-cable step limit: residuals of a few
    nm) have reached their least-squares pose, and further steps are
    round-off (steps shrink to 1e-14 m and below, halving after halving). Returns the largest
    length residual [m] reached. (The Jacobian's position columns reuse the orientation's platform offsets
    of q, `off_q`: the same numbers as recomputing them, without the trigonometry.)"""
    n, m = L.shape[0], free.shape[0]
    h = 1e-7
    off = np.empty((n, 6))
    off_q = np.empty((n, 6))
    Lq = np.empty(n)
    Lh = np.empty(n)
    res = np.empty(n)
    J = np.empty((n, m))
    JTJ = np.empty((m, m))
    JTr = np.empty(m)
    step = np.empty(m)
    qt = np.empty(6)
    pose2lengths_into(q, r, B, off_q, Lq)
    worst = 0.0
    sse = 0.0
    for i in range(n):
        res[i] = Lq[i] - L[i]
        worst = max(worst, abs(res[i]))
        sse += res[i] * res[i]
    for _ in range(max_iter):
        if worst < tol:
            break
        for j in range(m):
            qt[:] = q
            qt[free[j]] += h
            if free[j] < 3:
                lengths_at(qt[0], qt[1], qt[2], off_q, Lh)
            else:
                pose2lengths_into(qt, r, B, off, Lh)
            for i in range(n):
                J[i, j] = (Lh[i] - Lq[i]) / h
        for a in range(m):  # normal equations J^T J step = J^T res
            acc = 0.0
            for i in range(n):
                acc += J[i, a] * res[i]
            JTr[a] = acc
            for b in range(m):
                acc = 0.0
                for i in range(n):
                    acc += J[i, a] * J[i, b]
                JTJ[a, b] = acc
        solve_into(JTJ, JTr, step)
        big = 0.0
        for j in range(m):
            big = max(big, abs(step[j]))
        if big < tol:  # converged: the pose is the least-squares one within tol
            break
        lam = 1.0
        for _half in range(30):  # accept the first step (halved as needed) that lowers the residual
            qt[:] = q
            for j in range(m):
                qt[free[j]] -= lam * step[j]
            pose2lengths_into(qt, r, B, off, Lh)
            sse_t = 0.0
            for i in range(n):
                sse_t += (Lh[i] - L[i]) ** 2
            if sse_t < sse or lam < 1e-6:
                break
            lam *= 0.5
        q[:] = qt
        off_q[:] = off  # the offsets of the accepted trial, now q's
        worst = 0.0
        sse = 0.0
        for i in range(n):
            Lq[i] = Lh[i]
            res[i] = Lh[i] - L[i]
            worst = max(worst, abs(res[i]))
            sse += res[i] * res[i]
    return worst


@njit
def structure_matrix_into(q, r, B, off, A):
    """A (6, n): structure matrix of eq 8 at pose q (column i = structure_column of cable i); off (n, 6)
    scratch. Returns A."""
    platform_offsets(q[3], q[4], q[5], r, B, off)
    for i in range(r.shape[0]):
        _, ux, uy, uz = cable(q[0], q[1], q[2], off, i)
        A[0, i], A[1, i], A[2, i], A[3, i], A[4, i], A[5, i] = structure_column(ux, uy, uz, off[i, 3], off[i, 4],
                                                                                off[i, 5])
    return A


@njit
def bending_loop(l, vx, vy, vz, out):
    """out (m,): |theta| [rad] (eq 6) of cable vectors l (m, 3) for the base-plane normal v."""
    for k in range(l.shape[0]):
        L = math.sqrt(l[k, 0] * l[k, 0] + l[k, 1] * l[k, 1] + l[k, 2] * l[k, 2])
        out[k] = wrap_angle(l[k, 0] / L, l[k, 1] / L, l[k, 2] / L, vx, vy, vz, 0.0)
    return out


@njit
def lengths_outside(L, l_min, l_max):
    """Index of the first length [m] that is not finite or outside [l_min, l_max], -1 if none."""
    for i in range(L.shape[0]):
        if not (l_min <= L[i] <= l_max):
            return i
    return -1
