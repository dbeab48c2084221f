"""A generic sparse-regression peer: PySINDy's libraries and STLSQ optimiser, scored on the same held-out split.

Two forms, both fitted on the fit part and scored on the held-out part, the better one reported:

- static: y = Theta(w) xi, w = the link's inputs (input, drive position, its smoothed velocity and the
  velocity's sign, load, temperature, bend) through a polynomial (degree <= 3) + Fourier library, sparse
  coefficients by STLSQ; a memoryless map, like a regression a user would try first.
- free run: dy/dt = Theta(y, w) xi (pysindy.SINDy with the inputs as control), integrated from the measured
  output at the held-out start with the recorded inputs; an output-error score like the physics models'.

The physics models must fit at least as well as this peer: a named model that a generic polynomial beats
has not found the physics. Fitting runs at about PEER_HZ (the peer sees the same samples, decimated).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from teleop.core.physics.links import LinkData, clean_motion

PEER_HZ = 100.0
DEGREE = 3
THRESHOLDS = (1e-3, 1e-2, 3e-2, 1e-1)   # STLSQ thresholds tried (on standardised features); best on the fit part


def _inputs(d: LinkData) -> tuple[np.ndarray, list[str]]:
    cols, names = [d.u], ["u"]
    if d.x is not None:
        _, v = clean_motion(d.x, d.t, d.backward)
        scale = max(float(np.percentile(np.abs(v), 99)), 1e-300)
        cols += [v / scale, np.sign(v)]
        names += ["v", "sign_v"]
        if d.link.input != d.link.drive:
            cols.append(d.x)
            names.append("x")
    for name in ("temperature", "theta"):
        a = getattr(d, name)
        if a is not None and float(np.ptp(a)) > 0:
            cols.append(a)
            names.append(name)
    return np.column_stack(cols), names


def _library():
    import pysindy as ps  # heavy: loaded only for the sparse-regression peer (diagnose --sindy)
    return ps.PolynomialLibrary(degree=DEGREE) + ps.FourierLibrary(n_frequencies=1)


def _standardise(W: np.ndarray, fit: np.ndarray) -> np.ndarray:
    mu, sd = W[fit].mean(0), W[fit].std(0)
    sd[sd == 0] = 1.0
    out = (W - mu) / sd
    return out


def static_rmse(d: LinkData, fit_idx: slice, hold_idx: slice) -> float:
    """Held-out RMSE of the static sparse regression (output units)."""
    import pysindy as ps  # heavy: loaded only for the sparse-regression peer (diagnose --sindy)

    W, _ = _inputs(d)
    stride = max(1, int(round(1.0 / (PEER_HZ * float(np.median(np.diff(d.t)))))))
    fit = np.arange(fit_idx.start or 0, fit_idx.stop, stride)
    Z = _standardise(W, fit)
    lib = _library()
    lib.fit(Z[fit])
    T = lib.transform(Z)
    ysd = max(float(np.std(d.y[fit])), 1e-300)
    ym = float(np.mean(d.y[fit]))
    best, best_fit = math.inf, math.inf
    for thr in THRESHOLDS:
        opt = ps.STLSQ(threshold=thr, alpha=1e-6)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            opt.fit(T[fit], ((d.y[fit] - ym) / ysd)[:, None])
        pred = ym + ysd * (T @ opt.coef_.T)[:, 0]
        rf = float(np.sqrt(np.mean((pred[fit] - d.y[fit]) ** 2)))
        if rf < best_fit:
            best_fit = rf
            best = float(np.sqrt(np.mean((pred[hold_idx] - d.y[hold_idx]) ** 2)))
    return best


def free_run_rmse(d: LinkData, fit_idx: slice, hold_idx: slice) -> float:
    """Held-out RMSE of dy/dt = Theta(y, w) xi integrated over the held-out part (explicit Euler at the
    decimated rate, clamped to the fit part's range widened by its span); inf if it cannot be fitted."""
    import pysindy as ps  # heavy: loaded only for the sparse-regression peer (diagnose --sindy)

    W, _ = _inputs(d)
    dt = float(np.median(np.diff(d.t)))
    stride = max(1, int(round(1.0 / (PEER_HZ * dt))))
    idx = np.arange(0, d.n, stride)
    k_fit = int(np.searchsorted(idx, fit_idx.stop))
    t = d.t[idx]
    ysd = max(float(np.std(d.y[fit_idx])), 1e-300)
    ym = float(np.mean(d.y[fit_idx]))
    y = (d.y[idx] - ym) / ysd
    Z = _standardise(W, np.arange(fit_idx.start or 0, fit_idx.stop))[idx]
    best = math.inf
    for thr in THRESHOLDS[2:3]:
        try:
            model = ps.SINDy(feature_library=_library(), optimizer=ps.STLSQ(threshold=thr, alpha=1e-6))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model.fit(y[:k_fit, None], t=t[:k_fit], u=Z[:k_fit])
        except (ValueError, np.linalg.LinAlgError):
            continue
        lib = model.feature_library
        coef = model.coefficients()
        yk = float(y[k_fit - 1])
        out = np.empty(idx.size - k_fit)
        h = float(np.median(np.diff(t)))
        for j, k in enumerate(range(k_fit, idx.size)):
            feats = lib.transform(np.concatenate([[yk], Z[k - 1]])[None, :])
            yk = min(max(yk + h * float((feats @ coef.T)[0, 0]), -4.0), 4.0)
            out[j] = yk
        r = (ym + ysd * out) - d.y[idx[k_fit:]]
        best = min(best, float(np.sqrt(np.mean(r * r))))
    return best


def sindy_rmse(d: LinkData, fit_idx: slice, hold_idx: slice) -> dict:
    """{"static", "free_run", "best"} held-out RMSEs of the PySINDy peer (output units)."""
    s = static_rmse(d, fit_idx, hold_idx)
    try:
        f = free_run_rmse(d, fit_idx, hold_idx)
    except Exception:   # a diverging or ill-posed free-run fit is the peer's loss, not an error of ours
        f = math.inf
    return {"static": s, "free_run": f if math.isfinite(f) else None, "best": min(s, f)}
