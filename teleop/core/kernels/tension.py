"""Kernel of the closed-form tension distribution for a one-dimensional null space (teleop.core.tension).

A t + f = 0 with t = t_p + lambda n: t_p = -A^+ f the minimum-norm particular solution, n the null
direction (both from one LU factorisation of A, kernels.linalg); lambda is the value closest to t_ref (least squares: n . (t_ref - t_p) / n . n) clipped to the
interval where every tension lies in [t_min, t_max]; the tensions are finally clipped to that range.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels.jit import njit
from teleop.core.kernels.linalg import lu_complete, lu_null_vector, lu_particular

OK, OUT_OF_RANGE, INFEASIBLE = 0, 1, 2  # status codes of `null1_tensions`


@njit
def null1_terms(A, tol=1e-9):
    """(LU (n, n), p, q (n,) its complete-pivoting factors, null direction nv (n,) unit with a positive sum,
    is_null1: rank n - 1 at relative tolerance tol, else the rest is not meaningful) of A (n, n)."""
    n = A.shape[0]
    LU = np.empty((n, n))
    p = np.empty(n, dtype=np.int64)
    q = np.empty(n, dtype=np.int64)
    rank = lu_complete(A, LU, p, q, tol)
    nv = np.zeros(n)
    if rank == n - 1:
        lu_null_vector(LU, q, rank, nv)
    return LU, p, q, nv, rank == n - 1


@njit
def null1_tensions(LU, p, q, A, nv, f, t_min, t_max, t_ref, out):
    """Tensions (out, (n,) [N]) balancing the wrench f (n,): (status, residual). t_p = -A^+ f is the
    solution of A t = -f orthogonal to the null direction (a particular solution from the factors, minus
    its null component). Status OUT_OF_RANGE: f has a component A cannot produce (residual |A t_p + f| above
    1e-7 max(1, |f|)); INFEASIBLE: no lambda keeps every tension in [t_min, t_max]. `out` is written only
    when the status is OK."""
    n = nv.shape[0]
    t_p = np.empty(n)
    lu_particular(LU, p, q, n - 1, -f, t_p)
    c = 0.0
    for i in range(n):
        c += t_p[i] * nv[i]
    for i in range(n):
        t_p[i] -= c * nv[i]
    resid = 0.0
    fmax = 1.0
    for i in range(n):
        acc = f[i]
        for j in range(n):
            acc += A[i, j] * t_p[j]
        resid = max(resid, abs(acc))
        fmax = max(fmax, abs(f[i]))
    if resid > 1e-7 * fmax:
        return OUT_OF_RANGE, resid
    lo, hi = -math.inf, math.inf
    num = 0.0
    nn = 0.0
    for i in range(n):
        ni, ti = nv[i], t_p[i]
        num += ni * (t_ref - ti)
        nn += ni * ni
        if abs(ni) < 1e-12:
            if not (t_min - 1e-9 <= ti <= t_max + 1e-9):
                lo, hi = math.inf, -math.inf
            continue
        a, b = (t_min - ti) / ni, (t_max - ti) / ni
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    if lo > hi + 1e-12:
        return INFEASIBLE, resid
    lam = num / nn
    lam = lo if lam < lo else (hi if lam > hi else lam)
    for i in range(n):
        out[i] = min(t_max, max(t_min, t_p[i] + lam * nv[i]))
    return OK, resid


@njit
def tensions_batch(f, A, t_min, t_max, t_ref, out, status):
    """Per sample k of wrenches f (m, n) and structure matrices A (m, n, n): out[k] tensions [N] and
    status[k] (OK, OUT_OF_RANGE, INFEASIBLE, or -1: not a one-dimensional null space)."""
    for k in range(f.shape[0]):
        LU, p, q, nv, ok = null1_terms(A[k])
        if not ok:
            status[k] = -1
            continue
        status[k] = null1_tensions(LU, p, q, A[k], nv, f[k], t_min, t_max, t_ref, out[k])[0]
    return out
