"""The world's contact force: direction, friction sign, compliant drive reaching spring equilibrium."""

import numpy as np
import pytest

from scenes.pads import z_test_pad
from scenes.world import PadWorld, WorldParams

PARAMS = WorldParams()


def test_no_contact_above_surface_and_push_back_below():
    with PadWorld(z_test_pad(), PARAMS) as w:
        for _ in range(50):
            w.step([0.0, 0.0, PARAMS.surface_z - 0.001])
        assert np.allclose(w.contact_force(), 0.0)
        for _ in range(200):
            w.step([0.0, 0.0, PARAMS.surface_z + 0.001])
        F = w.contact_force()
        assert F[2] < -0.3 and abs(F[0]) < 1e-9


def test_friction_opposes_sliding():
    with PadWorld(z_test_pad(), PARAMS) as w:
        for _ in range(200):
            w.step([0.0, 0.0, PARAMS.surface_z + 0.001])
        for i in range(200):
            w.step([1e-5 * i, 0.0, PARAMS.surface_z + 0.001])
        assert w.contact_force()[0] < 0


def test_compliant_drive_settles_at_series_stiffness():
    k_r = 400.0
    K, C = np.eye(3) * k_r, np.eye(3) * 3.0
    pad = z_test_pad()
    k_p = pad.stiffness_at(np.zeros(2), PARAMS.tip_radius)
    with PadWorld(pad, PARAMS, stiffness=K, damping=C) as w:
        for _ in range(1500):
            w.step([0.0, 0.0, PARAMS.surface_z + 0.004])
        F = -w.contact_force()[2]
    assert F == pytest.approx(0.004 * k_r * k_p / (k_r + k_p), rel=0.03)


def test_one_contact_point_after_sliding_and_deep_poke():
    K, C = np.eye(3) * 400.0, np.eye(3) * 3.0
    with PadWorld(z_test_pad(), PARAMS, stiffness=K, damping=C) as w:
        for i in range(3000):  # slide 3 mm sideways while pressing, then poke 4 mm deeper
            w.step([1e-6 * i, 0.0, PARAMS.surface_z + 0.002 + (1.3e-6 * (i - 1500) if i > 1500 else 0.0)])
        assert w.n_contacts() == 1


def test_implicit_force_only_where_the_explicit_spring_would_diverge():
    from scenes.world import implicit_spring

    m, dt = PARAMS.indenter_mass, PARAMS.dt
    assert not implicit_spring(np.eye(3) * 382.0, np.eye(3) * 2.7, m, dt)  # a compliant robot: explicit
    from scenes.sim_robot import SimRobotParams

    k = SimRobotParams().tip_stiffness  # the cable-stiff default at palpation's 2 ms step: implicit
    assert implicit_spring(np.eye(3) * k, np.eye(3) * 2 * 0.7 * np.sqrt(m * k), m, 2e-3)
    assert implicit_spring(np.eye(3) * 3e4, np.eye(3) * 24.0, m, dt)


def test_stiff_series_spring_on_the_light_tip_stays_stable_and_settles():
    # 3e4 N/m on 10 g at 1 kHz: sqrt(K/m) dt = 1.7, where an explicit spring-damper diverges
    k_r = 3e4
    K, C = np.eye(3) * k_r, np.eye(3) * 2 * 0.7 * np.sqrt(PARAMS.indenter_mass * k_r)
    pad = z_test_pad()
    k_p = pad.stiffness_at(np.zeros(2), PARAMS.tip_radius)
    with PadWorld(pad, PARAMS, stiffness=K, damping=C) as w:
        for _ in range(500):
            w.step([0.0, 0.0, PARAMS.surface_z + 2e-4])
        F = -w.contact_force()[2]
    k_s = k_r * k_p / (k_r + k_p)
    assert F == pytest.approx(k_s * 2e-4, rel=0.1)


@pytest.mark.parametrize("k_r", [1e4, 400.0])
def test_tip_velocity_from_two_positions_is_pybullets(k_r):
    """The series spring's damper takes the tip's velocity as (x_k - x_(k-1)) / dt (Bullet integrates the base
    semi-implicitly): pybullet's own velocity to round-off at every step of a poke, a slide in contact and a
    lift off (fails if pybullet integrated otherwise, e.g. with sub-steps)."""
    K, C = np.eye(3) * k_r, np.eye(3) * 2 * 0.7 * np.sqrt(PARAMS.indenter_mass * k_r)
    worst, fastest, touching = 0.0, 0.0, 0
    with PadWorld(z_test_pad(), PARAMS, stiffness=K, damping=C) as w:
        for i in range(1500):
            z = PARAMS.surface_z + 0.003 * np.sin(np.pi * i / 1000)  # in 5 mm, 3 mm deep and out
            w.step([2e-6 * i if 300 < i < 900 else 6e-4, 0.0, z])
            w.tip()
            v = np.array(w.velocity())
            if w._vel_step == w._steps:  # the velocity the next step's spring takes
                worst = max(worst, np.abs(np.array(w._velocity()) - v).max())
            fastest = max(fastest, np.abs(v).max())
            touching += w.contact_force()[2] < -0.05
    assert touching > 300 and fastest > 0.1  # in contact for most of it; up to 1.5 m/s (measured)
    assert worst <= 1e-12  # m/s (measured: 2e-15)
