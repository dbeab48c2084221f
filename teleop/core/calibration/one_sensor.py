"""One sensor for all cables (seed 001 sec. 2.2, eq 7): Kp, Kr and the transition widths of one
instrumented cable, from its proximal (motor) and distal (tip) force.

The recording is interchange CSV (docs/formats.md) with `motor_force_N` and `tip_force_N` (or N m), or any
layout through a column map (`--map`, e.g. the shipped `mrdlab`). The fit is
`teleop.core.sensors.fit_proximal_distal` (line fits of the pulling and releasing phases, then least squares
of the play-operator prediction); this module adds standard errors (teleop.core.fit_statistics:
cov = s^2 (J^T J)^-1, J by central differences of the same prediction) and the transition widths: at a
distal force Fd the motor must change its force by w(Fd) = |(Fd - bp) / Kp - (Fd - br) / Kr| while the tip
stays put (the flat phases of seed 001 Fig 2b), reported at the record's top and bottom turns. Successive
samples of a recording are correlated, so the standard errors are a floor.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from teleop.core.errors import InputError
from teleop.core.fit_statistics import parameter_covariance, residual_variance, standard_errors
from teleop.core.sensors import ProximalDistalModel, fit_proximal_distal

NAMES = ("Kp", "Kr", "bp", "br")


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

    @property
    def predicted(self) -> np.ndarray:
        return self.model.distal(self.Fp, self.Fd[0])

    def summary(self) -> dict:
        m = self.model
        return {"kind": "one-sensor", "source": self.source, "unit": self.unit,
                "values": {"Kp": m.Kp, "Kr": m.Kr, "bp": m.bp, "br": m.br, "rmse": self.rmse},
                "stderr": self.stderr, "transition_width": self.widths, "samples": int(self.Fp.size)}


def fit_one_sensor(Fp, Fd, unit: str = "N", source: str = "") -> OneSensorFit:
    """Fit seed 001 eq 7 to one cable's proximal Fp (n,) and distal Fd (n,) forces [unit]."""
    Fp = np.asarray(Fp, dtype=float)
    Fd = np.asarray(Fd, dtype=float)
    try:
        model = fit_proximal_distal(Fp, Fd)
    except InputError as exc:
        raise InputError(f"{source or 'one-sensor'}: {exc}") from None
    z = np.array([model.Kp, model.Kr, model.bp, model.br])

    def predict(zz):
        return ProximalDistalModel(*zz).distal(Fp, Fd[0])

    r = predict(z) - Fd
    scale = float(np.ptp(Fp)) or 1.0
    steps = np.array([1e-6, 1e-6, 1e-6 * scale, 1e-6 * scale]) * np.maximum(1.0, np.abs(z))
    J = np.column_stack([(predict(z + h * e) - predict(z - h * e)) / (2 * h)
                         for h, e in zip(steps, np.eye(4))])
    cov = parameter_covariance(J, residual_variance(r, len(NAMES)))
    stderr = dict(zip(NAMES, standard_errors(cov).tolist()))
    widths = {}
    for name, level in (("top", float(np.max(Fd))), ("bottom", float(np.min(Fd)))):
        w = float(transition_width(model, level))
        g = np.array([(float(transition_width(ProximalDistalModel(*(z + h * e)), level))
                       - float(transition_width(ProximalDistalModel(*(z - h * e)), level))) / (2 * h)
                      for h, e in zip(steps, np.eye(4))])
        widths[name] = {"distal": level, "width": w, "stderr": float(np.sqrt(max(g @ cov @ g, 0.0)))}
    return OneSensorFit(Fp, Fd, model, stderr, widths, float(np.sqrt(np.mean(r ** 2))), unit, source)


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
    ax.set_title(f"transition widths: {w['top']['width']:.3g} {u} at the top, "
                 f"{w['bottom']['width']:.3g} {u} at the bottom", fontsize=9)
    ax.legend(fontsize=7)
    k = np.arange(fit.Fp.size)
    axr.plot(k, fit.predicted - fit.Fd, lw=0.6, color="tab:blue", label="prediction - measured")
    axr.axhline(0, color="k", lw=0.6)
    axr.set_xlabel("sample")
    axr.set_ylabel(f"distal force residual [{u}]")
    axr.legend(fontsize=7)
    fig.suptitle(f"one sensor for all cables, seed 001 eq 7 ({Path(fit.source).name})", fontsize=10)
    fig.tight_layout()
    return fig
