"""Effects inside a force sensor: loading/unloading hysteresis and drift (temperature or time).

- sensor_hysteresis: reading = F + h s, with s in [-1, 1] the loading state: +1 while the measured force
  rises, -1 while it falls. s switches play-type: z = play of F with half-width delta
  (z_k = clamp(z_k-1, F_k - delta, F_k + delta)), s = (F - z) / delta, so after a reversal the offset
  travels linearly from +h to -h over 2 delta of force change (delta -> 0: an abrupt switch).
  Starts neutral (s = 0).
- thermal_drift: reading = F + c (T - T0), T the sensor temperature [degC].
- thermal_drift_time: when no temperature is recorded, reading = F + offset + rate (t - t_0), t_0 = t[0].
Each effect's physics is one step kernel (teleop.core.kernels.effects); the array forms are the catalogue's
driver loop over it.
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.effects import hysteresis_offset_run, hysteresis_offset_step, sensor_hysteresis_run, \
    sensor_hysteresis_step, thermal_drift_run, thermal_drift_step, thermal_drift_time_run, thermal_drift_time_step
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, kernel_call, register

OFFSET = Kernel(hysteresis_offset_step, hysteresis_offset_run)
THERMAL = Kernel(thermal_drift_step, thermal_drift_run, state=())


def hysteresis_offset(F: np.ndarray, h: float, delta: float, z0=None) -> np.ndarray:
    """(n,) reading offset [N] of a sensor with loading/unloading hysteresis h [N], switch half-width delta [N].

    F may be (n, k) (k sensors along the columns). z0: the switch state [N] before F[0] ((k,) or a float;
    default F[0], neutral); the state after the last sample is F[-1] - offset[-1] delta / h."""
    F = np.asarray(F, dtype=float)
    cols = F.reshape(F.shape[0], -1)
    Z0 = np.broadcast_to(np.nan if z0 is None else np.asarray(z0, dtype=float), cols.shape[1:]).reshape(-1)
    out = np.column_stack([kernel_call(OFFSET, (h, delta), cols[:, j], state=np.array([Z0[j]]))
                           for j in range(cols.shape[1])])
    return out.reshape(F.shape)


def thermal_offset(T: np.ndarray, c: float, T0: float) -> np.ndarray:
    """Reading offset [N]: c (T - T0), c [N/K], T and T0 [degC] (the thermal_drift step kernel on a zero
    force)."""
    return kernel_call(THERMAL, (c, T0), 0.0, T)


def _hyst_guess(s: Signals, y: np.ndarray) -> dict:
    e = y - s.force
    h = 0.5 * float(np.percentile(e, 98) - np.percentile(e, 2))
    return {"h": h, "delta": 0.05 * float(np.ptp(s.force)) + 1e-6}


def _thermal_guess(s: Signals, y: np.ndarray) -> dict:
    # y - F = c T - c T0: a straight line in T
    c, a = np.polyfit(s.temperature, y - s.force, 1)
    return {"c": float(c), "T0": float(-a / c) if abs(c) > 1e-12 else float(np.mean(s.temperature))}


def _time_guess(s: Signals, y: np.ndarray) -> dict:
    rate, offset = np.polyfit(s.t - s.t[0], y - s.force, 1)
    return {"rate": float(rate), "offset": float(offset)}


def _thermal_hold(rec, known, direction) -> dict:
    """The zero-offset temperature trades with the baseline offset: held at the record's mean."""
    return {"T0": float(np.mean(rec.temperature))} if rec.temperature is not None else {}


def _thermal_draw(rng, s) -> dict:
    return {"c": float(rng.choice([-1, 1])) * rng.uniform(0.1, 0.25) * s.force_span / s.temp_span, "T0": 25.0}


SENSOR_HYSTERESIS = register(Effect(
    name="sensor_hysteresis", link="sensor",
    doc="loading vs unloading offset: +h while the force rises, -h while it falls, play-type switch",
    params=(ParamSpec("h", "N", 0.0, 50.0, 0.1, "half the gap between loading and unloading readings"),
            ParamSpec("delta", "N", 1e-6, 100.0, 0.2, "half the force change over which the offset flips",
                      log=True, positive=True)),
    inputs=("force",), output="force",
    guess=_hyst_guess, kernel=Kernel(sensor_hysteresis_step, sensor_hysteresis_run),
    # on the motor sensor under a spring load, a hysteresis is a constant-magnitude friction's band
    rules=Rules(channel="motor_force", primary=("h",),
                alike=("coulomb_friction", "stribeck_friction", "dahl_hysteresis"),
                draw=lambda rng, s: {"h": rng.uniform(0.06, 0.12) * s.force_span,
                                     "delta": rng.uniform(0.02, 0.06) * s.force_span})))

THERMAL_DRIFT = register(Effect(
    name="thermal_drift", link="sensor", doc="offset following temperature: c (T - T0)",
    params=(ParamSpec("c", "N/K", -10.0, 10.0, 0.01, "temperature coefficient of the reading"),
            ParamSpec("T0", "degC", -50.0, 150.0, 20.0, "temperature of zero offset")),
    inputs=("force", "temperature"), output="force",
    guess=_thermal_guess, kernel=THERMAL,
    rules=Rules(channel="motor_force", primary=("c",), hold=_thermal_hold, draw=_thermal_draw)))

THERMAL_DRIFT_TIME = register(Effect(
    name="thermal_drift_time", link="sensor",
    doc="drift without a temperature channel: offset + rate (t - t0)",
    params=(ParamSpec("offset", "N", -100.0, 100.0, 0.0, "offset at the first sample"),
            ParamSpec("rate", "N/s", -10.0, 10.0, 0.0, "drift rate")),
    inputs=("t", "force"), output="force",
    guess=_time_guess, kernel=Kernel(thermal_drift_time_step, thermal_drift_time_run),
    # no physical cause to name: a drift with time and no temperature channel is reported as unexplained
    rules=Rules(channel="motor_force", primary=("rate",), finding=False)))
