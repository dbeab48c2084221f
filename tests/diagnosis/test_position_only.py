"""Position-only recordings of a hysteretic transmission (motor_pos_deg -> tip_pos_deg, external load):
the diagnosis is never worse on held-out data than a single play operator (gain, offset, width) fitted to
the same split, whatever the play's width (radians of a tendon-sheath joint) or the gain's sign; on the real
da Vinci runs with their force columns dropped it still names the jaw's play.
Contains data from the MRDLab mis-tool-characterization dataset, ODbL 1.0."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from teleop.diagnosis.diagnose import diagnose, split
from teleop.io.recording_io import read_interchange, read_recording, write_interchange
from teleop.core.physics.backlash import backlash
from tests._data import EXAMPLE_MRDLAB, MRDLAB, needs_mrdlab


def _play_operator_rmse(u, y, fit, hold):
    """Held-out RMSE of the best single play operator y = backlash(g u + c, w) fitted on `fit`."""
    A = np.column_stack([u, np.ones_like(u)])
    (g, c), *_ = np.linalg.lstsq(A[fit], y[fit], rcond=None)
    best = None
    for gf in (1.0, 2.0, 4.0):
        for wf in (0.05, 0.3, 0.8):
            r = least_squares(lambda p: (backlash(p[0] * u + p[1], abs(p[2])) - y)[fit],
                              [g * gf, c, wf * np.ptp(y)])
            if best is None or r.cost < best.cost:
                best = r
    g, c, w = best.x
    return float(np.sqrt(np.mean((backlash(g * u + c, abs(w)) - y)[hold] ** 2)))


@pytest.mark.parametrize("seed, amp_deg, gain, play_frac, lag_s", [
    (0, 120.0, -0.62, 0.47, 0.0),     # a play of 2.1 rad at the tip, inverting transmission
    (1, 200.0, 1.9, 0.3, 0.04),       # a wide play and a tendon-sheath's take-up lag after it
    (2, 40.0, 0.4, 0.1, 0.0),
])
def test_never_worse_than_a_single_play_operator(tmp_path, seed, amp_deg, gain, play_frac, lag_s):
    rng = np.random.default_rng(seed)
    fs = 500.0
    t = np.arange(int(20 * fs)) / fs
    x = amp_deg * (0.6 * np.sin(2 * np.pi * 0.23 * t) + 0.4 * np.sin(2 * np.pi * 0.61 * t + 1.0))
    tip = backlash(gain * x + 10.0, play_frac * 2 * abs(gain) * amp_deg)
    if lag_s:
        a = np.exp(-1.0 / (fs * lag_s))
        for i in range(1, tip.size):
            tip[i] = a * tip[i - 1] + (1 - a) * tip[i]
    xm = x + rng.normal(0, 0.002 * amp_deg, t.size)
    ym = tip + rng.normal(0, 0.005 * np.ptp(tip), t.size)
    path = write_interchange(tmp_path / "p.csv", t, {"motor_pos": np.deg2rad(xm), "tip_pos": np.deg2rad(ym)},
                             {"motor_pos": "rad", "tip_pos": "rad"}, {"load": "external"})
    rec = read_interchange(path)
    fit, hold = split(rec.n, 0.4)
    doc = diagnose(rec).as_dict()
    assert doc["findings"] and doc["findings"][0]["effect"] == "backlash"
    play = _play_operator_rmse(rec.channels["motor_pos"], rec.channels["tip_pos"], fit, hold)
    assert doc["channels"]["tip_pos"]["rmse_model"] <= 1.05 * play


@pytest.mark.parametrize("path", [EXAMPLE_MRDLAB / "tool4_left_43_first8s.TXT",
                                  pytest.param(MRDLAB / "tool4_left_20.TXT", marks=needs_mrdlab)],
                         ids=["excerpt in examples/", "full MRDLab run"])
def test_mrdlab_position_columns_only(tmp_path, path):
    full = read_recording(path, "mrdlab")
    chans = {k: full.channels[k] for k in ("motor_pos", "tip_pos")}
    path = write_interchange(tmp_path / "pos.csv", full.t, chans, {"motor_pos": "rad", "tip_pos": "rad"},
                             {"load": "external"})
    rec = read_interchange(path)
    fit, hold = split(rec.n, 0.4)
    doc = diagnose(rec).as_dict()
    assert doc["findings"][0]["effect"] == "backlash" and doc["findings"][0]["improvement"] >= 2.0
    play = _play_operator_rmse(rec.channels["motor_pos"], rec.channels["tip_pos"], fit, hold)
    assert doc["channels"]["tip_pos"]["rmse_model"] <= 1.05 * play
