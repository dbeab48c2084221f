"""One exciting, noisy synthetic experiment per registered effect: signals, true params, noise, fixed."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from teleop.core.physics import Signals, linear_force

from ._signals import sum_of_sines, time_axis, triangle


@dataclass(frozen=True)
class Scenario:
    signals: Signals
    truth: dict            # parameters to recover
    sigma: float           # output noise standard deviation [output unit]
    fixed: dict = field(default_factory=dict)


def _motion(seconds: float = 8.0):
    t = time_axis(seconds)
    x = triangle(t, 8e-3, 2.0) + sum_of_sines(t, 2e-3, seed=3)
    return t, x


def _ramp_hold_release(t: np.ndarray, depth: float, ramp: float, hold: float) -> np.ndarray:
    """Indentation [m]: approach from -0.5 mm, ramp to depth, hold, release, pause; repeated."""
    period = 2 * ramp + 2 * hold
    ph = t % period
    up = np.clip(ph / ramp, 0, 1)
    down = np.clip((ph - ramp - hold) / ramp, 0, 1)
    return -0.5e-3 + (depth + 0.5e-3) * (up - down)


def scenario(name: str) -> Scenario:
    t, x = _motion()
    load = 3.0 + 1.5 * np.sin(2 * np.pi * 0.13 * t)
    if name == "backlash":
        return Scenario(Signals(t=t, x=x), {"width": 0.8e-3}, 10e-6)
    if name == "transmission_error":
        return Scenario(Signals(t=t, x=x), {"a1": 40e-6, "b1": -25e-6, "a2": 15e-6, "b2": 20e-6, "period": 3e-3},
                        2e-6)
    if name == "transport_delay":
        return Scenario(Signals(t=t, x=x), {"delay": 0.03}, 10e-6)
    if name == "first_order_lag":
        return Scenario(Signals(t=t, x=x), {"tau": 0.05}, 10e-6)
    if name == "cable_compliance":
        return Scenario(Signals(t=t, x=x, load=load), {"k": 2e4}, 2e-6)
    if name == "capstan_friction":
        return Scenario(Signals(t=t, x=x, load=load), {"mu": 0.1, "k": 3e3}, 0.02,
                        {"theta": np.deg2rad(140.0) + 1.0})
    if name == "pulley_friction":
        return Scenario(Signals(t=t, x=x, load=load), {"mu": 0.1, "bend": 0.2, "k": 3e3}, 0.02, {"wrap": np.pi})
    if name == "pulley_elongation":
        return Scenario(Signals(t=t, x=x, load=load), {"c": 2e-4, "mu": 0.1}, 2e-6,
                        {"wrap": np.pi, "bend": 0.2, "k": 3e3})
    if name == "coulomb_friction":
        return Scenario(Signals(t=t, x=x, load=load), {"Fc": 0.3}, 0.02)
    if name == "viscous_friction":
        return Scenario(Signals(t=t, x=x, load=load), {"b": 8.0}, 0.02)
    if name == "stribeck_friction":
        return Scenario(Signals(t=t, x=x, load=load), {"Fc": 0.3, "Fs": 0.6, "vs": 4e-3}, 0.02)
    if name == "dahl_hysteresis":
        return Scenario(Signals(t=t, x=x, load=load), {"sigma": 2e3, "Fc": 0.3}, 0.02)
    if name == "parallel_spring":
        return Scenario(Signals(t=t, x=x, load=load), {"k": 150.0}, 0.02, {"x_ref": 1e-3, "g": 1.2e4})
    if name == "sensor_hysteresis":
        F = 5.0 + 3.0 * np.sin(2 * np.pi * 0.5 * t) + sum_of_sines(t, 1.0, seed=5)
        return Scenario(Signals(t=t, force=F), {"h": 0.3, "delta": 0.5}, 0.02)
    if name == "thermal_drift":
        F = 5.0 + 3.0 * np.sin(2 * np.pi * 0.5 * t)
        T = 25.0 + 8.0 * np.sin(2 * np.pi * 0.06 * t) + 1.0 * t
        return Scenario(Signals(t=t, force=F, temperature=T), {"c": 0.05, "T0": 22.0}, 0.02)
    if name == "thermal_drift_time":
        F = 5.0 + 3.0 * np.sin(2 * np.pi * 0.5 * t)
        return Scenario(Signals(t=t, force=F), {"offset": 0.2, "rate": 0.03}, 0.02)
    d = _ramp_hold_release(t, 3e-3, 0.5, 1.5)
    Fe = linear_force(d, 800.0)
    if name == "linear_contact":
        return Scenario(Signals(t=t, d=d), {"k": 800.0}, 0.01)
    if name == "hertz_contact":
        return Scenario(Signals(t=t, d=d), {"k": 2e4}, 0.01)
    if name == "viscoelasticity":
        return Scenario(Signals(t=t, d=d, force=Fe), {"g": 0.6, "tau": 0.7}, 0.01)
    if name == "contact_damping":
        d = 1e-3 + 3e-3 * np.sin(2 * np.pi * 0.8 * t)
        return Scenario(Signals(t=t, d=d, force=linear_force(d, 800.0)), {"c": 50.0}, 0.01)
    raise KeyError(name)
