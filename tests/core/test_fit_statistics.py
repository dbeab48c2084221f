"""teleop.core.fit_statistics: the residual variance and the parameters' covariance of a least-squares fit."""

import numpy as np

from teleop.core.fit_statistics import parameter_covariance, residual_variance, standard_errors


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
