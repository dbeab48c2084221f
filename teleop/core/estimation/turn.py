"""Direction-change ("turn") compensation of the wrench, seed 000 §4 step 3 (Fig 13, segments EF and GH).

After the end effector reverses along an axis, the capstan-compensated wrench jumps and then settles. The
seed fits polynomials to those jump segments on a no-load back-and-forth run (20 mm, ~0.5 mm/s along z) and
subtracts them after every later turn. The fit is in time since the turn, at the speed of the fitting run:
this is why the strategy suits uniform motion only (seed 000 §6).

`fit_turn_compensation` makes one `AxisTurnFit` per axis from such a run; `TurnCompensation` holds the fits
(frozen); `TurnCompensator` applies them sample by sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import Polynomial

from teleop.core.errors import InputError
from teleop.core.direction import DirectionTracker
from teleop.core.kernels.estimate import turn_correct

FORWARD, BACKWARD = 1, -1


@dataclass(frozen=True)
class AxisTurnFit:
    """Jump polynomials for turns along one translation axis of the end effector.

    Attributes:
        axis: 0, 1, 2 for x, y, z of {B}.
        duration: length of the jump segment after a turn [s].
        forward, backward: (6, deg+1) power-series coefficients in s = tau / duration in [0, 1] of the wrench
            error [N, N m] after a turn to + (forward) and to - (backward) motion along the axis.
        deadband: position dead band of the turn detector [m]; 0 (default) detects the turn on the sample
            where the cables flip direction (single's jump starts there: a later detection misses its peak).
    """

    axis: int
    duration: float
    forward: tuple
    backward: tuple
    deadband: float = 0.0

    def correction(self, direction: int, tau: float) -> np.ndarray:
        """(6,) wrench error to subtract `tau` [s] after a turn to `direction` (zero outside the segment)."""
        if not 0.0 <= tau < self.duration or direction == 0:
            return np.zeros(6)
        coefs = self.forward if direction > 0 else self.backward
        s = tau / self.duration
        return np.array([Polynomial(c)(s) for c in coefs])


@dataclass(frozen=True)
class TurnCompensation:
    """The fitted turn corrections, one per axis that was fitted."""

    axes: tuple


def fit_turn_compensation(t, poses, wrench, axis: int = 2, degree: int = 4, duration: float | None = None,
                          deadband: float = 0.0, settle: float = 0.02, level_tail: float = 0.5) -> AxisTurnFit:
    """Fit the jump segments of a no-load back-and-forth run along `axis`.

    t (n,) [s]; poses (n, 6) end-effector poses; wrench (n, 6) the single-compensated wrench (the truth is 0).
    For every turn, the error in the segment is the wrench minus its settled level in that half cycle (mean
    of its last `level_tail` fraction, the wrench before the next turn), so the correction fades to zero at
    the segment end. A run where cables reverse mid-stroke (off the z axis, where a cable's length passes an
    extremum) needs a short tail: that reversal's transition must not count as the level. duration:
    segment length [s]; default: the median time after a turn until the error falls below `settle` of its
    peak (first crossing after
    the peak). Needs at least one turn each way.
    """
    t = np.asarray(t, dtype=float)
    p = np.asarray(poses, dtype=float)[:, axis]
    w = np.asarray(wrench, dtype=float)
    tracker = DirectionTracker(1, deadband)
    turns = []  # (index, new direction)
    for k in range(t.size):
        tracker.update(p[k:k + 1])
        if tracker.flipped[0]:
            turns.append((k, int(tracker.direction[0])))
    if not 0.0 < level_tail <= 1.0:
        raise InputError(f"turn-compensation fit: level_tail must be in (0, 1], got {level_tail}")
    if not any(d == FORWARD for _, d in turns) or not any(d == BACKWARD for _, d in turns):
        raise InputError(f"turn-compensation fit: the run needs turns both ways along axis {axis}")
    ends = [k for k, _ in turns[1:]] + [t.size]
    segments = []
    for (k0, d), k1 in zip(turns, ends):
        level = w[min(k0 + int((k1 - k0) * (1.0 - level_tail)), k1 - 1):k1].mean(axis=0)
        segments.append((d, t[k0:k1] - t[k0], w[k0:k1] - level))
    if duration is None:
        settle_times = []
        for _, tau, e in segments:
            mag = np.abs(e).max(axis=1)
            peak = int(np.argmax(mag[:mag.size // 2]))  # the jump sits in the first half of the half cycle
            small = np.nonzero(mag[peak:] < settle * mag[peak])[0]
            settle_times.append(tau[peak + small[0]] if small.size else tau[-1])
        duration = float(np.median(settle_times))
    if duration <= 0:
        raise InputError("turn-compensation fit: segment duration must be > 0")
    coefs = {}
    for d in (FORWARD, BACKWARD):
        tau = np.concatenate([s[1] for s in segments if s[0] == d])
        e = np.concatenate([s[2] for s in segments if s[0] == d])
        m = tau < duration
        coefs[d] = tuple(tuple(Polynomial.fit(tau[m] / duration, e[m, j], degree).convert().coef.tolist())
                         for j in range(6))
    return AxisTurnFit(axis=axis, duration=duration, forward=coefs[FORWARD], backward=coefs[BACKWARD],
                       deadband=deadband)


def turn_arrays(comp: TurnCompensation | None) -> tuple[np.ndarray, np.ndarray]:
    """(turn (k, 6), coefs (k, 2, 6, deg+1)): the arrays of teleop.core.kernels.estimate.turn_correct for the fits
    (state columns direction 0, extreme NaN, tau inf: no turn yet); (0, 6) and (0, 2, 6, 1) for none.
    Polynomials of lower degree are padded with zero high-order coefficients (the same values)."""
    axes = () if comp is None else comp.axes
    deg = max([len(c) for f in axes for c in (*f.forward, *f.backward)], default=1)
    turn = np.zeros((len(axes), 6))
    coefs = np.zeros((len(axes), 2, 6, deg))
    for k, f in enumerate(axes):
        turn[k, :6] = (f.axis, f.duration, f.deadband, 0.0, np.nan, np.inf)
        for b, side in enumerate((f.forward, f.backward)):
            for j, c in enumerate(side):
                coefs[k, b, j, :len(c)] = c
    return turn, coefs


class TurnCompensator:
    """Per-sample step 3: detects turns of the end effector and returns the wrench correction
    (teleop.core.kernels.estimate.turn_correct on the fits' arrays)."""

    def __init__(self, comp: TurnCompensation):
        self.comp = comp
        self.reset()

    def reset(self) -> None:
        self.turn, self.coefs = turn_arrays(self.comp)

    def update(self, position, dt: float) -> np.ndarray:
        """(6,) correction to subtract from the wrench, given the end-effector position (3,) [m]."""
        w = np.zeros(6)
        x, y, z = (float(v) for v in np.asarray(position, dtype=float)[:3])
        turn_correct(w, x, y, z, float(dt), self.turn, self.coefs)
        return -w
