"""One sensor for all cables (seed 001 sec. 2.2, eq 7): Kp, Kr and the transition widths of one
instrumented cable, from its proximal (motor) and distal (tip) force.

The recording is interchange CSV (docs/formats.md) with `motor_force_N` and `tip_force_N` (or N m), or any
layout through a column map (`--map`, e.g. the shipped `mrdlab`).

The fit:
1. Phases. The play-operator model (ProximalDistalModel.distal) is fitted by least squares to all samples,
   from `teleop.core.sensors.fit_proximal_distal`'s line fits (or, when its phase detection finds too few
   samples, `fit_proximal_distal_origin`'s ratios), driven by the proximal force seen through a centred
   moving average of n / 200 samples: each sample is then pulling (on the line Kp Fp + bp), releasing (on
   Kr Fp + br) or flat. The flats are left out of what follows: their level is the proximal force's extreme
   at the turn, where its noise is rectified (the play keeps the largest excursion), and a phase decided by
   the raw proximal force would count as "on the line" exactly the samples whose noise set a record.
2. Model. On the line samples eq 7 is linear: Fd = Kp Fp + bp pulling, Kr Fp + br releasing. Four models
   (MODELS): the slopes alone (lines through the origin, eqs 4-6), with bp, with br, with both (eq 7 as
   written), each by ordinary least squares; the one of least Akaike criterion on the effective size m / L
   is kept (teleop.core.fit_statistics.aic, L the fullest model's residual correlation length: samples
   counted one by one would keep every intercept). Akaike's and not Schwarz's penalty: an intercept wrongly
   left out moves the slope by more than its error (the forces are far from zero). An intercept left out
   is 0 with standard error 0 (`model` in the summary names the free parameters).
3. Errors. Each candidate's covariance is the AR(1)-prewhitened block sandwich
   (teleop.core.fit_statistics.sandwich_covariance(..., "auto")): it holds with coloured sensor noise,
   where s^2 (X^T X)^-1 counts correlated samples as independent. The kept model's covariance is
   unconditional on the choice (Buckland, Burnham & Augustin 1997): the candidates' covariances plus
   their estimates' outer distances from the kept one, weighted by exp(-delta AIC / 2) (`aic` in the
   summary): a slope is as uncertain as the question of its intercept moves it.
4. Transition widths: at a distal force Fd the motor must change its force by
   w(Fd) = |(Fd - bp) / Kp - (Fd - br) / Kr| while the tip stays put (the flat phases of seed 001 Fig 2b),
   reported at the record's top and bottom turns, their errors by the delta method.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scipy.optimize import least_squares

from teleop.core.errors import InputError
from teleop.core.fit_statistics import (aic, correlation_length, model_averaged_covariance, sandwich_covariance,
                                        standard_errors)
from teleop.core.sensors import ProximalDistalModel, fit_proximal_distal, fit_proximal_distal_origin

NAMES = ("Kp", "Kr", "bp", "br")
#: the candidate models, by their free parameters (the others 0); the last is eq 7 as written
MODELS = (("Kp", "Kr"), ("Kp", "Kr", "bp"), ("Kp", "Kr", "br"), ("Kp", "Kr", "bp", "br"))


def transition_width(model: ProximalDistalModel, Fd) -> np.ndarray:
    """Proximal force change [N] across the flat transition at distal force Fd [N] (module docstring)."""
    Fd = np.asarray(Fd, dtype=float)
    return np.abs((Fd - model.bp) / model.Kp - (Fd - model.br) / model.Kr)


@dataclass(frozen=True)
class OneSensorFit:
    """Result of `fit_one_sensor`: model, standard errors by name, widths at the turns, residual RMSE."""

    Fp: np.ndarray
    Fd: np.ndarray
    model: ProximalDistalModel
    stderr: dict
    widths: dict
    rmse: float
    unit: str
    source: str
    free: tuple = NAMES          # the kept model's free parameters (MODELS)
    block: int = 1               # the fullest model's residual correlation length [samples] (the criterion's m / L)
    criterion: dict = None       # each candidate's AIC on the effective size, by "+".join(free)

    @property
    def predicted(self) -> np.ndarray:
        return self.model.distal(self.Fp, self.Fd[0])

    def summary(self) -> dict:
        m = self.model
        return {"kind": "one-sensor", "source": self.source, "unit": self.unit,
                "values": {"Kp": m.Kp, "Kr": m.Kr, "bp": m.bp, "br": m.br, "rmse": self.rmse},
                "stderr": self.stderr, "transition_width": self.widths, "samples": int(self.Fp.size),
                "model": list(self.free), "block_samples": self.block, "aic": self.criterion}


def _start(Fp: np.ndarray, Fd: np.ndarray, where: str) -> np.ndarray:
    """Kp, Kr, bp, br to start the least squares from (module docstring)."""
    try:
        m = fit_proximal_distal(Fp, Fd)
    except InputError:
        try:
            m = fit_proximal_distal_origin(Fp, Fd)
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
    return np.array([m.Kp, m.Kr, m.bp, m.br])


def _moving_average(x: np.ndarray, w: int) -> np.ndarray:
    """Centred moving average of w samples (odd), the window shortened at the ends."""
    if w <= 1:
        return x
    c = np.r_[0.0, np.cumsum(x)]
    k = np.arange(x.size)
    lo, hi = np.maximum(k - w // 2, 0), np.minimum(k + w // 2 + 1, x.size)
    return (c[hi] - c[lo]) / (hi - lo)


def fit_one_sensor(Fp, Fd, unit: str = "N", source: str = "") -> OneSensorFit:
    """Fit seed 001 eq 7 to one cable's proximal Fp (n,) and distal Fd (n,) forces [unit]: the model the
    data ask for and block-robust standard errors (module docstring)."""
    Fp = np.asarray(Fp, dtype=float)
    Fd = np.asarray(Fd, dtype=float)
    where = source or "one-sensor"
    if Fp.shape != Fd.shape or Fp.ndim != 1 or Fp.size < 20:
        raise InputError(f"{where}: proximal and distal force must be 1-D series of the same length (>= 20)")
    z0 = _start(Fp, Fd, where)
    scale = float(np.ptp(Fp)) or 1.0
    # which phase each sample is in: the play model (least squares over all samples) driven by the proximal
    # force seen through a centred moving average (its noise would decide the phase: the play's clip
    # keeps the largest excursion, so a sample counted "on the line" would be one whose noise set a record)
    Fp_phase = _moving_average(Fp, max(1, Fp.size // 200) | 1)

    def predict(zz, x=Fp_phase):
        return ProximalDistalModel(*zz).distal(x, Fd[0])

    z_all = least_squares(lambda zz: predict(zz) - Fd, z0, x_scale=0.1).x
    m = ProximalDistalModel(*z_all)
    pred = predict(z_all)
    tol = 1e-9 * (1.0 + float(np.max(np.abs(pred))))
    pull = np.abs(pred - (m.Kp * Fp_phase + m.bp)) <= tol
    release = (np.abs(pred - (m.Kr * Fp_phase + m.br)) <= tol) & ~pull
    if min(np.count_nonzero(pull), np.count_nonzero(release)) < 5:
        raise InputError(f"{where}: the record needs both pulling and releasing phases (the distal force "
                         f"following the proximal one up and down), found {np.count_nonzero(pull)} and "
                         f"{np.count_nonzero(release)} samples")
    rows = pull | release
    # on the lines the model is linear: Fd = Kp Fp + bp pulling, Kr Fp + br releasing (the measured Fp)
    columns = {"Kp": Fp * pull, "Kr": Fp * release, "bp": pull * 1.0, "br": release * 1.0}
    fits = {}
    for free in MODELS:
        X = np.column_stack([columns[k][rows] for k in free])
        beta, *_ = np.linalg.lstsq(X, Fd[rows], rcond=None)
        z = np.zeros(4)
        z[[NAMES.index(k) for k in free]] = beta
        fits[free] = (z, Fd[rows] - X @ beta, X)
    block = correlation_length(fits[NAMES][1])
    crit = {free: aic(r, len(free), block) for free, (z, r, X) in fits.items()}
    free = min(crit, key=crit.get)
    z, r, X = fits[free]
    idx = [NAMES.index(k) for k in free]
    model = ProximalDistalModel(*map(float, z))
    steps = np.array([1e-6, 1e-6, 1e-6 * scale, 1e-6 * scale]) * np.maximum(1.0, np.abs(z))
    # errors unconditional on the choice (module docstring); a dropped intercept is 0 exactly
    covs = {}
    for f, (zf, rf, Xf) in fits.items():
        i_f = [NAMES.index(k) for k in f]
        covs[f] = np.zeros((4, 4))
        covs[f][np.ix_(i_f, i_f)] = sandwich_covariance(Xf, rf, "auto")
    cov = model_averaged_covariance({f: v[0] for f, v in fits.items()}, covs, crit, free)
    drop = [k for k in range(4) if k not in idx]
    cov[drop, :] = 0.0
    cov[:, drop] = 0.0
    stderr = dict(zip(NAMES, standard_errors(cov).tolist()))
    widths = {}
    for name, level in (("top", float(np.max(Fd))), ("bottom", float(np.min(Fd)))):
        w = float(transition_width(model, level))
        g = np.array([(float(transition_width(ProximalDistalModel(*(z + h * e)), level))
                       - float(transition_width(ProximalDistalModel(*(z - h * e)), level))) / (2 * h)
                      for h, e in zip(steps, np.eye(4))])
        widths[name] = {"distal": level, "width": w, "stderr": float(np.sqrt(max(g @ cov @ g, 0.0)))}
    rmse = float(np.sqrt(np.mean((model.distal(Fp, Fd[0]) - Fd) ** 2)))
    return OneSensorFit(Fp, Fd, model, stderr, widths, rmse, unit, source,
                        tuple(free), int(block), {"+".join(f): float(c) for f, c in crit.items()})


def plot_one_sensor_fit(fit: OneSensorFit):
    """Two panels: the proximal-distal profile with the pulling and releasing lines (seed 001 Fig 2b / 5),
    and the distal force and its prediction's residual over the samples."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    m, u = fit.model, fit.unit
    fig, (ax, axr) = plt.subplots(1, 2, figsize=(12, 4.5))
    ax.plot(fit.Fp, fit.Fd, ".", ms=2, color="0.6", label="measured")
    ax.plot(fit.Fp, fit.predicted, "-", lw=0.8, color="tab:blue", label=f"eq 7 play model (RMSE {fit.rmse:.3g} {u})")
    Fg = np.linspace(float(fit.Fp.min()), float(fit.Fp.max()), 400)
    lo, hi = float(fit.Fd.min()), float(fit.Fd.max())
    for K, b, color, label in ((m.Kp, m.bp, "tab:red", f"pulling: Kp = {m.Kp:.4f} +/- {fit.stderr['Kp']:.4f}"),
                               (m.Kr, m.br, "tab:green", f"releasing: Kr = {m.Kr:.4f} +/- {fit.stderr['Kr']:.4f}")):
        line = K * Fg + b
        inside = (line >= lo) & (line <= hi)          # each line over the distal range it explains
        ax.plot(Fg[inside], line[inside], "--", color=color, label=label)
    ax.set_xlabel(f"proximal (motor) force [{u}]")
    ax.set_ylabel(f"distal (tip) force [{u}]")
    w = fit.widths
    for name, marker in (("top", "v"), ("bottom", "^")):  # each width drawn where it is measured
        Fd_turn = w[name]["distal"]
        ends = [(Fd_turn - m.bp) / m.Kp, (Fd_turn - m.br) / m.Kr]
        ax.plot(ends, [Fd_turn] * 2, "-", color="m", lw=1.2, alpha=0.8, marker=marker, ms=5,
                label="transition widths (proximal change at the turns)" if name == "top" else None)
    ax.set_title(f"transition widths: {w['top']['width']:.3g} {u} at the top (distal {w['top']['distal']:.3g} {u}), "
                 f"{w['bottom']['width']:.3g} {u} at the bottom (distal {w['bottom']['distal']:.3g} {u})", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2)  # below: off the data
    k = np.arange(fit.Fp.size)
    axr.plot(k, fit.predicted - fit.Fd, lw=0.6, color="tab:blue", label="prediction - measured")
    axr.axhline(0, color="k", lw=0.6)
    axr.set_xlabel("sample index [-]")
    axr.set_ylabel(f"distal force residual [{u}]")
    axr.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18))
    fig.suptitle(f"teleop calibrate one-sensor: one sensor for all cables, seed 001 eq 7 "
                 f"({Path(fit.source).name})", fontsize=10)
    fig.tight_layout()
    return fig
