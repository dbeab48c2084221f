"""Seed 001's identification run of the one-sensor model on the simulated robot (``sim://robot?sensor=one``).

The instrumented cable's FSR (proximal) and FBG (distal) tensions over a haul-in and pay-out give the model's
Kp, Kr (teleop.core.estimation.sensor_reading.identify_one_sensor); the loop's estimator for that URL uses them
(teleop.loop.session.loop_estimator).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from scenes.sim_robot import SimRobot, home_pose
from teleop.core.estimation.sensor_reading import identify_one_sensor
from teleop.core.kinematics import poses2lengths
from teleop.core.sensors import FsrConverter

_IDENTIFIED: dict = {}


def identify_one_sensor_on(params, seed: int = 0, cable: int = 0, travel: float = 0.008, speed: float = 2e-3,
                           cycles: int = 2):
    """Seed 001's identification run on a simulated robot with `params` (sensor "one"): with the pad slid out
    of reach, the end effector goes `travel` [m] along -z and back `cycles` times at `speed` [m/s], hauling the
    instrumented cable in and paying it out at its pretension; its FSR (proximal) and FBG (distal) tensions
    give Kp, Kr (teleop.core.estimation.sensor_reading.identify_one_sensor). Cached per (params, seed, cable)."""
    key = (repr(params), int(seed), int(cable), travel, speed, int(cycles))
    if key not in _IDENTIFIED:
        _IDENTIFIED[key] = _identify(params, seed, cable, travel, speed, cycles)
    return _IDENTIFIED[key]


def _identify(params, seed, cable, travel, speed, cycles):
    p = replace(params, sensor="one", fbg_cable=int(cable))
    q0 = home_pose()
    steps = max(2, int(round(travel / (speed * p.dt))))
    z = np.linspace(0.0, -travel, steps)
    path = np.concatenate([np.r_[z, z[::-1]]] * int(cycles))
    q = np.repeat(q0[None], path.size, axis=0)
    q[:, 2] += path
    L = poses2lengths(q, p.geometry)
    with SimRobot(params=p, seed=int(seed)) as robot:
        robot.set_pad_offset((0.2, 0.0))
        tr = robot.run(L)
    conv = FsrConverter(robot.cal)
    Fp = np.array([conv.update(c)[cable] for c in tr.counts])
    return identify_one_sensor(Fp, tr.fbg_pm, L[:, cable], cable)
