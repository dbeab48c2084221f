"""Generic least-squares identification of any registered effect's parameters (scipy least_squares).

Free parameters are mapped to [0, 1] (linearly, or in log for `ParamSpec.log`), so one bounded problem
fits any effect; several starts (the data-driven guess, then seeded perturbations of it) guard against
bad initial guesses, and the lowest cost wins. Standard errors come from the Jacobian at the optimum:
cov = s^2 (J^T J)^-1 (teleop.core.fit_statistics), s^2 = SSR / (m - p), mapped back through d value / d u.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np
from scipy.optimize import least_squares

from teleop.core.errors import InputError
from teleop.core.fit_statistics import parameter_covariance
from teleop.core.physics.base import Effect, Signals, get_effect


@dataclass(frozen=True)
class FitResult:
    """Outcome of `fit`: all parameters (fixed ones included), standard errors of the free ones (fixed: 0),
    residual RMSE [output unit] on the fitted samples, sample count m, success flag, evaluations, message."""

    effect: str
    params: dict
    stderr: dict
    rmse: float
    m: int
    success: bool
    nfev: int
    message: str

    def predict(self, signals: Signals) -> np.ndarray:
        """The fitted effect's output for `signals`."""
        return get_effect(self.effect).apply(signals, self.params)

    def plot(self, signals: Signals, y, ax=None):
        """Measured vs fitted output over time on `ax` (a new Agg figure when None); returns the axes."""
        if ax is None:
            import matplotlib  # heavy: loaded only to draw
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt  # heavy: loaded only to draw
            _, ax = plt.subplots(figsize=(8, 3))
        ax.plot(signals.t, y, ".", ms=2, label="measured")
        ax.plot(signals.t, self.predict(signals), "-", lw=1, label=f"{self.effect} fit (rmse {self.rmse:.3g})")
        ax.set_xlabel("t [s]")
        ax.legend(loc="best")
        return ax


def rmse(effect: Effect | str, signals: Signals, y, params: Mapping[str, float], mask=None) -> float:
    """Root-mean-square of effect(signals, params) - y over `mask` (all samples when None)."""
    effect = get_effect(effect) if isinstance(effect, str) else effect
    r = effect.apply(signals, params) - np.asarray(y, dtype=float)
    if mask is not None:
        r = r[np.asarray(mask)]
    return float(np.sqrt(np.mean(r * r)))


def fit(effect: Effect | str, signals: Signals, y, fixed: Mapping[str, float] | None = None,
        guess: Mapping[str, float] | None = None, mask=None, n_starts: int = 4, seed: int = 0,
        max_nfev: int = 200, general: bool = False) -> FitResult:
    """Identify `effect`'s free parameters so that effect.apply(signals, p) matches y (n,).

    fixed: parameters held at given values; guess: starting values tried first (the effect's
    data-driven guess is tried as well); mask: (n,) bool or index array of samples that enter the
    residual (the model always runs over the whole signal, so stateful effects see their full history:
    use it for held-out validation);
    n_starts: number of starts (guesses, then seeded perturbations of the first); seed: for those;
    general: also fit the parameters of the effect's general form (ParamSpec.shape; else held at their
    defaults, the plain form).
    """
    effect = get_effect(effect) if isinstance(effect, str) else effect
    y = np.asarray(y, dtype=float)
    if y.shape != signals.t.shape or not np.isfinite(y).all():
        raise InputError(f"fit '{effect.name}': target must be {signals.t.shape} finite numbers, got {y.shape}")
    signals.require(effect.inputs, f"fit '{effect.name}'")
    fixed = dict(fixed or {})
    effect.check(fixed)
    if not general:
        fixed = {**effect.plain_form(), **fixed}
    free = [p for p in effect.params if p.name not in fixed]
    sel = np.arange(y.size) if mask is None else np.asarray(mask)
    if sel.dtype == bool:
        sel = np.flatnonzero(sel)
    m = int(sel.size)
    if m <= len(free):
        raise InputError(f"fit '{effect.name}': {m} samples for {len(free)} free parameters")

    g_data = effect.initial_guess(signals, y)
    g_data.update(fixed)
    g = effect.check(dict(g_data, **(guess or {})))
    g.update(fixed)
    scale = max(float(np.std(y[sel])), 1e-12)

    def unpack(u):
        p = dict(g)
        for spec, ui in zip(free, u):
            p[spec.name] = spec.from_unit(float(ui))
        return p

    def resid(u):
        r = (effect.simulate(signals, unpack(u))[sel] - y[sel]) / scale
        return np.nan_to_num(r, nan=1e6, posinf=1e6, neginf=-1e6)

    if not free:
        p = effect.check(g)
        return FitResult(effect.name, p, {k: 0.0 for k in p}, rmse(effect, signals, y, p, sel), m, True, 1,
                         "all parameters fixed")

    u0 = np.array([spec.to_unit(spec.clip(g[spec.name])) for spec in free])
    starts = [u0]
    if guess:  # a caller's guess may be poor: the data-driven guess is always tried as well
        starts.append(np.array([spec.to_unit(spec.clip(g_data[spec.name])) for spec in free]))
    rng = np.random.default_rng(seed)
    starts += [u0 + rng.normal(0.0, 0.2, u0.shape) for _ in range(max(n_starts - len(starts), 0))]
    best = None
    for s in starts:
        s = np.clip(s, 1e-6, 1 - 1e-6)
        res = least_squares(resid, s, bounds=(0.0, 1.0), x_scale="jac", diff_step=1e-5, max_nfev=max_nfev)
        if best is None or res.cost < best.cost:
            best = res

    p = effect.check(unpack(best.x))
    dof = max(m - len(free), 1)
    s2 = 2.0 * best.cost * scale * scale / dof
    # cov_u = s^2 (J^T J)^-1 with J in residual-units of y / scale
    cov_u = parameter_covariance(best.jac, s2) / (scale * scale)
    stderr = {k: 0.0 for k in p}
    for i, spec in enumerate(free):
        stderr[spec.name] = float(abs(spec.dvalue_du(p[spec.name])) * np.sqrt(max(cov_u[i, i], 0.0)))
    return FitResult(effect.name, p, stderr, rmse(effect, signals, y, p, sel), m, bool(best.success),
                     int(best.nfev), str(best.message))
