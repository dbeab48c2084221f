"""Tension distribution: feasible cable tensions t in [t_min, t_max] with A t + f = 0 (seed 000 eq 8).

With six cables and five cable-controlled degrees of freedom, A has a one-dimensional null space n > 0:
t = t_p + lambda n, where t_p is the minimum-norm particular solution. Among feasible tensions the one
closest to a reference pretension level t_ref is chosen (closed form for one null direction, a small QP
otherwise; the closed form is the kernel teleop.core.kernels.tension). Used by the simulated robot and for
pretension.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from teleop.core.errors import InfeasibleError
from teleop.core.kernels import tension as K


class TensionSolver:
    """The tension distribution for one structure matrix A (6, 6): its SVD done once, then `solve(f)` per
    wrench (the simulated robot holds a pose for several readings). Same numbers as `wrench2tensions`."""

    def __init__(self, A: np.ndarray, t_min: float, t_max: float, t_ref: float | None = None, tol: float = 1e-9):
        self.A = np.asarray(A, dtype=float)
        self.t_min, self.t_max = float(t_min), float(t_max)
        self.t_ref = 0.5 * (t_min + t_max) if t_ref is None else float(t_ref)
        U, s, Vt = np.linalg.svd(self.A)
        self.rank = int((s > tol * max(1.0, s[0])).sum())
        self.Ur, self.sr, self.Vr = U[:, :self.rank].T, s[:self.rank], Vt[:self.rank].T
        self.N = Vt[self.rank:].T
        self._null1 = None
        if self.N.shape[1] == 1:
            # the CDPR's one-dimensional null space: solved on floats (numpy's per-call cost dominates at six
            # cables). P = -A^+, n the null direction with positive sum.
            LU, p, q, n, _ = K.null1_terms(self.A)
            self._null1 = (LU, p, q, n)

    def solve(self, f) -> np.ndarray:
        """(6,) cable tensions [N] that balance the external wrench f (6,) [N, N m]: A t + f = 0.

        Raises InfeasibleError when f is outside the wrench-feasible set: either no tension vector produces
        it (e.g. a moment about the shaft axis) or every one that does violates [t_min, t_max].
        """
        f = np.asarray(f, dtype=float)
        if f.shape != (6,) or not np.isfinite(f).all():
            raise InfeasibleError(f"wrench must be 6 finite numbers, got {np.asarray(f).tolist()}")
        if self._null1 is not None:
            return self._solve_null1(f)
        t_min, t_max, t_ref, N = self.t_min, self.t_max, self.t_ref, self.N
        # t_p = -A^+ f (minimum norm), N = null-space basis (6 x k)
        t_p = -(self.Vr @ ((self.Ur @ f) / self.sr))
        resid = self.A @ t_p + f
        scale = max(1.0, float(np.abs(f).max()))
        if np.abs(resid).max() > 1e-7 * scale:
            raise InfeasibleError(
                f"wrench {np.round(f, 6).tolist()} has a component no cable tensions can produce "
                f"(residual {np.abs(resid).max():.3g}); for this robot that is a moment about the shaft axis")
        k = N.shape[1]
        if k == 0:
            t = t_p
        else:
            res = minimize(lambda z: np.sum((t_p + N @ z - t_ref) ** 2), np.zeros(k), method="SLSQP",
                           constraints=[{"type": "ineq", "fun": lambda z: t_p + N @ z - t_min},
                                        {"type": "ineq", "fun": lambda z: t_max - (t_p + N @ z)}])
            t = t_p + N @ res.x
            if not res.success or (t < t_min - 1e-6).any() or (t > t_max + 1e-6).any():
                raise InfeasibleError(f"wrench {np.round(f, 6).tolist()} outside the wrench-feasible set")
        return np.clip(t, t_min, t_max)

    def _solve_null1(self, f: list) -> list:
        """`solve` for a one-dimensional null space n: t = t_p + lambda n, t_p = -A^+ f the minimum-norm
        particular solution, lambda closest to t_ref and clipped to the interval where every tension lies in
        [t_min, t_max] (kernel tension.null1_tensions)."""
        LU, p, q, n = self._null1
        t = np.empty(len(n))
        status, resid = K.null1_tensions(LU, p, q, self.A, n, np.asarray(f, dtype=float), self.t_min, self.t_max,
                                         self.t_ref, t)
        if status == K.OUT_OF_RANGE:
            raise InfeasibleError(
                f"wrench {np.round(f, 6).tolist()} has a component no cable tensions can produce "
                f"(residual {resid:.3g}); for this robot that is a moment about the shaft axis")
        if status == K.INFEASIBLE:
            raise InfeasibleError(f"wrench {np.round(f, 6).tolist()} outside the wrench-feasible set for "
                                  f"tensions in [{self.t_min:g}, {self.t_max:g}] N")
        return t


def wrench2tensions(f, A: np.ndarray, t_min: float, t_max: float, t_ref: float | None = None,
                    tol: float = 1e-9) -> np.ndarray:
    """(6,) cable tensions [N] that balance the external wrench f (6,) [N, N m]: A t + f = 0 (see
    `TensionSolver.solve`; raises InfeasibleError outside the wrench-feasible set)."""
    return TensionSolver(A, t_min, t_max, t_ref, tol).solve(f)


def tensions2wrench(t, A: np.ndarray) -> np.ndarray:
    """(6,) external wrench f = -A t balanced by cable tensions t (6,) [N] (eq 8)."""
    return -(A @ np.asarray(t, dtype=float))
