"""The loop's compute step as pure functions of numpy arrays; the estimator protocol the loop calls.

The default estimator is teleop.estimation.reading.ReadingEstimator ("dynamic": FSR branches, capstan and
turn compensation, f = -A t, steady-state Kalman).

Force path (robot frame {B} -> stylus frame):  F = k_f R_reg^T f[:3], optional zeroing of -z, ramp-in
factor, then the safety clamp to the device's continuous limit (NaN/inf -> zero and a fault).
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np



class Estimator(Protocol):
    """Raw robot readings -> cable tensions t (6,) [N] and external wrench f (6,) [N, N m]."""

    def reset(self) -> None: ...
    def update(self, reading, pose, dt: float) -> tuple[np.ndarray, np.ndarray]: ...
    def describe(self) -> dict:
        """Calibration and settings, stored in the session metadata."""


def structure_matrix_at(p, Rr: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(6, 6) structure matrix A (eq 8) at position p (3,) [m] for precomputed R r_i (6, 3) and anchors B (6, 3).

    Same as kinematics.structure_matrix for that orientation: column i = [-u_i; -(R r_i) x u_i].
    """
    l = Rr - B + p
    u = l / np.sqrt(np.einsum("ij,ij->i", l, l))[:, None]
    A = np.empty((6, len(B)))
    A[:3] = -u.T
    A[3] = -(Rr[:, 1] * u[:, 2] - Rr[:, 2] * u[:, 1])
    A[4] = -(Rr[:, 2] * u[:, 0] - Rr[:, 0] * u[:, 2])
    A[5] = -(Rr[:, 0] * u[:, 1] - Rr[:, 1] * u[:, 0])
    return A


def render_force(f, R_reg: np.ndarray, force_scale: float, zero_neg_z: bool) -> np.ndarray:
    """(3,) stylus force [N] from the external wrench f (6,) in {B}: k_f R_reg^T f[:3], -z zeroed if asked.

    Non-finite or overflowing inputs give non-finite output, which clamp_force turns into a fault.
    """
    fx, fy, fz = np.asarray(f, dtype=float)[:3].tolist()
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R_reg.tolist()
    k = force_scale
    # F = k R^T f, written out (a 3x3 product in numpy costs more in call overhead than in arithmetic)
    Fx = k * (r00 * fx + r10 * fy + r20 * fz)
    Fy = k * (r01 * fx + r11 * fy + r21 * fz)
    Fz = k * (r02 * fx + r12 * fy + r22 * fz)
    if zero_neg_z and Fz < 0.0:
        Fz = 0.0
    return np.array([Fx, Fy, Fz])


def ramp_factor(elapsed: float, ramp_time: float) -> float:
    """Ramp-in gain in [0, 1]: linear over `ramp_time` [s] after engaging."""
    if ramp_time <= 0.0:
        return 1.0
    return min(1.0, max(0.0, elapsed / ramp_time))


def clamp_force(F, limit: float) -> tuple[np.ndarray, bool]:
    """(F', ok): F scaled down to norm <= limit [N]; any non-finite input gives zeros and ok=False."""
    F = np.asarray(F, dtype=float)
    if F.shape != (3,):
        return np.zeros(3), False
    x, y, z = F.tolist()
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return np.zeros(3), False
    n = math.hypot(x, y, z)  # no overflow for |F| ~ 1e308
    if n > limit:
        k = limit / n
        return np.array([x * k, y * k, z * k]), True
    return np.array([x, y, z]), True
