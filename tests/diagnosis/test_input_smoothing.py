"""A position link's input is smoothed by the smoothing that leaves it nearest the truth (links.smooth_input): a
curved input read on an encoder's lattice keeps its curvature (a local line over 20 ms biased it by (w dt)^2 / 24
times its curvature, far above the lattice's noise), a noisy one is smoothed, an exact one kept. The diagnosis
then fits a transport delay on a fast drive read by exact encoders down to their floor, which the local line's
bias kept it far above (issue 26: the naming bench's rig case 13, a delay on a strokes drive at 1.65 kHz)."""

import numpy as np
import pytest

from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.links import SMOOTH_S, smooth, smooth_input
from teleop.io.recording_io import read_interchange, write_interchange

Q = 1e-6                       # encoder count [m]
FLOOR = Q / np.sqrt(12.0)      # its quantisation noise [m]


def _fast_drive(fs: float, seconds: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] and a motor haul-in [m] of three sines up to 3 Hz (curvature up to about 1.5 m/s^2)."""
    t = np.arange(int(fs * seconds)) / fs
    return t, 3e-3 * np.sin(2 * np.pi * 0.9 * t) + 2e-3 * np.sin(2 * np.pi * 1.7 * t + 1.0) + \
        1e-3 * np.sin(2 * np.pi * 3.1 * t + 2.0)


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def test_a_curved_input_on_a_lattice_keeps_its_curvature():
    t, x = _fast_drive(1000.0)
    read = np.round(x / Q) * Q
    s, _ = smooth_input(read, 1e-3)
    inner = slice(100, -100)
    assert _rms((s - x)[inner]) <= 1.1 * FLOOR
    # the local line over SMOOTH_S, what the inputs had before, is far off the truth here
    line = smooth(read, int(round(SMOOTH_S / 1e-3)) | 1)
    assert _rms((line - x)[inner]) > 5 * FLOOR


def test_a_noisy_input_is_smoothed():
    t, x = _fast_drive(1000.0)
    sigma = 20e-6
    read = x + np.random.default_rng(3).normal(0.0, sigma, x.shape)
    s, w = smooth_input(read, 1e-3)
    assert w > 1 and _rms((s - x)[100:-100]) < 0.4 * sigma


def test_an_exact_input_is_kept():
    t, x = _fast_drive(500.0)
    s, w = smooth_input(x, 2e-3)
    assert w == 1 and s is x


def test_a_delay_on_a_fast_drive_is_fitted_to_the_encoder_floor(tmp_path):
    fs, delay = 1649.5, 3.36e-3
    t, x = _fast_drive(fs)
    tip = np.interp(t - delay, t, x, left=x[0])
    path = write_interchange(tmp_path / "delay.csv", t, {"motor_pos": np.round(x / Q) * Q, "tip_pos": np.round(tip / Q) * Q},
                             {"motor_pos": "m", "tip_pos": "m"})
    doc = diagnose(read_interchange(path)).as_dict()
    assert [f["effect"] for f in doc["findings"]] == ["transport_delay"], doc["findings"]
    f = doc["findings"][0]
    assert f["params"]["delay"]["value"] == pytest.approx(delay, rel=0.01)
    assert doc["channels"]["tip_pos"]["rmse_model"] <= 1.5 * FLOOR
