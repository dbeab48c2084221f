"""Test signals and recordings shared by the generated-recording tests."""

import numpy as np

from teleop.io.recording_io import read_interchange, write_interchange


def multisine(rng: np.random.Generator, t: np.ndarray, total: float, n: int, f_lo: float, f_hi: float) -> np.ndarray:
    """Sum of n sines over t [s], amplitudes a Dirichlet split of `total`, frequencies uniform in [f_lo, f_hi]
    [Hz], random phases (drawn from rng in that order: the same rng state gives the same signal)."""
    x = np.zeros_like(t)
    for amp, f in zip(rng.dirichlet(np.ones(n)) * total, rng.uniform(f_lo, f_hi, n)):
        x += amp * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    return x


def force_link_recording(path, t: np.ndarray, x: np.ndarray, motor: np.ndarray, load: np.ndarray, seed: int):
    """Write and read back an interchange recording of one force link (`load = external`): motor position x
    [m] with 2 um noise, motor force and tip force (load) [N] with 0.01 N noise, from rng(seed)."""
    rng = np.random.default_rng(seed)
    write_interchange(path, t, {"motor_pos": x + rng.normal(0, 2e-6, t.size),
                                "motor_force": motor + rng.normal(0, 0.01, t.size),
                                "tip_force": load + rng.normal(0, 0.01, t.size)},
                      {"motor_pos": "m", "motor_force": "N", "tip_force": "N"}, {"load": "external"})
    return read_interchange(path)
