"""Excitation trajectories and seeded noise shared by the physics tests."""

from __future__ import annotations

import numpy as np

from teleop.core.physics import Signals


def time_axis(seconds: float = 8.0, rate_hz: float = 1000.0) -> np.ndarray:
    """(n,) uniformly sampled time [s]."""
    return np.arange(int(seconds * rate_hz)) / rate_hz


def triangle(t: np.ndarray, amplitude: float, period: float) -> np.ndarray:
    """(n,) symmetric triangle wave of +/- amplitude, starting at 0 going up: reversals every period/2."""
    phase = (t / period + 0.25) % 1.0
    return amplitude * (4.0 * np.abs(phase - 0.5) - 1.0) * -1.0


def sum_of_sines(t: np.ndarray, amplitude: float, freqs=(0.23, 0.61, 1.37), seed: int = 0) -> np.ndarray:
    """(n,) sum of sines with seeded phases, peak around `amplitude`."""
    rng = np.random.default_rng(seed)
    ph = rng.uniform(0, 2 * np.pi, len(freqs))
    x = sum(np.sin(2 * np.pi * f * t + p) / (i + 1) for i, (f, p) in enumerate(zip(freqs, ph)))
    return amplitude * x / np.abs(x).max()


def all_channels(n: int, seed: int = 0) -> Signals:
    """A 1 kHz signal of n samples with every channel present: reversing motion, load, a pad's contact cycles
    (in and out of contact), temperature and bend."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    x = 8e-3 * np.sin(2 * np.pi * 2.0 * t) + 1e-3 * np.sin(2 * np.pi * 9.3 * t) + rng.normal(0, 1e-6, n)
    d = 1e-3 + 3e-3 * np.sin(2 * np.pi * 3.1 * t)
    return Signals(t=t, x=x, load=3 + np.sin(5.0 * t) + rng.normal(0, 0.05, n), force=500 * np.maximum(d, 0),
                   temperature=25 + 10 * t, theta=2.4 + 0.2 * np.sin(3.0 * t), d=d)


def noisy(y: np.ndarray, sigma: float, seed: int = 1) -> np.ndarray:
    """y plus seeded Gaussian noise of standard deviation sigma."""
    return y + np.random.default_rng(seed).normal(0.0, sigma, y.shape)


def assert_params_close(found: dict, truth: dict, rel: float = 0.05) -> None:
    """Every parameter in `truth` recovered within `rel` relative error."""
    for k, v in truth.items():
        err = abs(found[k] - v) / abs(v)
        assert err <= rel, f"{k}: found {found[k]:.6g}, truth {v:.6g}, rel err {err:.3%}"


def step_matches_apply(effect, signals: Signals, params: dict, rtol: float = 1e-9, atol: float = 1e-12):
    """Run the effect's Step over every sample and compare with the array form."""
    y = effect.apply(signals, params)
    st = effect.make_step(params)
    names = tuple(effect.inputs) + tuple(c for c in effect.optional if signals[c] is not None)
    cols = [signals[c] for c in names]
    ys = np.array([st.step(**{c: float(col[k]) for c, col in zip(names, cols)}) for k in range(signals.n)])
    np.testing.assert_allclose(ys, y, rtol=rtol, atol=atol)
    return y, ys
