"""Lags between the motor and the tip: a pure transport delay and a first-order lag of the link's input.

- transport_delay: tip(t) = x(t - delay), x the motor position referred through the link's gain (a dead
  time: a communication or sampling delay, a tendon's travel time, a late encoder). The step kernel keeps
  the last BUFFER samples (time and value) in its state, a ring buffer, and reads x at t - delay by linear
  interpolation between the two kept samples that bracket it, so the delay is fractional and does not
  depend on the sample rate (the diagnosis fits on decimated samples and scores on all of them); a delay of
  a whole number of sample intervals reads a kept sample. Before the first sample x is held at its first
  value; a delay longer than the kept samples span (BUFFER samples: 0.25 s above 8 kHz) reads the oldest.
- first_order_lag: the tip follows x through dy/dt = (x - y) / tau (a catheter's or a sensor's smoothing
  lag, a damped tip), integrated exactly for x linear between its samples (a first-order hold: a ramp's
  steady lag is tau times its slope at any sample rate), starting at rest on the first sample.

On a drive of one frequency the two cannot be told apart (a lag is a phase shift and a gain there, and the
link's gain takes the gain): Rules.alike. Each is one step kernel (teleop.core.kernels.effects); the array
form is the catalogue's driver loop over it and the Step calls it per sample.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels.effects import first_order_lag_run, first_order_lag_step, transport_delay_run, \
    transport_delay_step
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Scale, Signals, drive_kernel, register

BUFFER = 2048         # samples the transport delay keeps: MAX_DELAY_S of history up to 8 kHz
MAX_DELAY_S = 0.25    # [s] the delay's upper bound
GUESS_SAMPLES = 2000  # the guesses compare at most about this many samples

# the delay's start state as a read-only array (the run copies it once per call: from a tuple of 2 BUFFER + 2
# floats that copy cost several times the run itself on a fit's decimated samples)
_START = np.zeros(2 + 2 * BUFFER)
_START[0] = math.nan
_START.flags.writeable = False
DELAY = Kernel(transport_delay_step, transport_delay_run, state=_START)
LAG = Kernel(first_order_lag_step, first_order_lag_run, state=(math.nan, 0.0, 0.0))


def transport_delay(t: np.ndarray, x: np.ndarray, delay: float) -> np.ndarray:
    """(n,) x (n,) [any unit] read `delay` [s] late along the times t (n,) [s] (the transport_delay kernel)."""
    U = np.column_stack([np.asarray(t, dtype=float), np.asarray(x, dtype=float)])
    return drive_kernel(DELAY, np.array(DELAY.state), U, np.array([float(delay)]))


def first_order_lag(t: np.ndarray, x: np.ndarray, tau: float) -> np.ndarray:
    """(n,) y following x (n,) [any unit] through dy/dt = (x - y) / tau, tau [s] > 0, along the times t (n,)
    [s], from y = x[0] (the first_order_lag kernel)."""
    U = np.column_stack([np.asarray(t, dtype=float), np.asarray(x, dtype=float)])
    return drive_kernel(LAG, np.array(LAG.state), U, np.array([float(tau)]))


def _sub(n: int) -> np.ndarray:
    """Indices of at most about GUESS_SAMPLES of n samples, evenly spaced, skipping the first tenth (a lag's
    start)."""
    return np.arange(n // 10, n, max(1, n // GUESS_SAMPLES))


def _affine_rss(A: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(k,) residual sums of squares of y (m,) fitted as g a + c by least squares, a each row of A (k, m)."""
    Ac = A - A.mean(axis=1, keepdims=True)
    yc = y - y.mean()
    aa = np.einsum("ij,ij->i", Ac, Ac)
    ay = Ac @ yc
    return float(yc @ yc) - ay * ay / np.maximum(aa, 1e-300)


def _delay_guess(s: Signals, y: np.ndarray) -> dict:
    # the delay, on a grid of sample intervals (at most 250 steps) up to the bound, whose delayed input
    # explains y best affinely (the link's gain may not have taken its share of the lag yet)
    i = _sub(s.n)
    dt = float(np.median(np.diff(s.t)))
    grid = np.arange(0.0, MAX_DELAY_S, max(dt, MAX_DELAY_S / 250))
    A = np.interp(s.t[i][None, :] - grid[:, None], s.t, s.x)
    return {"delay": float(grid[int(np.argmin(_affine_rss(A, y[i])))])}


def _lag_guess(s: Signals, y: np.ndarray) -> dict:
    # tau on a log grid from one sample interval to 3 s, by the lagged input's affine fit of y
    i = _sub(s.n)
    dt = float(np.median(np.diff(s.t)))
    grid = np.geomspace(max(dt, 1e-4), 3.0, 40)
    A = np.array([first_order_lag(s.t, s.x, tau)[i] for tau in grid])
    return {"tau": float(grid[int(np.argmin(_affine_rss(A, y[i])))])}


def _drive_time(s: Scale) -> float:
    """[s] the drive's time scale: its half travel over its fast speed (1 / (2 pi f) for a sine of f Hz)."""
    return s.travel / s.v_fast


TRANSPORT_DELAY = register(Effect(
    name="transport_delay", link="position",
    doc="pure delay of the link's input: tip(t) = x(t - delay), fractional (interpolated)",
    params=(ParamSpec("delay", "s", 0.0, MAX_DELAY_S, 0.01, "dead time between the motor and the tip"),),
    inputs=("t", "x"), output="x",
    guess=_delay_guess, kernel=DELAY,
    rules=Rules(channel="tip_pos", primary=("delay",), alike=("first_order_lag",), reading=True,
                also_known_as=("sensor_delay",),
                draw=lambda rng, s: {"delay": min(rng.uniform(0.05, 0.15) * _drive_time(s), 0.8 * MAX_DELAY_S)}),
))

FIRST_ORDER_LAG = register(Effect(
    name="first_order_lag", link="position",
    doc="first-order lag of the link's input: d tip/dt = (x - tip) / tau",
    params=(ParamSpec("tau", "s", 1e-4, 10.0, 0.02, "time constant of the tip's lag behind the motor",
                      log=True, positive=True),),
    inputs=("t", "x"), output="x",
    guess=_lag_guess, kernel=LAG,
    rules=Rules(channel="tip_pos", primary=("tau",), reading=True,
                draw=lambda rng, s: {"tau": rng.uniform(0.05, 0.15) * _drive_time(s)}),
))
