"""Vectorised per-sample recursions: play (clamp) operators and first-order affine recurrences.

Hysteretic and stateful models need `y_k = f_k(y_{k-1})` for every sample. Two families cover all the
effects in this package, and both compose in closed form, so the whole signal is solved by a
Hillis-Steele prefix scan in ceil(log2 n) vectorised numpy passes instead of a Python loop:

- clamp maps  f_k(y) = min(max(y, a_k), b_k)          (a_k <= b_k): the play operator;
  f_2(f_1(y)) = clamp(y, clip(a_1, a_2, b_2), clip(b_1, a_2, b_2));
- affine maps f_k(y) = alpha_k y + beta_k:           first-order filters, Dahl, the SLS branch;
  f_2(f_1(y)) = alpha_2 alpha_1 y + (alpha_2 beta_1 + beta_2).

Both are exact up to floating-point reassociation (relative differences ~1e-15 versus the loop).
"""

from __future__ import annotations

import numpy as np

from teleop.kernels.friction import clamp as _clamp_kernel


def clamp_scan(y0: float, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """y (n,): y_k = min(max(y_{k-1}, lo_k), hi_k) with y_{-1} = y0; needs lo <= hi elementwise."""
    A = np.array(lo, dtype=float, copy=True)
    B = np.array(hi, dtype=float, copy=True)
    n = A.shape[0]
    s = 1
    while s < n:
        a, b = A[s:], B[s:]
        # composite(k) = f_k..f_{k-s+1} o composite(k-s): clamp the earlier bounds into the later ones
        newA = np.minimum(np.maximum(A[:-s], a), b)
        newB = np.minimum(np.maximum(B[:-s], a), b)
        A[s:] = newA
        B[s:] = newB
        s *= 2
    return np.minimum(np.maximum(y0, A), B)


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
#: has one home, the compiled kernel teleop.kernels.friction.clamp that the capstan kernels use too
clamp_step = _clamp_kernel
