"""FBG force sensor calibration (seed 001 sec. 2.1.3-2.1.4, 3.1) from load steps at two or more temperatures.

The recording: a reference force (load cell) stepped up and down, the sensor's temperature, and the Bragg
shifts of FBG1 (strain-free, temperature only) and FBG2 (force and temperature), one row per sample or per
hold. Columns `force_N`, `temperature_C`, `dl1_pm`, `dl2_pm`, optionally `branch` (loading|unloading).

Model (linear in its parameters, solved by ordinary least squares; seed 001 eq 2-3):

    dl1 = kT1 (T - Tm) + c1
    dl2 = S F + s h(u) + kT2 (T - Tm) + c2     s in [-1, 1]: +1 after the force rose, -1 after it fell
    h(u) = sum_k a_k 4 u (1 - u) P_k(2u - 1),  u = (F - F_lo) / (F_hi - F_lo)

Tm is the mean temperature, c1 and c2 the shifts' zeros. The hysteresis is a loop: the loading - unloading
gap 2 h(u) [pm] is a function of the force, zero at the ends of the loop (F_lo, F_hi: the smallest and
largest reference force, where the branches meet) and largest in between; P_k are Legendre polynomials,
their number (3 to 6, HYSTERESIS_TERMS) chosen by the Bayesian information criterion (below). Three at least: the
arch, its tilt and its flattening (an arch alone misses a half sine's largest gap by 3 %, and the criterion,
on a noisy sensor, keeps to one term: a gap biased low by more than its standard error); more when the
data ask for them (a flat-topped or lopsided loop). Reported: the sensitivity S [pm/N], the temperature
sensitivities kT1, kT2 [pm/degC] and their ratio r = kT2 / kT1 (eq 3), the hysteresis as seed 001 states it
(sec. 3.1: 4.798 %): the MAXIMUM loading - unloading gap over the full-scale output S (F_hi - F_lo) [%], that
gap in pm and as a force, / S [N], and the force where it is largest; the RMSE of dl2 [pm], that of the
compensated shift dl2 - r dl1 [pm] and the force error it means, / S [N] (seed: 12.59 pm, 0.37 N). Standard
errors per equation from the AR(1)-prewhitened block sandwich (teleop.core.fit_statistics.
sandwich_covariance(..., "auto"): a grating's noise that wanders within a hold and across holds, a load
cell's error shared by a hold's samples, a loop shape the terms miss, are counted as the correlated errors
they are, where s^2 (X^T X)^-1 would count every sample as independent); r's by the
delta method, the maximum gap's through the gradient of 2 h at its maximum (the envelope theorem: the
place of the maximum moves to first order without changing it). The loop's terms are chosen by the BIC
on the effective size m / L (teleop.core.fit_statistics.bic), L the fullest loop's residual correlation
length; the errors of dl2's coefficients and of the gap are unconditional on that choice (averaged over
the 3-6 term fits with weights exp(-delta BIC / 2), each fit's variance plus its estimate's squared
distance from the kept one's: teleop.core.fit_statistics.model_averaged_covariance).

The loading state s is the catalogue's sensor-hysteresis switch (teleop.core.physics.hysteresis_offset with
h = 1) applied to the reference force, its half-width five times the force noise (so noise does not flip
it); a `branch` column, when given, is used instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from teleop.core.errors import InputError
from teleop.core.fit_statistics import bic, correlation_length, model_averaged_covariance, sandwich_covariance
from teleop.core.physics import hysteresis_offset
from teleop.core.sensors import FbgParams

BRANCH_WORDS = {"loading": 1.0, "unloading": -1.0, "+1": 1.0, "1": 1.0, "-1": -1.0}
HYSTERESIS_TERMS = (3, 6)  # fewest and most Legendre terms of the loop's half-gap h(u) (module docstring)
_U_GRID = np.linspace(0.0, 1.0, 1001)  # where the gap's maximum is looked for


@dataclass(frozen=True)
class FbgData:
    """force (n,) [N] reference, temperature (n,) [degC], dl1, dl2 (n,) [pm], s (n,) loading state, source."""

    force: np.ndarray
    temperature: np.ndarray
    dl1: np.ndarray
    dl2: np.ndarray
    s: np.ndarray
    source: str = ""


def loading_state(force: np.ndarray, width: float | None = None) -> np.ndarray:
    """(n,) loading state -1, 0 or +1 of a stepped force [N]: the sign of hysteresis_offset(F, 1, width).

    width [N]: the switch's half-width, default five times the force noise (1.4826 median |dF| / sqrt 2,
    most samples being holds), at least 1e-6 of the force range."""
    F = np.asarray(force, dtype=float)
    if width is None:
        noise = 1.4826 * float(np.median(np.abs(np.diff(F)))) / np.sqrt(2.0)
        width = max(5.0 * noise, 1e-6 * float(np.ptp(F)) + 1e-12)
    s = hysteresis_offset(F, 1.0, width)
    # the switch's value drifts inside [-1, 1] as noise nudges the play during a hold; its sign does not
    # (noise < 2 width): +/-1 once the force has first moved a full width, 0 (neutral) before
    moved = np.maximum.accumulate(np.abs(s) >= 1.0 - 1e-9)
    return np.where(moved, np.sign(s), 0.0)


@dataclass(frozen=True)
class FbgFit:
    """Result of `fit_fbg`: values and standard errors by name (units in the names), the fitted shifts
    (dl1, dl2) [pm] and the temperature levels found."""

    data: FbgData
    values: dict
    stderr: dict
    dl1_fit: np.ndarray
    dl2_fit: np.ndarray
    Tm: float
    coef: np.ndarray = None  # dl2's fitted coefficients: S, kT2, c2, then the loop's a_k [pm]

    @property
    def params(self) -> FbgParams:
        """The fitted sensor as the loop's FbgParams."""
        v = self.values
        return FbgParams(S_pm_N=v["S_pm_N"], r=v["r"], kT1_pm_C=v["kT1_pm_C"], kT2_pm_C=v["kT2_pm_C"],
                         noise_pm=v["rmse_compensated_pm"])

    def summary(self) -> dict:
        return {"kind": "fbg", "source": self.data.source, "values": self.values, "stderr": self.stderr,
                "samples": int(self.data.force.size)}


def loop_basis(u: np.ndarray, terms: int) -> np.ndarray:
    """(n, terms) shapes of the hysteresis loop's half-gap at the loop coordinate u (n,) in [0, 1]:
    4 u (1 - u) P_k(2u - 1), k < terms (P_k Legendre): each zero at both ends, the first the arch of height 1."""
    u = np.asarray(u, dtype=float)
    arch = 4.0 * u * (1.0 - u)
    return np.column_stack([arch * np.polynomial.legendre.Legendre.basis(k)(2.0 * u - 1.0) for k in range(terms)])


def _ols(X: np.ndarray, y: np.ndarray, block: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(beta, cov, residual) of y ~ X beta; cov the block-robust sandwich over blocks of `block` rows
    (default "auto": prewhitened, teleop.core.fit_statistics)."""
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ beta
    return beta, sandwich_covariance(X, r, "auto" if block is None else block), r


def _largest_gap(a: np.ndarray, cov_a: np.ndarray) -> tuple[float, float, int]:
    """(gap [pm], its standard error [pm], index into _U_GRID of where it is): the largest |loading -
    unloading| gap 2 |h(u)| of the loop with coefficients a (terms,) and their covariance (module docstring)."""
    shapes = loop_basis(_U_GRID, a.size)
    gaps = 2.0 * shapes @ a
    i = int(np.argmax(np.abs(gaps)))
    g = 2.0 * shapes[i]
    return float(abs(gaps[i])), float(np.sqrt(max(float(g @ cov_a @ g), 0.0))), i


def fit_fbg(data: FbgData, min_temperature_span_C: float = 2.0) -> FbgFit:
    """Sensitivity, hysteresis and temperature ratio of one dual-FBG sensor (module docstring)."""
    F, T = data.force, data.temperature
    where = data.source or "fbg calibration"
    if float(np.ptp(T)) < min_temperature_span_C:
        raise InputError(f"{where}: column 'temperature_C' spans {float(np.ptp(T)):.2f} degC; the temperature "
                         f"ratio r needs load steps at two or more temperatures (>= {min_temperature_span_C} degC apart)")
    if float(np.ptp(F)) <= 0:
        raise InputError(f"{where}: column 'force_N' is constant; the sensitivity needs load steps")
    Tm = float(np.mean(T))
    one = np.ones_like(F)
    b1, cov1, r1 = _ols(np.column_stack([T - Tm, one]), data.dl1)
    has_h = bool(np.any(data.s > 0.5) and np.any(data.s < -0.5))  # both branches seen
    F_lo, F_hi = float(np.min(F)), float(np.max(F))
    u = np.clip((F - F_lo) / (F_hi - F_lo), 0.0, 1.0)
    base = [F, T - Tm, one]
    b2, cov2, r2 = _ols(np.column_stack(base), data.dl2)
    terms = 0
    gap_pm, se_gap, F_at = 0.0, 0.0, float("nan")
    if has_h:  # the loop's shape: the number of terms the data ask for (BIC), HYSTERESIS_TERMS
        lo, hi = HYSTERESIS_TERMS
        fits = {m: _ols(np.column_stack(base + list((data.s[:, None] * loop_basis(u, m)).T)), data.dl2)
                for m in range(lo, hi + 1)}
        block = correlation_length(fits[hi][2])   # the fullest loop's residuals: the effective size m / L
        crit = {m: bic(fits[m][2], len(base) + m, block) for m in fits}
        terms = min(crit, key=crit.get)
        b2, _, r2 = fits[terms]
        # errors unconditional on the number of terms (teleop.core.fit_statistics.model_averaged_covariance,
        # weights exp(-delta BIC / 2)): the coefficients padded to the most terms, the gap averaged alike
        p = len(base) + hi
        est, covs, gaps = {}, {}, {}
        for m, (bm, cm, _) in fits.items():
            est[m] = np.zeros(p)
            est[m][:bm.size] = bm
            covs[m] = np.zeros((p, p))
            covs[m][:bm.size, :bm.size] = cm
            gaps[m] = _largest_gap(bm[len(base):], cm[len(base):, len(base):])
        cov2 = model_averaged_covariance(est, covs, crit, terms)
        best = min(crit.values())
        w = {m: float(np.exp(-(c - best) / 2.0)) for m, c in crit.items()}
        gap_pm, _, i_at = gaps[terms]
        se_gap = float(np.sqrt(sum(w[m] * (gaps[m][1] ** 2 + (gaps[m][0] - gap_pm) ** 2) for m in fits)
                               / sum(w.values())))
        F_at = F_lo + float(_U_GRID[i_at]) * (F_hi - F_lo)
    S, kT2, kT1 = float(b2[0]), float(b2[1]), float(b1[0])
    se_S, se_kT2, se_kT1 = (float(np.sqrt(max(c, 0.0))) for c in (cov2[0, 0], cov2[1, 1], cov1[0, 0]))
    if abs(kT1) < 1e-12 or S <= 0:
        raise InputError(f"{where}: FBG1 shows no temperature sensitivity or FBG2 no force sensitivity "
                         f"(kT1 = {kT1:.3g} pm/degC, S = {S:.3g} pm/N)")
    r = kT2 / kT1
    se_r = abs(r) * float(np.hypot(se_kT2 / kT2 if kT2 else 0.0, se_kT1 / kT1))
    span = F_hi - F_lo
    rmse = float(np.sqrt(np.mean(r2 ** 2)))
    # the temperature-compensated shift dl2 - r dl1 (eq 3) carries both gratings' errors
    rmse_comp = float(np.sqrt(np.mean((r2 - r * r1) ** 2)))
    values = {"S_pm_N": S, "kT1_pm_C": kT1, "kT2_pm_C": kT2, "r": r, "hysteresis_pm": gap_pm,
              "hysteresis_N": gap_pm / S, "hysteresis_percent": 100 * gap_pm / (S * span),
              "hysteresis_at_N": F_at, "hysteresis_terms": terms,
              "rmse_pm": rmse, "rmse_compensated_pm": rmse_comp, "force_error_N": rmse_comp / S,
              "rmse_dl1_pm": float(np.sqrt(np.mean(r1 ** 2))), "full_scale_N": span}
    stderr = {"S_pm_N": se_S, "kT1_pm_C": se_kT1, "kT2_pm_C": se_kT2, "r": se_r, "hysteresis_pm": se_gap,
              "hysteresis_N": se_gap / S, "hysteresis_percent": 100 * se_gap / (S * span)}
    return FbgFit(data, values, stderr, data.dl1 - r1, data.dl2 - r2, Tm, np.asarray(b2, dtype=float))


def plot_fbg_fit(fit: FbgFit):
    """Three panels like seed 001 Fig 4a/4b: FBG2's temperature-free shift against force (loading and
    unloading), both shifts against temperature at zero force, and the residuals against force."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    d, v = fit.data, fit.values
    fig, (ax, axT, axr) = plt.subplots(1, 3, figsize=(13, 5.2))
    temp_part = v["kT2_pm_C"] * (d.temperature - fit.Tm)
    y = d.dl2 - temp_part
    up, down = d.s >= 0, d.s < 0
    ax.plot(d.force[up], y[up], ".", ms=3, color="tab:red", label="loading")
    ax.plot(d.force[down], y[down], ".", ms=3, color="tab:blue", label="unloading")
    F_lo, F_hi = float(d.force.min()), float(d.force.max())
    Fg = np.linspace(F_lo, F_hi, 101)
    terms = int(v["hysteresis_terms"])
    half = loop_basis((Fg - F_lo) / (F_hi - F_lo), terms) @ fit.coef[3:3 + terms] if terms else 0.0 * Fg
    base = fit.dl2_fit - temp_part - v["S_pm_N"] * d.force - (
        d.s * (loop_basis((d.force - F_lo) / (F_hi - F_lo), terms) @ fit.coef[3:3 + terms]) if terms else 0.0)
    c0 = float(np.mean(base))
    line = v["S_pm_N"] * Fg + c0
    ax.plot(Fg, line, "k-", lw=1, label=f"S = {v['S_pm_N']:.2f} +/- {fit.stderr['S_pm_N']:.2f} pm/N")
    if terms:
        ax.plot(Fg, line + half, "k--", lw=0.8, label="loop model (loading, unloading)")
        ax.plot(Fg, line - half, "k--", lw=0.8)
        ax.plot([v["hysteresis_at_N"]] * 2, np.interp(v["hysteresis_at_N"], Fg, line) + np.array([-0.5, 0.5])
                * v["hysteresis_pm"], "m-", lw=2, label=f"largest gap: hysteresis {v['hysteresis_percent']:.2f} % "
                                                        f"of full scale")
    ax.set_xlabel("reference force [N]")
    ax.set_ylabel("FBG2 shift minus kT2 (T - Tm) [pm]")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    ax.set_title("force calibration (seed 001 Fig 4a)", fontsize=9)
    # each shift minus its fitted non-temperature part (zero, force, hysteresis): k (T - Tm) + residual
    rest1 = fit.dl1_fit - v["kT1_pm_C"] * (d.temperature - fit.Tm)
    rest2 = fit.dl2_fit - v["kT2_pm_C"] * (d.temperature - fit.Tm)
    axT.plot(d.temperature, d.dl1 - rest1, ".", ms=3, color="tab:green",
             label=f"FBG1 minus its zero, kT1 = {v['kT1_pm_C']:.2f} pm/degC")
    axT.plot(d.temperature, d.dl2 - rest2, ".", ms=3, color="tab:orange",
             label=f"FBG2 minus zero, force and hysteresis, kT2 = {v['kT2_pm_C']:.2f} pm/degC")
    axT.set_xlabel("temperature [degC]")
    axT.set_ylabel("Bragg shift about the mean temperature [pm]")
    axT.set_title(f"temperature: r = kT2/kT1 = {v['r']:.3f} +/- {fit.stderr['r']:.3f} (seed 001 Fig 4b)", fontsize=9)
    axT.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    axr.plot(d.force, d.dl2 - fit.dl2_fit, ".", ms=3, color="tab:blue", label="FBG2 residual")
    axr.plot(d.force, d.dl1 - fit.dl1_fit, ".", ms=3, color="tab:green", alpha=0.6, label="FBG1 residual")
    axr.axhline(0, color="k", lw=0.6)
    axr.set_xlabel("reference force [N]")
    axr.set_ylabel("residual [pm]")
    axr.set_title(f"RMSE FBG2 {v['rmse_pm']:.2f} pm; compensated {v['rmse_compensated_pm']:.2f} pm "
                  f"= {v['force_error_N']:.3f} N", fontsize=9)
    axr.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    fig.suptitle(f"teleop calibrate fbg: FBG calibration, seed 001 ({Path(d.source).name})", fontsize=10)
    fig.tight_layout()
    return fig
