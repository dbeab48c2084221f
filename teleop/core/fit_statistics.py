"""Statistics of a least-squares fit: the one definition of the residual variance and the parameters' covariance.

    s^2 = r . r / max(m - p, 1)          (m residuals, p fitted parameters)
    cov = s^2 (J^T J)^+                  (J (m, p) the residuals' Jacobian; pseudo-inverse, so a parameter
                                          the data do not determine gives a finite, large variance)

Read by the calibration fits (FSR, FBG, one sensor), the effect fits (teleop.core.physics.fit) and the
diagnosis's link fits. Successive samples of a recording are correlated, so these standard errors are a
floor unless the caller inflates s^2 (the diagnosis does, by m / n_eff).
"""

from __future__ import annotations

import numpy as np


def residual_variance(r, n_params: int) -> float:
    """s^2 = r . r / max(m - p, 1) of residuals r (m,) after fitting n_params parameters [unit of r squared]."""
    r = np.asarray(r, dtype=float)
    return float(r @ r) / max(r.size - int(n_params), 1)


def parameter_covariance(J, s2: float) -> np.ndarray:
    """(p, p) covariance s^2 (J^T J)^+ of the parameters of a fit with Jacobian J (m, p) and residual
    variance s2."""
    J = np.asarray(J, dtype=float)
    return np.linalg.pinv(J.T @ J) * s2


def standard_errors(cov) -> np.ndarray:
    """(p,) standard errors sqrt(diag(cov)), negative round-off clipped to 0."""
    return np.sqrt(np.clip(np.diag(cov), 0, None))
