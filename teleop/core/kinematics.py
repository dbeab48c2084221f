"""CDPR kinematics (seed 000 eqs 4-8): pose -> cable vectors, lengths, bending angles, structure matrix.

Pose convention: a 6-vector ``pose = [x, y, z, alpha, beta, gamma]`` in {B}: the end effector's reference
point p [m] and Z-Y-X Euler angles [rad], R = Rz(alpha) Ry(beta) Rx(gamma) (eq 5: p_i = p + R r_i).
Cable vector l_i = B_i P_i = p_i - B_i (eq 4), pointing from the scaffold to the end effector.
The formulas are the kernels of teleop.core.kernels.geometry; this module is their numpy face. No devices, no
pybullet.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

from teleop.core.errors import InfeasibleError, InputError
from teleop.core.geometry import Geometry
from teleop.core.kernels import geometry as K


def rotation_zyx(alpha: float, beta: float, gamma: float) -> np.ndarray:
    """(3, 3) rotation R = Rz(alpha) Ry(beta) Rx(gamma) mapping {P} to {B} (angles in rad; kernel
    geometry.rotation_zyx)."""
    return np.array(K.rotation_zyx(float(alpha), float(beta), float(gamma))).reshape(3, 3)


def _offsets(pose, geom: Geometry) -> np.ndarray:
    """(6, 6) per cable (R r_i - B_i, R r_i) at the pose's orientation (kernel geometry.platform_offsets)."""
    q = np.asarray(pose, dtype=float)
    return K.platform_offsets(float(q[3]), float(q[4]), float(q[5]), geom.r, geom.B, np.empty((len(geom.B), 6)))


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
    return np.asarray(pose, dtype=float)[:3] + _offsets(pose, geom)[:, 3:]


def pose2cables(pose, geom: Geometry) -> np.ndarray:
    """(6, 3) cable vectors l_i = p_i - B_i = p + (R r_i - B_i) [m] (eq 4)."""
    return np.asarray(pose, dtype=float)[:3] + _offsets(pose, geom)[:, :3]


def pose2lengths(pose, geom: Geometry) -> np.ndarray:
    """(6,) cable lengths |l_i| [m] (kernel geometry.pose2lengths_into)."""
    n = len(geom.B)
    return K.pose2lengths_into(np.asarray(pose, dtype=float), geom.r, geom.B, np.empty((n, 6)), np.empty(n))


def poses2lengths(poses, geom: Geometry) -> np.ndarray:
    """(N, 6) cable lengths [m] for (N, 6) poses (a compiled loop over a trajectory)."""
    q = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, dtype=float)))
    return K.poses2lengths_batch(q, geom.r, geom.B, np.empty((len(q), len(geom.B))))


def bending_angles(l: np.ndarray, geom: Geometry) -> np.ndarray:
    """(6,) cable bending angle theta_i [rad] at the scaffold exit (eq 6), as a magnitude.

    theta = 90 deg - arccos(v . l / (|v| |l|)), v the normal of the base-anchor plane. Rear cables leave
    the plane backwards (negative elevation); the sheath bends the same amount the other way, so the
    capstan angle is |theta|.
    """
    l = np.asarray(l, dtype=float)
    vx, vy, vz = (float(c) for c in geom.v)
    flat = np.ascontiguousarray(l.reshape(-1, 3))
    out = K.bending_loop(flat, vx, vy, vz, np.empty(len(flat)))  # kernel geometry.wrap_angle
    return out.reshape(l.shape[:-1]) if l.ndim > 1 else float(out[0])


def capstan_angles(pose, geom: Geometry) -> np.ndarray:
    """(6,) total wrap Theta_i = theta_i (eq 6) + theta0 [rad] between each FSR and the end effector."""
    return bending_angles(pose2cables(pose, geom), geom) + geom.theta0


def structure_matrix(pose, geom: Geometry) -> np.ndarray:
    """(6, 6) structure matrix A of eq 8, so that A t + f = 0 for cable tensions t [N] and wrench f.

    Column i is [-u_i; -(R r_i) x u_i] with u_i = l_i / |l_i|: the wrench on the end effector per newton
    of cable i (a cable pulls P_i towards B_i). Moments are taken about the reference point p.
    f = [F (N), tau (N m)].
    """
    n = len(geom.B)
    return K.structure_matrix_into(np.asarray(pose, dtype=float), geom.r, geom.B, np.empty((n, 6)), np.empty((6, n)))


def is_axial(geom: Geometry) -> bool:
    """True when every platform anchor lies on the shaft axis (z of {P}): roll is not cable-controlled."""
    return bool(np.allclose(geom.r[:, :2], 0.0, atol=1e-12))


def check_lengths(lengths, geom: Geometry) -> np.ndarray:
    """Return finite (6,) lengths within [l_min, l_max] or raise InfeasibleError."""
    L = np.asarray(lengths, dtype=float)
    if L.shape == (6,) and K.lengths_outside(np.ascontiguousarray(L), float(geom.l_min), float(geom.l_max)) < 0:
        return L
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
    # several null directions: an LP decides positivity
    k = null.shape[0]
    res = linprog(np.zeros(k), A_ub=-null.T, b_ub=-np.ones(6), bounds=[(None, None)] * k, method="highs")
    return bool(res.status == 0)


FREE_ALL = np.arange(6)
FREE_AXIAL = np.array([0, 1, 2, 4, 5])  # an axial geometry: the roll alpha is not set by the cables


def lengths2pose(lengths, geom: Geometry, guess=None, tol: float = 1e-14) -> np.ndarray:
    """Forward kinematics: the pose whose cable lengths match `lengths` [m] within tol [m] (Gauss-Newton from
    `guess`, default the zero pose; kernel geometry.forward_kinematics).

    For an axial geometry (anchors on the shaft axis) alpha is not observable from the lengths and is
    returned as 0 (the instrument's roll); the pose is then [x, y, z, 0, beta, gamma].
    Raises InfeasibleError when no pose reproduces the lengths within 1 um.
    """
    L = np.asarray(lengths, dtype=float)
    if L.shape != (6,) or not np.isfinite(L).all():
        raise InputError(f"cable lengths must be 6 finite numbers, got {np.asarray(lengths).tolist()}")
    q = np.zeros(6) if guess is None else np.array(guess, dtype=float).reshape(6)
    free = FREE_AXIAL if is_axial(geom) else FREE_ALL
    if free is FREE_AXIAL:
        q[3] = 0.0
    worst = K.forward_kinematics(L, q, free, geom.r, geom.B, tol, 100)
    if not worst <= 1e-6:
        raise InfeasibleError(f"no pose reproduces cable lengths {np.round(L * 1e3, 4).tolist()} mm "
                              f"(residual {worst * 1e3:.3g} mm)")
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
