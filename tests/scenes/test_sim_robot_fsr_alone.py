"""The distributed robot's FSRs as the sensor alone (SimRobotParams.fsr, scenes.fsr_sensor) and the estimators'
calibration fitted on a simulated calibration platform of that plant (scenes.fsr_lab)."""

import numpy as np

from scenes.fsr_lab import calibration_run, plant_fsr_calibration, weight_profile
from scenes.fsr_sensor import INTERLINK_HYSTERESIS, FsrSensorParams
from scenes.sim_robot import SimRobot, SimRobotParams, with_named_plant
from scenes.tendon_sheath import TendonSheathParams
from teleop.core.sensors import LOADING, UNLOADING, default_fsr_calibration
from teleop.core.kinematics import poses2lengths
from tests.scenes._readings import read_then_run


def _press(n=1200, depth=8e-3):
    """(n, 6) poses: the end effector down `depth` [m] along z and back."""
    z = np.concatenate([np.linspace(0.0, depth, n // 2), np.linspace(depth, 0.0, n - n // 2)])
    q = np.zeros((n, 6))
    q[:, 2] = z
    return q


def test_the_plants_pick_their_fsr():
    assert with_named_plant(SimRobotParams(), "distributed", 1).fsr == FsrSensorParams()
    for plant in ("matched", "rich", "pulley"):
        sim = with_named_plant(SimRobotParams(fsr=FsrSensorParams()), plant, 1)
        assert sim.fsr is None                                     # the branch lag, as before
        assert plant_fsr_calibration(sim) == default_fsr_calibration()


def test_the_distributed_robots_fsr_reads_with_the_datasheets_hysteresis():
    p = SimRobotParams(cable=TendonSheathParams(), fsr=FsrSensorParams(), noise_counts=0.0)
    with SimRobot(params=p, seed=1) as robot:
        trace = robot.run(poses2lengths(_press(), robot.geom))
        cal = robot.cal
    t, G = trace.t_fsr[:, 0], cal.counts2conductance(trace.counts[:, 0])
    top = int(np.argmax(t))
    assert 0 < top < len(t) - 1 and t[top] - t[-1] > 1.0           # cable 0 loads, then unloads past its start
    # at 2.9-3.0 N the unloading has swung ln G by more than the plays' widest (2 gap): the whole gap is open
    up = (np.arange(len(t)) <= top) & (t > 2.9) & (t < 3.0)
    down = (np.arange(len(t)) > top) & (t > 2.9) & (t < 3.0)
    assert up.sum() > 5 and down.sum() > 5
    g_up = np.interp(t[down], t[:top + 1], G[:top + 1])              # the loading reading at the same tension
    rel = (G[down] - g_up) / G[down]                                  # (R_F+ - R_F-) / R_F+
    assert np.allclose(rel, INTERLINK_HYSTERESIS, atol=0.015)
    # the branch lag of the calibration's whole gap (no fsr) reads otherwise at the same tensions
    with SimRobot(params=SimRobotParams(cable=TendonSheathParams(), noise_counts=0.0), seed=1) as robot:
        lagged = robot.run(poses2lengths(_press(), robot.geom))
    assert np.array_equal(lagged.t_fsr, trace.t_fsr) and not np.array_equal(lagged.counts, trace.counts)


def test_the_batch_path_reads_what_the_readings_read_with_the_fsr_alone():
    rows, trace = read_then_run(with_named_plant(SimRobotParams(), "distributed", 4), 4,
                                lambda g: poses2lengths(_press(600), g))
    assert np.allclose(trace.t_fsr, np.array([x["t_fsr"] for _, x in rows]), atol=1e-9)
    assert np.array_equal(trace.counts, np.array([c for c, _ in rows]))


def test_the_platform_calibration_holds_the_sensor_and_the_cables_friction():
    W, holds = weight_profile(1)
    assert len(holds) == 27 and W.max() == holds[13][2]              # 0-650 g up, 600-0 g down
    data = calibration_run(TendonSheathParams(), FsrSensorParams(noise_counts=0.0), 0, repeats=1)
    truth = default_fsr_calibration()
    lo, un = data.branch == LOADING, data.branch == UNLOADING
    mid = (data.tension > 1.0) & (data.tension < 5.0)
    # loading: the scaffold's friction holds part of each added weight off B; unloading: it holds tension in
    assert np.all(data.reading[lo & mid] < truth.reading(data.tension[lo & mid], LOADING))
    assert np.all(data.reading[un & mid] > truth.reading(data.tension[un & mid], LOADING))
    # frictionless cable: only the sensor's own hysteresis separates the branches (at most its full gap)
    free = calibration_run(TendonSheathParams(mu_c=0.0, mu_s=0.0), FsrSensorParams(noise_counts=0.0), 0, repeats=1)
    g_lo = free.reading[lo & mid]
    assert np.allclose(g_lo, truth.reading(free.tension[lo & mid], LOADING), rtol=0.01)
    ratio = free.reading[un & mid] / truth.reading(free.tension[un & mid], LOADING)
    assert np.all((ratio > 1.0) & (ratio < 1 / (1 - INTERLINK_HYSTERESIS) + 0.01))
    # the branches' gap (unloading - loading conductance at each weight) is wider with the cable's friction
    gap = lambda d: np.sort(d.reading[un & mid]) - np.sort(d.reading[lo & mid])  # noqa: E731  (weights in order)
    assert np.all(gap(data) > gap(free))
