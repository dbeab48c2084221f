"""scenes.cable_rig with `given`: a set experiment gets exactly the physics it asks for, and whatever it
does not set is what the seed draws without it."""

import io

import numpy as np

from scenes.cable_rig import simulate
from teleop.core.physics import tip2motor_transitions


def _cols(rec):
    lines = [ln for ln in rec.csv.splitlines() if not ln.startswith("#")]
    data = np.loadtxt(io.StringIO("\n".join(lines[1:])), delimiter=",")
    return dict(zip(lines[0].split(","), data.T))


def test_given_trajectory_bend_and_load_are_used_exactly():
    n = 1000
    t = np.arange(n) / 500.0
    x = 4e-3 * np.sin(2 * np.pi * 0.5 * t)
    load = np.full(n, 1.96)
    rec = simulate(3, load="external", duration_s=2.0, noise=0.0,
                   given={"x": x, "theta": 2.0, "mu": 0.05, "k_stick": 2e3, "tip_force": load, "ideal_sensors": True})
    c = _cols(rec)
    np.testing.assert_allclose(c["tip_force_N"], 1.96, atol=1e-8)
    np.testing.assert_allclose(c["motor_force_N"], tip2motor_transitions(x, load, 0.05, 2.0, 2e3), atol=1e-7)
    np.testing.assert_allclose(c["bend_angle_deg"], np.rad2deg(2.0), atol=1e-6)
    assert rec.trajectory == "given" and rec.setup["mu"] == 0.05 and rec.setup["k_stick"] == 2e3


def test_what_is_not_given_stays_as_drawn():
    plain = _cols(simulate(5, duration_s=2.0))
    spring = _cols(simulate(5, duration_s=2.0, given={"mu": 0.07}))
    np.testing.assert_array_equal(plain["motor_pos_mm"], spring["motor_pos_mm"])   # same trajectory, noise
    assert not np.array_equal(plain["motor_force_N"], spring["motor_force_N"])     # another friction
