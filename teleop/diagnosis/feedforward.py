"""Feed-forward pre-compensation of backlash in the position command (cable-pulley seed 002).

The play operator y_k = clamp(y_k-1, x_k - w/2, x_k + w/2) is inverted by driving the motor half the
play ahead of the wanted tip position in the direction of motion: x = y_d + (w/2) s, s the held direction
of y_d; at each reversal the command crosses the dead band at once (or at `max_step` per sample).
"""

from __future__ import annotations

import numpy as np

from teleop.diagnosis.links import LinkModel
from teleop.errors import InputError


def backlash_inverse(y_d: np.ndarray, width: float, max_step: float | None = None) -> np.ndarray:
    """(n,) input x that makes a play of total `width` output y_d (n,) [same unit]; max_step limits the
    per-sample change of x while crossing the dead band (None: cross in one sample)."""
    y_d = np.asarray(y_d, dtype=float)
    r = 0.5 * float(width)
    dy = np.diff(y_d, prepend=y_d[0])
    s = np.sign(dy)
    idx = np.where(s != 0, np.arange(s.size), 0)
    np.maximum.accumulate(idx, out=idx)
    s = s[idx]
    if s.size and s[0] == 0:  # before the first motion: start centred
        first = np.flatnonzero(s != 0)
        s[: first[0] if first.size else s.size] = 0.0
    x = y_d + r * s
    if max_step is not None:
        x = x.copy()
        for k in range(1, x.size):
            step = x[k] - x[k - 1]
            if abs(step) > max_step:
                x[k] = x[k - 1] + np.sign(step) * max_step
    return x


def precompensate(model: LinkModel, tip_target: np.ndarray, max_step: float | None = None) -> np.ndarray:
    """Motor command (n,) [input unit] making the position link `model` (gain, offset, backlash) follow
    tip_target (n,) [output unit]: x = (backlash_inverse(tip_target) - offset) / gain."""
    if model.link.kind != "position":
        raise InputError(f"precompensate: needs a position link model, got {model.link.kind}")
    width = 0.0
    for name, p in model.effects:
        if name == "backlash":
            width = float(p["width"])
    z = backlash_inverse(tip_target, width, None if max_step is None else abs(model.gain) * max_step)
    return (z - model.offset) / model.gain
