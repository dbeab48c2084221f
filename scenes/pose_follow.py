"""Per-sample forward kinematics and pose terms of the simulated robot.

The loop commands one length vector per tick and the pose moves by micrometres between ticks, so the
simulated slave solves its forward kinematics from the previous pose (teleop.core.kernels.geometry
forward_kinematics: Gauss-Newton, a couple of iterations per tick). `pose_terms` gives what the robot needs
at a pose (teleop.core.kernels.sim.pose_terms): the structure matrix A (eq 8, as teleop.core.kinematics.structure_matrix),
the capstan wraps Theta_i = theta_i (eq 6) + theta0 and the tool-tip offset R tip.
"""

from __future__ import annotations

import numpy as np

from teleop.core.errors import InputError
from teleop.core.geometry import Geometry
from teleop.core.kernels import sim as KS
from teleop.core.kernels.geometry import forward_kinematics
from teleop.core.kernels.jit import bind
from teleop.core.kinematics import FREE_AXIAL, check_lengths

FREE = tuple(FREE_AXIAL.tolist())  # axial geometry: the roll alpha is not set by the cables


class PoseFollower:
    """Forward kinematics one sample at a time from the previous pose (see the module docstring).

    Args:
        geom: the robot geometry (axial: roll not set by the cables).
        pose: (6,) starting pose [m, rad].
        tol: length residual [m] at which Newton stops.
        max_residual: `solve` raises InputError when the least-squares pose misses a length by more [m]
            (lengths that no pose has exactly, e.g. after per-cable play, need more than the 1e-6 default).
    """

    def __init__(self, geom: Geometry, pose, tol: float = 1e-12, max_residual: float = 1e-6):
        self.geom, self.r, self.B = geom, geom.r, geom.B
        self._limits = float(geom.l_min), float(geom.l_max)
        self.tol, self.max_residual = float(tol), float(max_residual)
        self._q = np.array(pose, dtype=float).reshape(6)
        self._L = np.zeros(len(geom.B))
        self._bound = self._bound_terms = self._fixed = None  # follow's kernel, the terms it was bound with, its
        # fixed arguments

    @property
    def q(self) -> list:
        """The current pose (6 floats) [m, rad]."""
        return self._q.tolist()

    @q.setter
    def q(self, pose) -> None:
        self._q[:] = pose

    def solve_into(self, L: np.ndarray) -> np.ndarray:
        """The pose (its (6,) array, updated in place) whose cable lengths are L (n,) float64 [m]."""
        self._check(forward_kinematics(L, self._q, FREE_AXIAL, self.r, self.B, self.tol, 12))
        return self._q

    def follow(self, L: np.ndarray, terms: tuple) -> np.ndarray | None:
        """solve_into, and when the pose moved, the pose terms at it written into `terms` (v, theta0, tip, off,
        A, theta, tip_off, target: the arguments of kernel sim.pose_target after the pose and the geometry's
        anchors) in the same kernel call (sim.follow_pose), which first checks L (n,) float64 against the
        geometry's length limits (teleop.core.kinematics.check_lengths raises with the reason, the pose unchanged);
        the pose's (6,) array if it moved, else None."""
        if terms is not self._bound_terms:  # the other arguments held together (kernel sim.fixed_follow) and the
            # kernel bound to their types and the lengths' (jit.bind: the robot's own float64 arrays)
            self._fixed = KS.fixed_follow(*self._limits, self._q, FREE_AXIAL, self.r, self.B, self.tol, 12,
                                          self.max_residual, *terms)
            self._bound = bind(KS.follow_pose_fixed, L, self._fixed)
            self._bound_terms = terms
        worst, moved, bad = self._bound(L, self._fixed)
        if bad >= 0:
            check_lengths(L, self.geom)
        if not worst <= self.max_residual:  # _check's test (this runs every tick)
            self._check(worst)
        return self._q if moved else None

    def _check(self, worst: float) -> None:
        if not worst <= self.max_residual:
            raise InputError(f"sim robot: no pose reproduces the commanded lengths (residual {worst:.3g} m)")

    def solve(self, L) -> list:
        """Pose (6 floats) [m, rad] whose cable lengths are L (6,) [m]."""
        self._L[:] = L
        return self.solve_into(self._L).tolist()


def pose_terms(q, geom: Geometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A (6, 6) structure matrix of eq 8, Theta (6,) capstan wraps theta (eq 6) + theta0 [rad],
    tool-tip offset R tip (3,) [m]) at pose q."""
    n = len(geom.B)
    A, theta, tip = np.empty((6, n)), np.empty(n), np.empty(3)
    KS.pose_terms(np.asarray(q, dtype=float), geom.r, geom.B, np.asarray(geom.v, dtype=float), float(geom.theta0),
                  np.asarray(geom.tip, dtype=float), np.empty((n, 6)), A, theta, tip)
    return A, theta, tip
