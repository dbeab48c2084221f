"""Per-sample forward kinematics and pose terms of the simulated robot, in plain floats.

The loop commands one length vector per tick and the pose moves by micrometres between ticks, so the
simulated slave solves its forward kinematics from the previous pose by a chord Newton method: the
Jacobian pseudo-inverse of a recent pose is reused (refreshed when convergence slows) and the residual is
computed on Python floats (six cables: numpy's per-call overhead would dominate). Same poses as the batched
Gauss-Newton `scenes.sim_robot.lengths2poses` to 1e-9 m (tested); ~6x faster per sample.

`pose_terms` gives what the robot needs at a pose, from the same float cable vectors: the structure matrix
A (eq 8, as teleop.kinematics.structure_matrix), the capstan wraps Theta_i = theta_i (eq 6) + theta0 and the
tool-tip offset R tip.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.errors import InputError
from teleop.geometry import Geometry

FREE = (0, 1, 2, 4, 5)  # axial geometry: the roll alpha is not set by the cables


def _rotation(a: float, b: float, c: float) -> tuple:
    """R = Rz(a) Ry(b) Rx(c) as three row tuples (teleop.kinematics.rotation_zyx)."""
    ca, sa, cb, sb, cg, sg = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return ((ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg),
            (sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg),
            (-sb, cb * sg, cb * cg))


def cables(q, B: list, r: list) -> tuple[list, list]:
    """(cable vectors l_i = p + R r_i - B_i, R r_i) at pose q (6 floats) [m], as lists of 3-tuples."""
    x, y, z = q[0], q[1], q[2]
    R0, R1, R2 = _rotation(q[3], q[4], q[5])
    ls, rrs = [], []
    for (bx, by, bz), (rx, ry, rz) in zip(B, r):
        rr = (R0[0] * rx + R0[1] * ry + R0[2] * rz, R1[0] * rx + R1[1] * ry + R1[2] * rz,
              R2[0] * rx + R2[1] * ry + R2[2] * rz)
        rrs.append(rr)
        ls.append((x + rr[0] - bx, y + rr[1] - by, z + rr[2] - bz))
    return ls, rrs


def lengths(q, B: list, r: list) -> list:
    """Six cable lengths [m] at pose q."""
    return [math.sqrt(lx * lx + ly * ly + lz * lz) for lx, ly, lz in cables(q, B, r)[0]]


class PoseFollower:
    """Forward kinematics one sample at a time from the previous pose (see the module docstring).

    Args:
        geom: the robot geometry (axial: roll not set by the cables).
        pose: (6,) starting pose [m, rad].
        tol: length residual [m] at which Newton stops; `solve` raises InputError above 1e-6 m.
    """

    def __init__(self, geom: Geometry, pose, tol: float = 1e-9):
        self.B, self.r = geom.B.tolist(), geom.r.tolist()
        self.tol = tol
        self.q = [float(v) for v in pose]
        self._pinv = None

    def _refresh(self, q: list) -> None:
        h = 1e-7
        L0 = lengths(q, self.B, self.r)
        J = np.empty((6, len(FREE)))
        for j, k in enumerate(FREE):
            qq = list(q)
            qq[k] += h
            J[:, j] = [(a - b) / h for a, b in zip(lengths(qq, self.B, self.r), L0)]
        self._pinv = np.linalg.pinv(J).tolist()

    def solve(self, L) -> list:
        """Pose (6 floats) [m, rad] whose cable lengths are L (6,) [m]."""
        L = [float(v) for v in L]
        q = list(self.q)
        if self._pinv is None:
            self._refresh(q)
        for it in range(12):
            res = [a - b for a, b in zip(lengths(q, self.B, self.r), L)]
            worst = max(abs(v) for v in res)
            if worst < self.tol:
                break
            if it in (3, 7):  # slow chord convergence: a fresh Jacobian where we are
                self._refresh(q)
            for row, k in zip(self._pinv, FREE):
                q[k] -= sum(a * b for a, b in zip(row, res))
        else:
            if worst > 1e-6:
                raise InputError(f"sim robot: no pose reproduces the commanded lengths (residual {worst:.3g} m)")
        self.q = q
        return list(q)


def pose_terms(q, geom: Geometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A (6, 6) structure matrix of eq 8, Theta (6,) capstan wraps theta (eq 6) + theta0 [rad],
    tool-tip offset R tip (3,) [m]) at pose q."""
    ls, rrs = cables(q, geom.B.tolist(), geom.r.tolist())
    vx, vy, vz = (float(v) for v in geom.v)
    A = np.empty((6, 6))
    theta = np.empty(6)
    for i, ((lx, ly, lz), (rx, ry, rz)) in enumerate(zip(ls, rrs)):
        n = math.sqrt(lx * lx + ly * ly + lz * lz)
        ux, uy, uz = lx / n, ly / n, lz / n
        A[:, i] = (-ux, -uy, -uz, -(ry * uz - rz * uy), -(rz * ux - rx * uz), -(rx * uy - ry * ux))
        c = min(1.0, max(-1.0, vx * ux + vy * uy + vz * uz))
        theta[i] = abs(math.asin(c)) + geom.theta0
    R = _rotation(q[3], q[4], q[5])
    tx, ty, tz = (float(v) for v in geom.tip)
    tip = np.array([R[k][0] * tx + R[k][1] * ty + R[k][2] * tz for k in range(3)])
    return A, theta, tip
