"""An exact drive (a commanded position: no noise, no encoder lattice) with an operator's tremor on it: every
reversal is motion, and a Coulomb friction flips with each. Whether the recording's friction followed the
central difference (the catalogue's array forms) or the backward one (a per-sample simulation) shows at
those reversals; the diagnosis identifies the link both ways and the held-out part picks (JSON drive_rate)."""

import numpy as np
import pytest

from teleop.diagnosis.diagnose import diagnose
from teleop.core.physics.links import is_exact, noise_sigma
from teleop.io.recording_io import read_interchange, write_interchange
from teleop.core.physics import coulomb


def _drive(t):
    # 1 s pokes of 1.5 mm held at the bottom, and a 9 Hz tremor of 3 um: while held, the command reverses 18
    # times a second (200 reversals in 20 s)
    return 1.5e-3 * np.clip(1.6 * np.sin(np.pi * t) ** 2, 0.0, 1.0) + 3e-6 * np.sin(2 * np.pi * 9.0 * t + 0.3)


@pytest.mark.parametrize("rate", ["central", "backward"])
def test_coulomb_on_a_tremulous_exact_drive_is_named_with_the_rate_it_followed(tmp_path, rate):
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 20.0, 1e-3)
    x = _drive(t)
    v = np.gradient(x, t) if rate == "central" else np.concatenate(([0.0], np.diff(x) / np.diff(t)))
    tip = 3.0 + 0.2 * np.sin(2 * np.pi * 0.37 * t)
    motor = tip + coulomb(v, 0.3)
    ch = {"motor_pos": x, "motor_force": motor + rng.normal(0, 0.01, t.size), "tip_force": tip}
    path = tmp_path / "r.csv"
    write_interchange(path, t, ch, {"motor_pos": "m", "motor_force": "N", "tip_force": "N"},
                      {"load": "external"})
    doc = diagnose(read_interchange(path), baseline=()).as_dict()
    found = [f for f in doc["findings"] if f["channel"] == "motor_force"]
    assert found and found[0]["effect"] == "coulomb_friction", doc["findings"]
    assert abs(found[0]["params"]["Fc"]["value"] - 0.3) < 0.05 * 0.3 and found[0]["improvement"] > 10
    assert doc["channels"]["motor_force"]["drive_rate"] == f"{rate} (exact drive)"


def test_tremor_is_motion_and_noise_is_noise():
    t = np.arange(0.0, 20.0, 1e-3)
    x = _drive(t)
    assert is_exact(x) and noise_sigma(x) < 1e-9               # third differences leave the tremor out
    noisy = x + np.random.default_rng(0).normal(0, 1e-6, t.size)
    assert not is_exact(noisy) and noise_sigma(noisy) == pytest.approx(1e-6, rel=0.1)
    q = 1e-5                                                     # an encoder's lattice: q / sqrt(12)
    assert not is_exact(np.round(x / q) * q) and noise_sigma(np.round(x / q) * q) >= q / np.sqrt(12) * 0.99
