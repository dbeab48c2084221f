"""FSR calibration from a step protocol (seed 000 sec. 2.2, eq 2, Fig 7): one quintic per branch.

The protocol: weights added in steps (loading) then removed (unloading), the conductance read at each
hold, repeated (the seed: 0-600 g in 50 g steps, three times, averaged). The CSV gives one row per hold:
`tension_N`, `conductance_uS` and optionally `branch` (loading|unloading|+1|-1); without `branch` the
rows' order tells it (a row above the previous one is loading, below it unloading, equal keeps the branch).

The quintics are fitted by `teleop.core.sensors.fit_fsr_calibration` (the one home of that fit); this module
adds what a calibration report needs: the coefficients' standard errors (ordinary least squares,
cov = s^2 (V^T V)^-1 with V the power-basis Vandermonde matrix, teleop.core.fit_statistics), the residuals,
and their size in newtons (residual / local slope dG/dt).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.polynomial import polynomial as P

from teleop.core.fit_statistics import parameter_covariance, residual_variance, standard_errors
from teleop.core.sensors import LOADING, UNLOADING, FsrCalibration, FsrCalibrationData, fit_fsr_calibration

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

    def summary(self) -> dict:
        """JSON-ready fitted values with uncertainty."""
        out = {"kind": "fsr", "source": self.data.source, "t_max_N": self.cal.t_max}
        for br, name in BRANCHES:
            coefs = self.cal.loading if br == LOADING else self.cal.unloading
            out[name] = {"coef_S": list(coefs), "stderr_S": list(self.stderr[name]),
                         "rms_residual_uS": self.rms_S[name] * 1e6, "rms_residual_N": self.rms_N[name],
                         "rows": int(np.count_nonzero(self.data.branch == br))}
        mid = 0.5 * self.cal.t_max
        gap = self.cal.reading(mid, UNLOADING) - self.cal.reading(mid, LOADING)
        out["branch_gap_uS_at_mid"] = float(gap) * 1e6
        return out


def fit_fsr(data: FsrCalibrationData, degree: int = 5) -> FsrFit:
    """Quintics per branch (seed 000 eq 2) with standard errors and residuals."""
    cal = fit_fsr_calibration(data, degree)
    residual = data.reading - cal.reading(data.tension, data.branch)
    stderr, rms_S, rms_N = {}, {}, {}
    for br, name in BRANCHES:
        m = data.branch == br
        t, r = data.tension[m], residual[m]
        V = P.polyvander(t, degree)
        cov = parameter_covariance(V, residual_variance(r, degree + 1))
        stderr[name] = tuple(standard_errors(cov).tolist())
        rms_S[name] = float(np.sqrt(np.mean(r ** 2)))
        coefs = cal.loading if br == LOADING else cal.unloading
        slope = np.abs(P.polyval(t, P.polyder(coefs)))
        # a residual in tension: what the inverse map would read wrong at this row
        rms_N[name] = float(np.sqrt(np.mean((r / np.maximum(slope, 1e-12)) ** 2)))
    return FsrFit(data, cal, stderr, residual, rms_S, rms_N)


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
