"""Small dense linear algebra for the kernels (6 x 6 at most): Gaussian elimination written out.

Why by hand: numba's np.linalg (LAPACK) costs more per call at this size in allocation and dispatch
than the arithmetic; the loop and the simulated robot call these every tick.

- `solve_into(M, b, x)`: x = M^-1 b from the complete-pivoting factors (M, b left unchanged).
- `lu_complete(A, LU, p, q)`: P A Q = L U with complete pivoting (rows p, columns q); its rank.
- `lu_null_vector(LU, q, rank, out)`: the null vector of a matrix of rank n - 1 from its factors.
- `lu_particular(LU, p, q, rank, b, out)`: a solution of A x = b with the free coordinates 0; returns the
  residual of the rows beyond the rank (0 when b is in the range of A).
- `horner(c, s)`: the power series sum c_j s^j (numpy.polynomial.polynomial.polyval's order of operations).
- `interp1(x, xp, fp)`: np.interp at one float x (numpy's formula and edge cases, as numba's facsimile of
  numpy's arr_interp): numba's np.interp boxes a scalar x into arrays, which costs more than the
  interpolation; the simulated FSRs interpolate six times a reading.
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.jit import njit


@njit
def lu_complete(A, LU, p, q, tol):
    """Factor A (n, n) into LU (n, n) (unit-lower multipliers below the diagonal, U on and above) with row
    order p and column order q (int arrays (n,)) by complete pivoting; rank = pivots above tol * max|A|."""
    n = A.shape[0]
    LU[:, :] = A
    for i in range(n):
        p[i] = i
        q[i] = i
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(A[i, j]))
    rank = 0
    for k in range(n):
        bi, bj, best = k, k, -1.0
        for i in range(k, n):
            for j in range(k, n):
                if abs(LU[i, j]) > best:
                    bi, bj, best = i, j, abs(LU[i, j])
        if best <= tol * scale:
            break
        rank += 1
        if bi != k:
            for j in range(n):
                LU[k, j], LU[bi, j] = LU[bi, j], LU[k, j]
            p[k], p[bi] = p[bi], p[k]
        if bj != k:
            for i in range(n):
                LU[i, k], LU[i, bj] = LU[i, bj], LU[i, k]
            q[k], q[bj] = q[bj], q[k]
        for i in range(k + 1, n):
            m = LU[i, k] / LU[k, k]
            LU[i, k] = m
            for j in range(k + 1, n):
                LU[i, j] -= m * LU[k, j]
    return rank


@njit
def lu_null_vector(LU, q, rank, out):
    """Unit null vector (out (n,)) of a rank-(n-1) matrix from its `lu_complete` factors, sign: positive sum."""
    n = LU.shape[0]
    y = np.zeros(n)
    y[rank] = 1.0  # the free coordinate (rank = n - 1)
    for i in range(rank - 1, -1, -1):
        acc = -LU[i, rank]
        for j in range(i + 1, rank):
            acc -= LU[i, j] * y[j]
        y[i] = acc / LU[i, i]
    norm = 0.0
    total = 0.0
    for j in range(n):
        norm += y[j] * y[j]
        total += y[j]
    s = (1.0 if total >= 0.0 else -1.0) / np.sqrt(norm)
    for j in range(n):
        out[q[j]] = s * y[j]
    return out


@njit
def lu_particular(LU, p, q, rank, b, out):
    """out (n,): x with A x = b from the factors, free coordinates 0; returns max |residual| of the rows
    beyond the rank (b's component outside the range of A, in the eliminated rows)."""
    n = LU.shape[0]
    c = np.empty(n)
    for i in range(n):
        acc = b[p[i]]
        for j in range(min(i, rank)):
            acc -= LU[i, j] * c[j]
        c[i] = acc
    resid = 0.0
    for i in range(rank, n):
        resid = max(resid, abs(c[i]))
    z = np.zeros(n)
    for i in range(rank - 1, -1, -1):
        acc = c[i]
        for j in range(i + 1, rank):
            acc -= LU[i, j] * z[j]
        z[i] = acc / LU[i, i]
    for j in range(n):
        out[q[j]] = z[j]
    return resid


@njit
def horner(c, s):
    """sum_j c[j] s^j by Horner's rule from the highest coefficient (c (k,), k >= 1)."""
    acc = c[c.shape[0] - 1]
    for m in range(c.shape[0] - 2, -1, -1):
        acc = c[m] + acc * s
    return acc


@njit
def solve_into(M, b, x):
    """x (n,) = M^-1 b for a nonsingular M (n, n) (complete-pivoting factors; M, b left unchanged); returns x."""
    n = b.shape[0]
    LU = np.empty((n, n))
    p = np.empty(n, dtype=np.int64)
    q = np.empty(n, dtype=np.int64)
    lu_particular(LU, p, q, lu_complete(M, LU, p, q, 0.0), b, x)
    return x


@njit
def interp1(x, xp, fp):
    """np.interp(x, xp, fp) for one float x (xp (k,) increasing, fp (k,), k >= 2): fp[0] left of xp[0], fp[-1]
    from xp[-1] on, NaN for NaN; else slope (x - xp[j]) + fp[j] on the segment xp[j] <= x < xp[j + 1] (fp[j]
    where x == xp[j]; a NaN from an infinite slope retried from the right end, as numpy)."""
    k = xp.shape[0]
    if x != x:
        return x
    if x < xp[0]:
        return fp[0]
    if x >= xp[k - 1]:
        return fp[k - 1]
    lo, hi = 0, k - 1  # xp[lo] <= x < xp[hi]
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if xp[mid] <= x:
            lo = mid
        else:
            hi = mid
    if xp[lo] == x:
        return fp[lo]
    slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo])
    y = slope * (x - xp[lo]) + fp[lo]
    if y != y:
        y = slope * (x - xp[lo + 1]) + fp[lo + 1]
        if y != y and fp[lo] == fp[lo + 1]:
            y = fp[lo]
    return y
