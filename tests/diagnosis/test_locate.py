"""Locate: the condition explaining a residual, and windows where it concentrates."""

import numpy as np

from teleop.core.physics.links import Link, LinkData
from teleop.diagnosis.locate import locate, reversal_times


def _data(t, x, temperature=None):
    link = Link("force", "motor_force", "tip_force", "motor_pos")
    load = 5 + np.sin(0.7 * t)
    return LinkData(link, t, load, load, x, None, temperature, None)


def test_direction_switch_is_after_reversals():
    t = np.arange(0, 20, 1e-3)
    x = np.sin(2 * np.pi * 0.3 * t)
    r = 0.2 * np.sign(np.cos(2 * np.pi * 0.3 * t)) + np.random.default_rng(0).normal(0, 0.01, t.size)
    loc = locate(_data(t, x), r, r)
    assert loc.condition == "after motion reversals"
    rev = reversal_times(t, x)
    assert len(rev) == 12
    # every window starts within 50 ms of a reversal
    for w0, _ in loc.windows:
        assert np.min(np.abs(rev - w0)) < 0.05


def test_temperature_drift_is_found():
    t = np.arange(0, 20, 1e-3)
    x = np.sin(2 * np.pi * 0.3 * t)
    T = 25 + 3 * np.sin(2 * np.pi * t / 13)
    r = 0.05 * (T - 25) + np.random.default_rng(1).normal(0, 0.01, t.size)
    loc = locate(_data(t, x, T), r, r)
    assert loc.condition == "drifting with temperature"
    assert loc.evidence["drifting with temperature"] > 0.9
