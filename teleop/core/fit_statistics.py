"""Statistics of a least-squares fit: the one definition of the residual variance and the parameters' covariance.

    s^2 = r . r / max(m - p, 1)          (m residuals, p fitted parameters)
    cov = s^2 (J^T J)^+                  (J (m, p) the residuals' Jacobian; pseudo-inverse, so a parameter
                                          the data do not determine gives a finite, large variance)

Read by the calibration fits (FSR, FBG, one sensor), the effect fits (teleop.core.physics.fit) and the
diagnosis's link fits. Successive samples of a recording are correlated, so these standard errors are a
floor unless the caller inflates s^2 (the diagnosis does, by m / n_eff) or uses the residual-based
(sandwich) covariance below.

Model choice and errors that hold when the model's assumptions do not (the calibration fits):

    bic = n ln(r . r / m) + p ln n       (Schwarz's criterion: the smallest wins; a parameter must lower
                                          n ln s^2 by ln n to be kept; n = m for independent residuals,
                                          m / L for residuals correlated over blocks of L samples)
    aic = n ln(r . r / m) + 2 p          (Akaike's: the lighter penalty, for parameters whose omission biases)
    sandwich: cov = B (sum_g u_g u_g^T) B,  B = (J^T J)^+,  u_g = J_g^T r_g
        blocks of one residual, each scaled by 1 / (1 - h_i) (HC3, MacKinnon & White 1985: heteroscedastic
        noise, the leverage's shrinking of the residual undone), or contiguous blocks of residuals as long
        as their correlation (block-robust / cluster sandwich, scaled by G / (G - 1) (m - 1) / (m - p),
        CR1): coloured noise and a model that misses a slow shape leave correlated residuals, which the
        plain s^2 (J^T J)^-1 counts as independent; the blocks count them as what they are.
        With strongly correlated residuals (AR(1) rho 0.9 and up) blocks alone miss the correlation across
        their borders, so `block="auto"` prewhitens first
        (Andrews & Monahan 1992): rho the residuals' lag-one correlation, the blocks summed over
        v_t = u_t - rho u_(t-1) (u_t = J_t r_t), the result divided by (1 - rho)^2; the blocks then as
        long as the prewhitened residuals stay correlated, at least m^(1/3) samples (the usual bandwidth
        rule; tests/core/test_fit_statistics.py checks its coverage on AR(1) noise).
    model-averaged covariance of the kept fit (Buckland, Burnham & Augustin 1997; Burnham & Anderson 2002
        eq 6.12): sum_f w_f (C_f + (b_f - b_kept)(b_f - b_kept)^T), w_f = exp(-delta_f / 2) / sum, delta_f a
        candidate's criterion above the least: the errors unconditional on which candidate was kept (a
        slope is as uncertain as the question of its intercept moves it).
    correlation length: twice the residuals' integrated autocorrelation time (their normalised
        autocorrelation summed over lags until it first drops below zero), at least 1, at most m / 4.
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


def bic(r, n_params: int, block: float = 1.0) -> float:
    """Bayesian information criterion n ln(r . r / m) + p ln n of residuals r (m,) after fitting n_params
    parameters, n = m / block the effective number of independent samples when residuals stay correlated
    over `block` samples (module docstring; dimensionless, only differences between fits of the same data
    mean anything)."""
    r = np.asarray(r, dtype=float)
    m = r.size
    n = m / max(float(block), 1.0)
    return n * float(np.log(max(float(r @ r) / m, 1e-300))) + int(n_params) * float(np.log(n))


def aic(r, n_params: int, block: float = 1.0) -> float:
    """Akaike's criterion n ln(r . r / m) + 2 p on the effective size n = m / block (as `bic`): a parameter is
    kept when it lowers n ln s^2 by 2, a lighter penalty than ln n (a likelihood-ratio test at about 16 %):
    for a parameter whose wrongful omission biases the others by more than their standard error."""
    r = np.asarray(r, dtype=float)
    m = r.size
    n = m / max(float(block), 1.0)
    return n * float(np.log(max(float(r @ r) / m, 1e-300))) + 2.0 * int(n_params)


def correlation_length(r) -> int:
    """Block length [samples] over which residuals r (m,) in their recorded order stay correlated: twice
    their integrated autocorrelation time, at least 1, at most m // 4 (module docstring)."""
    r = np.asarray(r, dtype=float)
    m = r.size
    x = r - r.mean()
    v = float(x @ x)
    if m < 8 or v <= 0:
        return 1
    n = 1 << int(np.ceil(np.log2(2 * m)))
    f = np.fft.rfft(x, n)
    acf = np.fft.irfft(f * np.conj(f), n)[:m // 4] / v
    neg = np.flatnonzero(acf[1:] <= 0.0)
    stop = int(neg[0]) + 1 if neg.size else acf.size
    tau = 0.5 + float(np.sum(acf[1:stop]))
    return int(min(max(1, int(np.ceil(2.0 * tau))), max(1, m // 4)))


def sandwich_covariance(J, r, block: int | str | None = None) -> np.ndarray:
    """(p, p) residual-based covariance of the parameters of a least-squares fit with Jacobian J (m, p)
    and residuals r (m,) in their recorded order (module docstring). block: None or 1 for HC3 (independent
    rows, any variance each); L > 1 for contiguous blocks of L rows (correlated residuals); "auto" for the
    AR(1)-prewhitened block sandwich with its own block length (coloured noise, a slow misfit)."""
    J = np.asarray(J, dtype=float)
    r = np.asarray(r, dtype=float)
    m, p = J.shape
    B = np.linalg.pinv(J.T @ J)
    if block is None or (block != "auto" and int(block) <= 1):
        h = np.einsum("ij,jk,ik->i", J, B, J)
        u = J * (r / np.maximum(1.0 - h, 1e-3))[:, None]
        return B @ (u.T @ u) @ B
    u = J * r[:, None]
    rho = 0.0
    if block == "auto":
        x = r - r.mean()
        xx = float(x @ x)
        rho = float(np.clip(float(x[1:] @ x[:-1]) / xx, 0.0, 0.98)) if xx > 0 and m > 2 else 0.0
        u = u[1:] - rho * u[:-1]
        e = r[1:] - rho * r[:-1]
        block = max(correlation_length(e), int(np.ceil(u.shape[0] ** (1.0 / 3.0))))
    n = u.shape[0]
    L = min(int(block), max(1, n // 2))       # two blocks at least
    g = np.arange(n) // L
    G = int(g[-1]) + 1
    U = np.zeros((G, p))
    np.add.at(U, g, u)
    scale = G / (G - 1) * (m - 1) / max(m - p, 1) / (1.0 - rho) ** 2
    return B @ (U.T @ U) @ B * scale


def model_averaged_covariance(estimates: dict, covariances: dict, criteria: dict, kept) -> np.ndarray:
    """(p, p) covariance of the kept candidate's parameters unconditional on the choice (module docstring).

    estimates, covariances, criteria: by candidate, its (p,) parameters (a parameter the candidate does not
    fit: 0), their (p, p) covariance (0 there) and its information criterion; kept: the key of the one kept."""
    best = min(criteria.values())
    w = {f: float(np.exp(-(c - best) / 2.0)) for f, c in criteria.items()}
    total = sum(w.values())
    b0 = np.asarray(estimates[kept], dtype=float)
    cov = np.zeros((b0.size, b0.size))
    for f, b in estimates.items():
        d = np.asarray(b, dtype=float) - b0
        cov += w[f] / total * (np.asarray(covariances[f], dtype=float) + np.outer(d, d))
    return cov
