"""A static transmission error on the position link: the tip's position carries a fixed periodic function of
the drive's own position.

tip = x + sum_k a_k sin(2 pi k x / P) + b_k cos(2 pi k x / P), k = 1, 2, with x the drive position [m; rad
on a rotary drive, referred to the tip through the link's gain], a_k, b_k the harmonics' amplitudes [same
unit] and P the period [same unit]. It is the same in both directions of motion and at every speed: a
function of where the drive is, not of where it has been (no loop, unlike a play or a friction).

Where it comes from: anything that turns once (or a fixed number of times) per period of the drive: an
eccentric or out-of-round idler pulley or capstan, the lay of the cable's strands wound over a spindle, a
gear's tooth-to-tooth error. On the MRDLab da Vinci instrument the jaw angle's residual beyond the play is
such a function of the spindle angle, the same at every frequency and in both directions (docs/diagnosis.md).

It IS the map periodic in position that the diagnosis otherwise treats as physics outside the catalogue
(Rules.periodic): on the position link it is named; a force periodic in the motor position on the force
link (an eccentric pulley's torque) has no catalogue effect and stays unexplained.
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.transmission import transmission_error_run, transmission_error_step
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, register

KERNEL = Kernel(transmission_error_step, transmission_error_run, state=())
HARMONICS = 2
#: the guess's trial periods, as fractions of the record's drive span (log-spaced)
PERIOD_GRID = np.geomspace(1.0 / 40.0, 1.0 / 3.0, 100)
#: periods the record's drive span must hold: a period as long as the span is a smooth bend of the map (a
#: stiffening spring's cubic, a gain's curvature), not an error that repeats
MIN_PERIODS = 3.0


def harmonics(x: np.ndarray, period: float) -> np.ndarray:
    """(n, 2 HARMONICS) columns sin(2 pi k x / period), cos(2 pi k x / period), k = 1..HARMONICS."""
    w = 2.0 * np.pi * np.asarray(x, dtype=float)[:, None] * np.arange(1, HARMONICS + 1) / period
    return np.column_stack([f(w[:, j]) for j in range(HARMONICS) for f in (np.sin, np.cos)])


def _guess(signals: Signals, y: np.ndarray) -> dict:
    # linear least squares of the harmonics (and a constant) on what the input leaves, for each trial period
    # over the record's span; the period that leaves the least
    x = np.asarray(signals.x, dtype=float)
    r = np.asarray(y, dtype=float) - x
    span = float(np.ptp(x)) or 1.0
    best = (np.inf, PERIOD_GRID[0] * span, np.zeros(2 * HARMONICS))
    for period in PERIOD_GRID * span:
        A = np.column_stack([harmonics(x, period), np.ones_like(x)])
        coef, *_ = np.linalg.lstsq(A, r, rcond=None)
        cost = float(np.sum((r - A @ coef) ** 2))
        if cost < best[0]:
            best = (cost, period, coef[:-1])
    _, period, c = best
    out = {s.name: float(s.clip(v)) for s, v in zip(PARAMS[:4], c)}
    out["period"] = float(PARAMS[4].clip(period))
    return out


PARAMS = (ParamSpec("a1", "m", -1e3, 1e3, 0.0, "first harmonic's sine amplitude (rad on a rotary drive)",
                    log=True, tiny=1e-7),
          ParamSpec("b1", "m", -1e3, 1e3, 0.0, "first harmonic's cosine amplitude (rad on a rotary drive)",
                    log=True, tiny=1e-7),
          ParamSpec("a2", "m", -1e3, 1e3, 0.0, "second harmonic's sine amplitude (rad on a rotary drive)",
                    log=True, tiny=1e-7),
          ParamSpec("b2", "m", -1e3, 1e3, 0.0, "second harmonic's cosine amplitude (rad on a rotary drive)",
                    log=True, tiny=1e-7),
          ParamSpec("period", "m", 1e-6, 1e3, 1e-2, "drive travel over which the error repeats (rad on a "
                    "rotary drive)", log=True, positive=True))


def _wrong_form(p, rec) -> bool:
    # fewer than MIN_PERIODS periods over the span of the tip's travel (the effect's input, in its unit)
    return p["period"] * MIN_PERIODS > float(np.ptp(rec.tip))


def _draw(rng: np.random.Generator, s) -> dict:
    # a period of 1/12 to 1/5 of the drive's span, the first harmonic 4-8 % of the span at a random phase,
    # the second 20-50 % of the first
    span = 2.0 * s.travel
    c1 = rng.uniform(0.04, 0.08) * span
    c2 = rng.uniform(0.2, 0.5) * c1
    f1, f2 = rng.uniform(0.0, 2.0 * np.pi, 2)
    return {"a1": c1 * np.cos(f1), "b1": c1 * np.sin(f1), "a2": c2 * np.cos(f2), "b2": c2 * np.sin(f2),
            "period": span * rng.uniform(1.0 / 12.0, 1.0 / 5.0)}


TRANSMISSION_ERROR = register(Effect(
    name="transmission_error",
    link="position",
    doc="static, periodic in position: x + sum_k a_k sin(2 pi k x / P) + b_k cos(2 pi k x / P), k = 1, 2",
    params=PARAMS,
    inputs=("x",),
    output="x",
    guess=_guess,
    kernel=KERNEL,
    rules=Rules(channel="tip_pos", primary=("period",), position_only=True, periodic=True,
                wrong_form=_wrong_form, draw=_draw),
))
