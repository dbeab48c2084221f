"""Test signals shared by the generated-recording tests."""

import numpy as np


def multisine(rng: np.random.Generator, t: np.ndarray, total: float, n: int, f_lo: float, f_hi: float) -> np.ndarray:
    """Sum of n sines over t [s], amplitudes a Dirichlet split of `total`, frequencies uniform in [f_lo, f_hi]
    [Hz], random phases (drawn from rng in that order: the same rng state gives the same signal)."""
    x = np.zeros_like(t)
    for amp, f in zip(rng.dirichlet(np.ones(n)) * total, rng.uniform(f_lo, f_hi, n)):
        x += amp * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    return x
