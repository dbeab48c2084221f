"""Per-sample recursions over whole signals: play (clamp) operators and first-order affine recurrences.

Hysteretic and stateful models need `y_k = f_k(y_{k-1})` for every sample. Two families cover all the
effects in this package:

- clamp maps  f_k(y) = min(max(y, a_k), b_k)          (a_k <= b_k): the play operator; run by the compiled
  loop `teleop.core.kernels.friction.clamp_run` over the one clamp kernel (exact: min and max do not round;
  the diagnosis's fits call it tens of thousands of times);
- affine maps f_k(y) = alpha_k y + beta_k:           first-order filters, the SLS branch; these compose
  in closed form, f_2(f_1(y)) = alpha_2 alpha_1 y + (alpha_2 beta_1 + beta_2), so the whole signal is
  solved by a Hillis-Steele prefix scan in ceil(log2 n) vectorised numpy passes (exact up to
  floating-point reassociation, relative differences ~1e-15 versus the loop).
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.friction import clamp as _clamp_kernel
from teleop.core.kernels.friction import clamp_run as _clamp_run


def clamp_scan(y0, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """y (n, ...): y_k = min(max(y_{k-1}, lo_k), hi_k) with y_{-1} = y0 along the first axis (trailing axes,
    e.g. (n, 6) cables, are independent recursions; y0 a scalar or broadcast to them); needs lo <= hi."""
    lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
    n = lo.shape[0]
    L, H = lo.reshape(n, -1), hi.reshape(n, -1)
    Y0 = np.broadcast_to(np.asarray(y0, dtype=float), lo.shape[1:]).reshape(-1)
    out = np.empty((n, L.shape[1]))
    for j in range(L.shape[1]):
        out[:, j] = _clamp_run(float(Y0[j]), np.ascontiguousarray(L[:, j]), np.ascontiguousarray(H[:, j]),
                               np.empty(n))
    return out.reshape(lo.shape)


def affine_scan(y0: float, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """y (n,): y_k = alpha_k y_{k-1} + beta_k with y_{-1} = y0."""
    P = np.array(alpha, dtype=float, copy=True)
    Q = np.array(beta, dtype=float, copy=True)
    n = P.shape[0]
    s = 1
    while s < n:
        p = P[s:]
        # (P_k, Q_k) <- (P_k P_{k-s}, P_k Q_{k-s} + Q_k)
        newQ = p * Q[:-s] + Q[s:]
        newP = p * P[:-s]
        Q[s:] = newQ
        P[s:] = newP
        s *= 2
    return P * y0 + Q


def play(y0: float, u: np.ndarray, r) -> np.ndarray:
    """Play operator (backlash) of half-width r >= 0 (scalar or (n,)): y_k = clamp(y_{k-1}, u_k - r, u_k + r)."""
    u = np.asarray(u, dtype=float)
    return clamp_scan(y0, u - r, u + r)


#: one sample of `clamp_scan` (scalar): clamp_step(y, lo, hi) = min(max(y, lo), hi); the play operator's step
#: has one home, the compiled kernel teleop.core.kernels.friction.clamp that the capstan kernels use too
clamp_step = _clamp_kernel
