"""A generic regression peer: a linear ARX model fitted by least squares, scored in free run.

y_k = sum_i a_i y_k-i + sum_j b_j . w_k-j + c, with w the link's input signals (input, drive and its
velocity, load); fitted on the fit part at about PEER_HZ, then simulated from the held-out start using its
own past outputs (an output-error score, like the physics models, which never see the measured output).
"""

from __future__ import annotations

import numpy as np

from teleop.core.physics.links import LinkData

PEER_HZ = 100.0
NA, NB = 2, 3


def _inputs(d: LinkData) -> np.ndarray:
    cols = [d.u]
    if d.x is not None:
        cols += [d.x, np.gradient(d.x, d.t)]
    if d.load is not None:
        cols.append(d.load)
    if d.temperature is not None:
        cols.append(d.temperature)
    return np.column_stack(cols)


def arx_rmse(d: LinkData, fit_idx: slice, hold_idx: slice) -> float:
    """Held-out free-run RMSE of an ARX(NA, NB) model fitted on fit_idx (output units)."""
    stride = max(1, int(round(1.0 / (PEER_HZ * float(np.median(np.diff(d.t)))))))
    W = _inputs(d)
    mu, sd = W[fit_idx].mean(0), W[fit_idx].std(0) + 1e-300
    W = ((W - mu) / sd)[::stride]
    y = d.y[::stride]
    k_fit = (fit_idx.stop - (fit_idx.start or 0)) // stride
    lag = max(NA, NB)
    rows = []
    for k in range(lag, k_fit):
        rows.append(np.concatenate([y[k - NA:k][::-1], W[k - NB + 1:k + 1][::-1].ravel(), [1.0]]))
    A = np.array(rows)
    theta, *_ = np.linalg.lstsq(A, y[lag:k_fit], rcond=None)
    # free run over the held-out part, seeded with the measured outputs just before it
    yh = y.copy()
    lo, hi = float(y.min()), float(y.max())
    span = hi - lo
    for k in range(k_fit, y.size):
        row = np.concatenate([yh[k - NA:k][::-1], W[k - NB + 1:k + 1][::-1].ravel(), [1.0]])
        yh[k] = min(max(float(row @ theta), lo - span), hi + span)
    r = yh[k_fit:] - y[k_fit:]
    return float(np.sqrt(np.mean(r * r)))
