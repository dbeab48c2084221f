"""teleop.core.fit_statistics: the residual variance and the parameters' covariance of a least-squares fit, the
residual-based (sandwich) covariance, the information criteria and the model-averaged covariance."""

import numpy as np
import pytest

from teleop.core.fit_statistics import (aic, bic, correlation_length, model_averaged_covariance, parameter_covariance,
                                        residual_variance, sandwich_covariance, standard_errors)


def test_straight_line_fit_has_the_textbook_slope_variance():
    rng = np.random.default_rng(0)
    x = np.linspace(0.0, 2.0, 40)
    y = 0.3 + 1.7 * x + rng.normal(0.0, 0.05, x.size)
    X = np.column_stack([np.ones_like(x), x])
    beta = np.linalg.lstsq(X, y, rcond=None)[0]
    r = y - X @ beta
    s2 = residual_variance(r, 2)
    assert s2 == float(r @ r) / (x.size - 2)
    se = standard_errors(parameter_covariance(X, s2))
    # simple regression: var(slope) = s^2 / sum (x - mean x)^2, var(intercept) = s^2 sum x^2 / (m sum (x - mean)^2)
    sxx = float(np.sum((x - x.mean()) ** 2))
    assert np.isclose(se[1], np.sqrt(s2 / sxx), rtol=1e-10)
    assert np.isclose(se[0], np.sqrt(s2 * float(np.sum(x * x)) / (x.size * sxx)), rtol=1e-10)


def test_an_undetermined_parameter_gives_finite_errors_and_no_degrees_of_freedom_gives_one():
    X = np.column_stack([np.ones(5), np.ones(5)])      # two parameters the data cannot tell apart
    cov = parameter_covariance(X, 1.0)
    assert np.all(np.isfinite(cov))
    assert residual_variance(np.array([1.0, 1.0]), 5) == 2.0   # m - p clipped to 1


def test_hc3_sandwich_is_the_textbook_formula_and_follows_heteroscedastic_noise():
    rng = np.random.default_rng(1)
    x = np.linspace(0.0, 1.0, 30)
    X = np.column_stack([np.ones_like(x), x])
    y = 1.0 + 2.0 * x + rng.normal(0.0, 0.1, x.size) * (0.02 + 3.0 * x * x)   # noise grows with x
    beta = np.linalg.lstsq(X, y, rcond=None)[0]
    r = y - X @ beta
    B = np.linalg.inv(X.T @ X)
    h = np.einsum("ij,jk,ik->i", X, B, X)
    meat = (X * (r / (1 - h))[:, None]).T @ (X * (r / (1 - h))[:, None])
    np.testing.assert_allclose(sandwich_covariance(X, r), B @ meat @ B, rtol=1e-12)
    # the plain formula spreads the noise evenly, the sandwich puts it where it is: small at x = 0 (the
    # intercept's error falls), large at x = 1 (the slope's rises)
    plain = standard_errors(parameter_covariance(X, residual_variance(r, 2)))
    se = standard_errors(sandwich_covariance(X, r))
    assert se[0] < 0.9 * plain[0] and se[1] > 1.1 * plain[1]


def test_prewhitened_sandwich_covers_a_slope_in_strongly_coloured_noise():
    """A line through AR(1) noise (rho 0.95): s^2 (X^T X)^-1 holds the slope far less often than 95 %, the
    prewhitened block sandwich about 95 % (200 draws: 90-99 %)."""
    rng = np.random.default_rng(7)
    n, draws, rho = 800, 200, 0.95
    x = np.sin(2 * np.pi * 3 * np.arange(n) / n)
    X = np.column_stack([np.ones(n), x])
    e = rng.normal(0.0, np.sqrt(1 - rho ** 2), (draws, n))
    noise = np.empty_like(e)
    noise[:, 0] = rng.normal(0.0, 1.0, draws)
    for k in range(1, n):
        noise[:, k] = rho * noise[:, k - 1] + e[:, k]
    Y = 1.0 + 2.0 * x + noise
    beta = np.linalg.lstsq(X, Y.T, rcond=None)[0]          # (2, draws)
    R = Y - (X @ beta).T
    z_plain, z_auto = [], []
    for d in range(draws):
        z_plain.append((beta[1, d] - 2.0) / standard_errors(parameter_covariance(X, residual_variance(R[d], 2)))[1])
        z_auto.append((beta[1, d] - 2.0) / standard_errors(sandwich_covariance(X, R[d], "auto"))[1])
    assert np.mean(np.abs(z_plain) < 1.96) < 0.5
    assert 0.90 <= np.mean(np.abs(z_auto) < 1.96) <= 0.99
    assert correlation_length(R[0]) > 10 and correlation_length(rng.normal(size=500)) <= 3


def test_criteria_and_model_averaging():
    rng = np.random.default_rng(3)
    r = rng.normal(0.0, 1.0, 100)
    assert bic(r, 3) - bic(r, 2) == pytest.approx(np.log(100))
    assert aic(r, 3) - aic(r, 2) == pytest.approx(2.0)
    # on the effective size: 100 samples correlated over 4 count as 25
    assert bic(r, 2, block=4) == pytest.approx(25 * np.log(float(r @ r) / 100) + 2 * np.log(25))
    # one candidate far ahead: its own covariance; two tied: their mean plus half the spread between them
    est = {"a": np.array([1.0, 0.0]), "b": np.array([1.2, 0.5])}
    cov = {"a": np.eye(2) * 0.01, "b": np.eye(2) * 0.04}
    np.testing.assert_allclose(model_averaged_covariance(est, cov, {"a": 0.0, "b": 100.0}, "a"), cov["a"], atol=1e-12)
    tied = model_averaged_covariance(est, cov, {"a": 0.0, "b": 0.0}, "a")
    d = est["b"] - est["a"]
    np.testing.assert_allclose(tied, 0.5 * (cov["a"] + cov["b"] + np.outer(d, d)))
