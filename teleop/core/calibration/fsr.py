"""FSR calibration from a step protocol (seed 000 sec. 2.2, eq 2, Fig 7): one quintic per branch.

The protocol: weights added in steps (loading) then removed (unloading), the conductance read at each
hold, repeated (the seed: 0-600 g in 50 g steps, three times, averaged). The CSV gives one row per hold:
`tension_N`, `conductance_uS` and optionally `branch` (loading|unloading|+1|-1); without `branch` the
rows' order tells it (a row above the previous one is loading, below it unloading, equal keeps the branch).

Seed 000 fits a quintic per branch; the data do not always need one. Per branch the candidates are the
polynomials of degree 1 to `degree` (5), each with and without the conductance at zero tension c0
(an unloaded FSR conducts nothing: c0 = 0 unless the data say otherwise), fitted by ordinary least squares
in the scaled tension t / t_max (conditioning), the one of least Akaike criterion on the effective size
(teleop.core.fit_statistics.aic, m / L with L the fullest candidate's residual correlation length along
the protocol) kept: Akaike's lighter penalty because a term wrongly left out bends the curve by more than
its error. Terms left out are 0 with standard error 0; the coefficients are written as the quintic's six
(the calibration file keeps its form). Standard errors: each candidate's covariance the AR(1)-prewhitened
block sandwich (teleop.core.fit_statistics.sandwich_covariance(..., "auto"): noise that grows with the
reading, drift along the protocol), the kept one's unconditional on the choice
(teleop.core.fit_statistics.model_averaged_covariance). Also reported: the residuals and their size in
newtons (residual / local slope dG/dt).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.polynomial import polynomial as P

from teleop.core.errors import InputError
from teleop.core.fit_statistics import (aic, correlation_length, model_averaged_covariance, sandwich_covariance,
                                        standard_errors)
from teleop.core.sensors import LOADING, UNLOADING, FsrCalibration, FsrCalibrationData

BRANCH_WORDS = {"loading": LOADING, "unloading": UNLOADING, "+1": LOADING, "1": LOADING, "-1": UNLOADING}
BRANCHES = ((LOADING, "loading"), (UNLOADING, "unloading"))


def branches_from_order(tension: np.ndarray) -> np.ndarray:
    """(n,) +1/-1 per row of a step protocol: above the previous row loading, below unloading, equal keeps
    the previous branch (the first row: loading)."""
    d = np.sign(np.diff(np.asarray(tension, dtype=float)))
    b = np.empty(len(tension))
    b[0] = LOADING
    for k, s in enumerate(d, start=1):
        b[k] = b[k - 1] if s == 0 else s
    return b


@dataclass(frozen=True)
class FsrFit:
    """Result of `fit_fsr`: the calibration, per branch the coefficients' standard errors [S / N^k], the
    residuals [S] per row, their RMS [S] and the RMS in tension [N]."""

    data: FsrCalibrationData
    cal: FsrCalibration
    stderr: dict
    residual: np.ndarray
    rms_S: dict
    rms_N: dict
    cov: dict = None     # per branch name the (6, 6) covariance of the coefficients [S^2 / N^(j+k)]
    terms: dict = None   # per branch name the powers of tension kept (the others 0)

    def summary(self) -> dict:
        """JSON-ready fitted values with uncertainty."""
        out = {"kind": "fsr", "source": self.data.source, "t_max_N": self.cal.t_max}
        for br, name in BRANCHES:
            coefs = self.cal.loading if br == LOADING else self.cal.unloading
            out[name] = {"coef_S": list(coefs), "stderr_S": list(self.stderr[name]),
                         "rms_residual_uS": self.rms_S[name] * 1e6, "rms_residual_N": self.rms_N[name],
                         "rows": int(np.count_nonzero(self.data.branch == br)),
                         "powers": list(self.terms[name]), "covariance_S2": np.asarray(self.cov[name]).tolist()}
        mid = 0.5 * self.cal.t_max
        gap = self.cal.reading(mid, UNLOADING) - self.cal.reading(mid, LOADING)
        out["branch_gap_uS_at_mid"] = float(gap) * 1e6
        return out


def _branch_fit(t: np.ndarray, g: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray, tuple]:
    """(coefficients (degree + 1,) [S / N^k], their covariance, the powers kept) of one branch's readings
    g (m,) [S] at tensions t (m,) [N] in the recorded order (module docstring)."""
    scale = float(np.max(np.abs(t))) or 1.0
    V = P.polyvander(t / scale, degree)
    to_S = 1.0 / scale ** np.arange(degree + 1)          # coefficient of (t / scale)^k -> of t^k
    fits = {}
    for d in range(1, degree + 1):
        for c0 in (False, True):
            powers = tuple(range(0 if c0 else 1, d + 1))
            if len(powers) >= t.size:
                continue
            X = V[:, powers]
            beta, *_ = np.linalg.lstsq(X, g, rcond=None)
            r = g - X @ beta
            b = np.zeros(degree + 1)
            b[list(powers)] = beta * to_S[list(powers)]
            cov = np.zeros((degree + 1, degree + 1))
            cov[np.ix_(powers, powers)] = sandwich_covariance(X, r, "auto") * np.outer(to_S[list(powers)],
                                                                                          to_S[list(powers)])
            fits[powers] = (b, cov, r)
    fullest = max(fits, key=len)
    block = correlation_length(fits[fullest][2])
    crit = {f: aic(r, len(f), block) for f, (b, c, r) in fits.items()}
    kept = min(crit, key=crit.get)
    cov = model_averaged_covariance({f: v[0] for f, v in fits.items()}, {f: v[1] for f, v in fits.items()},
                                    crit, kept)
    drop = [k for k in range(degree + 1) if k not in kept]
    cov[drop, :] = 0.0
    cov[:, drop] = 0.0
    return fits[kept][0], cov, kept


def fit_fsr(data: FsrCalibrationData, degree: int = 5) -> FsrFit:
    """Per branch the polynomial (degree <= 5, seed 000 eq 2) the data ask for, with standard errors and
    residuals (module docstring)."""
    coefs, stderr, cov, terms = {}, {}, {}, {}
    for br, name in BRANCHES:
        m = data.branch == br
        if np.count_nonzero(m) < 3:
            raise InputError(f"{data.source or 'calibration'}: {np.count_nonzero(m)} {name} rows, need at least 3")
        coefs[name], cov[name], terms[name] = _branch_fit(data.tension[m], data.reading[m], degree)
        stderr[name] = tuple(standard_errors(cov[name]).tolist())
    cal = FsrCalibration(loading=tuple(coefs["loading"].tolist()), unloading=tuple(coefs["unloading"].tolist()),
                         t_max=float(np.max(data.tension)))
    residual = data.reading - cal.reading(data.tension, data.branch)
    rms_S, rms_N = {}, {}
    for br, name in BRANCHES:
        m = data.branch == br
        t, r = data.tension[m], residual[m]
        rms_S[name] = float(np.sqrt(np.mean(r ** 2)))
        slope = np.abs(P.polyval(t, P.polyder(coefs[name])))
        # a residual in tension: what the inverse map would read wrong at this row
        rms_N[name] = float(np.sqrt(np.mean((r / np.maximum(slope, 1e-12)) ** 2)))
    return FsrFit(data, cal, stderr, residual, rms_S, rms_N, cov, terms)


def plot_fsr_fit(fit: FsrFit):
    """Two panels: the points and quintics like seed 000 Fig 7, and the residuals [uS] against tension."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    fig, (ax, axr) = plt.subplots(2, 1, figsize=(9.5, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1.4]})
    t = np.linspace(0.0, fit.cal.t_max, 300)
    d = fit.data
    for br, name in BRANCHES:
        color = "tab:red" if br == LOADING else "tab:purple"
        m = d.branch == br
        ax.plot(d.tension[m], d.reading[m] * 1e6, "o", ms=4, color=color, label=f"{name} steps")
        ax.plot(t, fit.cal.reading(t, br) * 1e6, "-", color=color,
                label=f"{name} quintic (RMS {fit.rms_S[name] * 1e6:.2f} uS = {fit.rms_N[name]:.3f} N)")
        axr.plot(d.tension[m], fit.residual[m] * 1e6, "o", ms=4, color=color, label=name)
    axr.axhline(0.0, color="k", lw=0.6)
    ax.set_ylabel("conductance [uS]")
    ax.set_title(f"teleop calibrate fsr: FSR calibration, seed 000 eq 2 ({Path(d.source).name})", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside: off the data
    axr.set_xlabel("tension [N]")
    axr.set_ylabel("residual [uS]")
    axr.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig
