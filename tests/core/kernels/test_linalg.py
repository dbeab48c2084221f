"""The 6 x 6 elimination kernels against numpy's LAPACK on the robot's own matrices (identities, tolerances)."""

import numpy as np

from teleop.core.geometry import default_geometry
from teleop.core.kernels.linalg import horner, interp1, lu_complete, lu_null_vector, lu_particular, solve_into
from teleop.core.kinematics import structure_matrix

G = default_geometry()


def test_null_vector_and_minimum_norm_solution_of_the_structure_matrix():
    rng = np.random.default_rng(0)
    for _ in range(50):
        q = np.r_[rng.uniform(-0.004, 0.004, 3), 0.0, rng.uniform(-0.1, 0.1, 2)]
        A = structure_matrix(q, G)
        LU, p, qq = np.empty((6, 6)), np.empty(6, np.int64), np.empty(6, np.int64)
        rank = lu_complete(A, LU, p, qq, 1e-9)
        assert rank == 5 == np.linalg.matrix_rank(A)
        n = lu_null_vector(LU, qq, rank, np.empty(6))
        Vn = np.linalg.svd(A)[2][5]
        np.testing.assert_allclose(n, Vn * np.sign(Vn.sum()), atol=1e-12)  # unit, positive sum: pretension
        f = -A @ rng.uniform(0.5, 5.0, 6)
        x = np.empty(6)
        assert lu_particular(LU, p, qq, rank, -f, x) < 1e-12
        np.testing.assert_allclose(A @ x, -f, atol=1e-12)
        t_p = x - (x @ n) * n  # the minimum-norm solution is the one orthogonal to the null space
        np.testing.assert_allclose(t_p, -np.linalg.pinv(A) @ f, atol=1e-10)


def test_solve_and_horner():
    rng = np.random.default_rng(1)
    for _ in range(20):
        M, b = rng.normal(size=(5, 5)) + 5 * np.eye(5), rng.normal(size=5)
        np.testing.assert_allclose(solve_into(M, b, np.empty(5)), np.linalg.solve(M, b), rtol=1e-12)
    c = rng.normal(size=6)
    s = 0.37
    assert horner(c, s) == np.polynomial.polynomial.polyval(s, c)


def test_interp1_is_numpy_interp_bit_for_bit():
    """One x at a time, as the FSR branch lag calls it: numpy's numbers, at the grid points, between them,
    outside the table, for NaN and infinities, on the lag's uniform table and on an irregular one with
    repeated values."""
    rng = np.random.default_rng(1)
    grids = [(np.linspace(0.0, 6.0, 1024), rng.random(1024)),
             (np.cumsum(rng.uniform(0.01, 1.0, 50)), np.repeat(rng.normal(size=25), 2))]
    for xp, fp in grids:
        xs = np.concatenate([rng.uniform(xp[0] - 1, xp[-1] + 1, 20000), xp, [np.nan, np.inf, -np.inf]])
        got = np.array([interp1(float(x), xp, fp) for x in xs])
        assert np.array_equal(got, np.interp(xs, xp, fp), equal_nan=True)
