"""CDPR kinematics (seed 000 eqs 4-8): pose -> cable vectors, lengths, bending angles, structure matrix.

Pose convention: a 6-vector ``pose = [x, y, z, alpha, beta, gamma]`` in {B}: the end effector's reference
point p [m] and Z-Y-X Euler angles [rad], R = Rz(alpha) Ry(beta) Rx(gamma) (eq 5: p_i = p + R r_i).
Cable vector l_i = B_i P_i = p_i - B_i (eq 4), pointing from the scaffold to the end effector.
Pure numpy; no devices, no pybullet.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from teleop.errors import InfeasibleError, InputError
from teleop.geometry import Geometry


def rotation_zyx(alpha: float, beta: float, gamma: float) -> np.ndarray:
    """(3, 3) rotation R = Rz(alpha) Ry(beta) Rx(gamma) mapping {P} to {B} (angles in rad)."""
    ca, sa = np.cos(alpha), np.sin(alpha)
    cb, sb = np.cos(beta), np.sin(beta)
    cg, sg = np.cos(gamma), np.sin(gamma)
    return np.array([
        [ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg],
        [sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg],
        [-sb, cb * sg, cb * cg],
    ])


def check_pose(pose) -> np.ndarray:
    """Return `pose` as a finite (6,) float array or raise InputError."""
    q = np.asarray(pose, dtype=float)
    if q.shape != (6,):
        raise InputError(f"pose must be 6 numbers [x, y, z, alpha, beta, gamma], got shape {q.shape}")
    if not np.isfinite(q).all():
        raise InputError(f"pose must be finite, got {q.tolist()}")
    return q


def pose2anchors(pose, geom: Geometry) -> np.ndarray:
    """(6, 3) platform anchors p_i = p + R r_i in {B} [m] (eq 5)."""
    q = np.asarray(pose, dtype=float)
    return q[:3] + geom.r @ rotation_zyx(q[3], q[4], q[5]).T


def pose2cables(pose, geom: Geometry) -> np.ndarray:
    """(6, 3) cable vectors l_i = p_i - B_i [m] (eq 4)."""
    return pose2anchors(pose, geom) - geom.B


def pose2lengths(pose, geom: Geometry) -> np.ndarray:
    """(6,) cable lengths |l_i| [m]."""
    return np.linalg.norm(pose2cables(pose, geom), axis=1)


def poses2lengths(poses, geom: Geometry) -> np.ndarray:
    """(N, 6) cable lengths [m] for (N, 6) poses (vectorised over a trajectory)."""
    q = np.atleast_2d(np.asarray(poses, dtype=float))
    a, b, g = q[:, 3], q[:, 4], q[:, 5]
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    R = np.empty((len(q), 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 0, 2] = ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg
    R[:, 1, 0], R[:, 1, 1], R[:, 1, 2] = sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg
    R[:, 2, 0], R[:, 2, 1], R[:, 2, 2] = -sb, cb * sg, cb * cg
    P = q[:, None, :3] + np.einsum("nij,kj->nki", R, geom.r)
    return np.linalg.norm(P - geom.B[None], axis=2)


def bending_angles(l: np.ndarray, geom: Geometry) -> np.ndarray:
    """(6,) cable bending angle theta_i [rad] at the scaffold exit (eq 6), as a magnitude.

    theta = 90 deg - arccos(v . l / (|v| |l|)), v the normal of the base-anchor plane. Rear cables leave
    the plane backwards (negative elevation); the sheath bends the same amount the other way, so the
    capstan angle is |theta|.
    """
    l = np.asarray(l, dtype=float)
    s = (l @ geom.v) / np.linalg.norm(l, axis=-1)
    return np.abs(np.arcsin(np.clip(s, -1.0, 1.0)))


def capstan_angles(pose, geom: Geometry) -> np.ndarray:
    """(6,) total wrap Theta_i = theta_i (eq 6) + theta0 [rad] between each FSR and the end effector."""
    return bending_angles(pose2cables(pose, geom), geom) + geom.theta0


def structure_matrix(pose, geom: Geometry) -> np.ndarray:
    """(6, 6) structure matrix A of eq 8, so that A t + f = 0 for cable tensions t [N] and wrench f.

    Column i is [-u_i; -(R r_i) x u_i] with u_i = l_i / |l_i|: the wrench on the end effector per newton
    of cable i (a cable pulls P_i towards B_i). Moments are taken about the reference point p.
    f = [F (N), tau (N m)].
    """
    q = np.asarray(pose, dtype=float)
    Rr = geom.r @ rotation_zyx(q[3], q[4], q[5]).T
    l = q[:3] + Rr - geom.B
    u = l / np.linalg.norm(l, axis=1)[:, None]
    return np.vstack([-u.T, -np.cross(Rr, u).T])


def is_axial(geom: Geometry) -> bool:
    """True when every platform anchor lies on the shaft axis (z of {P}): roll is not cable-controlled."""
    return bool(np.allclose(geom.r[:, :2], 0.0, atol=1e-12))


def check_lengths(lengths, geom: Geometry) -> np.ndarray:
    """Return finite (6,) lengths within [l_min, l_max] or raise InfeasibleError."""
    L = np.asarray(lengths, dtype=float)
    if L.shape != (6,) or not np.isfinite(L).all():
        raise InputError(f"cable lengths must be 6 finite numbers, got {np.asarray(lengths).tolist()}")
    if (L < geom.l_min).any() or (L > geom.l_max).any():
        raise InfeasibleError(
            f"cable lengths {np.round(L * 1e3, 3).tolist()} mm outside [{geom.l_min * 1e3:g}, {geom.l_max * 1e3:g}] mm")
    return L


def pose2lengths_checked(pose, geom: Geometry) -> np.ndarray:
    """Inverse kinematics with validation: a NaN pose is an InputError, an unreachable one InfeasibleError.

    Unreachable means a cable length outside its limits, or a pose where the cables cannot hold the end
    effector in pretension (no strictly positive tension vector in the null space of A).
    """
    q = check_pose(pose)
    L = pose2lengths(q, geom)
    try:
        check_lengths(L, geom)
    except InfeasibleError as exc:
        raise InfeasibleError(f"pose {np.round(q, 6).tolist()} unreachable: {exc}") from None
    if not is_tensionable(q, geom):
        raise InfeasibleError(f"pose {np.round(q, 6).tolist()} unreachable: cables cannot all stay in tension")
    return L


def is_tensionable(pose, geom: Geometry, tol: float = 1e-9) -> bool:
    """True if some strictly positive tension vector t satisfies A t = 0 (the pose holds pretension)."""
    A = structure_matrix(pose, geom)
    _, s, Vt = np.linalg.svd(A)
    null = Vt[s < tol * max(1.0, s[0])] if s.size else Vt
    if null.shape[0] == 0:
        return False
    if null.shape[0] == 1:
        n = null[0]
        return bool((n > tol).all() or (n < -tol).all())
    from scipy.optimize import linprog  # several null directions: an LP decides positivity

    k = null.shape[0]
    res = linprog(np.zeros(k), A_ub=-null.T, b_ub=-np.ones(6), bounds=[(None, None)] * k, method="highs")
    return bool(res.status == 0)


def lengths2pose(lengths, geom: Geometry, guess=None, tol: float = 1e-14) -> np.ndarray:
    """Forward kinematics: the pose whose cable lengths match `lengths` [m] (least squares).

    For an axial geometry (anchors on the shaft axis) alpha is not observable from the lengths and is
    returned as 0 (the instrument's roll); the pose is then [x, y, z, 0, beta, gamma].
    Raises InfeasibleError when no pose reproduces the lengths within 1 um.
    """
    L = np.asarray(lengths, dtype=float)
    if L.shape != (6,) or not np.isfinite(L).all():
        raise InputError(f"cable lengths must be 6 finite numbers, got {np.asarray(lengths).tolist()}")
    axial = is_axial(geom)
    x0 = np.zeros(6) if guess is None else np.asarray(guess, dtype=float).copy()
    free = [0, 1, 2, 4, 5] if axial else [0, 1, 2, 3, 4, 5]
    if axial:
        x0[3] = 0.0

    def residual(z):
        q = x0.copy()
        q[free] = z
        return pose2lengths(q, geom) - L

    def jac(z):
        q = x0.copy()
        q[free] = z
        return length_jacobian(q, geom)[:, free]

    sol = least_squares(residual, x0[free], jac=jac, method="lm", xtol=tol, ftol=tol, gtol=tol, max_nfev=200)
    q = x0.copy()
    q[free] = sol.x
    if np.max(np.abs(sol.fun)) > 1e-6:
        raise InfeasibleError(f"no pose reproduces cable lengths {np.round(L * 1e3, 4).tolist()} mm "
                              f"(residual {np.max(np.abs(sol.fun)) * 1e3:.3g} mm)")
    return q


def length_jacobian(pose, geom: Geometry) -> np.ndarray:
    """(6, 6) d(lengths)/d(pose) with pose = [x, y, z, alpha, beta, gamma] (m and rad)."""
    q = np.asarray(pose, dtype=float)
    l = pose2cables(q, geom)
    u = l / np.linalg.norm(l, axis=1)[:, None]
    J = np.empty((6, 6))
    J[:, :3] = u
    a, b, g = q[3:]
    h = 1e-7
    for k, idx in enumerate((3, 4, 5)):
        dq = np.zeros(3)
        dq[k] = h
        dR = (rotation_zyx(*(q[3:] + dq)) - rotation_zyx(*(q[3:] - dq))) / (2 * h)
        J[:, idx] = np.einsum("ij,ij->i", u, geom.r @ dR.T)
    return J
