"""The simulated slave: Robot protocol conformance, batch path == per-tick path, determinism, physics."""

import numpy as np
import pytest

from devices.base import Robot, RobotReading
from scenes.pads import three_region_pad, z_test_pad
from scenes.sim_robot import (SimRobot, SimRobotParams, capstan_angles_batch, lengths2poses, structure_matrices,
                              wrenches2tensions)
from scenes.world import WorldParams
from teleop.core.errors import InfeasibleError, InputError
from teleop.core.geometry import default_geometry
from teleop.core.kinematics import (bending_angles, lengths2pose, pose2cables, poses2lengths, structure_matrix)
from teleop.core.robot_status import RobotStatus
from teleop.core.tension import wrench2tensions
from teleop.loop.devices_by_url import open_device

GEOM = default_geometry()
PARAMS = SimRobotParams(substeps=2, world=WorldParams(surface_z=0.0235, dt=2e-3))


def _poke(n_down=60, depth=0.003, x=0.0):
    """(n, 6) lengths: from 1 mm above the surface down `depth` past it and back, at x."""
    z0, z1 = -0.0025, -0.0015 + depth
    z = np.r_[np.linspace(z0, z1, n_down), np.linspace(z1, z0, n_down)[1:]]
    poses = np.zeros((len(z), 6))
    poses[:, 2] = z
    poses[:, 0] = x
    return poses2lengths(poses, GEOM)


def test_conforms_to_robot_protocol():
    robot = SimRobot(z_test_pad(), PARAMS, seed=1)
    assert isinstance(robot, Robot)
    with pytest.raises(InputError):
        robot.read()
    with robot as r:
        world = r.world
        assert r.__enter__() is r and r.world is world  # entering again does not reopen
        r.command_lengths(_poke()[0])
        rd = r.read()
        assert isinstance(rd, RobotReading)
        assert rd.fsr_counts.shape == (6,) and rd.fsr_counts.dtype.kind == "i"
        assert ((rd.fsr_counts >= 0) & (rd.fsr_counts <= r.spec.adc_max)).all()
        assert rd.wrench_truth.shape == (6,) and rd.position_steps.shape == (6,)
        assert rd.seq == 1 and rd.t == pytest.approx(PARAMS.dt)
        with pytest.raises(InfeasibleError):
            r.command_lengths(np.full(6, 0.2))
        r.stop()
        L = r.L_cmd.copy()
        r.command_lengths(_poke()[5])
        # a host stop is the STOPPED bit (the firmware's bit 2), not the watchdog's
        status = r.read().status
        assert np.array_equal(r.L_cmd, L) and status & RobotStatus.STOPPED and not status & RobotStatus.WATCHDOG_STOP
    assert not robot.is_open


def test_batch_path_equals_per_tick_path():
    L = _poke()
    with SimRobot(three_region_pad(), PARAMS, seed=5) as a:
        ticks = []
        for row in L:
            a.command_lengths(row)
            ticks.append(a.read())
    with SimRobot(three_region_pad(), PARAMS, seed=5) as b:
        tr = b.run(L)
    counts = np.array([r.fsr_counts for r in ticks])
    assert np.abs(counts - tr.counts).max() <= 1 and (counts == tr.counts).mean() > 0.99
    assert np.allclose([r.wrench_truth for r in ticks], tr.wrench_truth, atol=1e-6)
    assert np.allclose([r.extras["t_fsr"] for r in ticks], tr.t_fsr, atol=1e-6)


def test_same_seed_same_counts_and_contact_pushes_back():
    L = _poke()
    runs = []
    for seed in (3, 3, 4):
        with SimRobot(z_test_pad(), PARAMS, seed=seed) as r:
            runs.append(r.run(L))
    assert np.array_equal(runs[0].counts, runs[1].counts)
    assert not np.array_equal(runs[0].counts, runs[2].counts)
    tr = runs[0]
    k = len(L) // 2
    assert tr.wrench_truth[k, 2] < -0.3 and abs(tr.wrench_truth[0, 2]) < 1e-9  # pushed back only in contact
    # A t + f = 0 at the commanded pose, and every tension within bounds
    A = structure_matrix(tr.poses[k], GEOM)
    assert np.allclose(A @ tr.t_tip[k] + tr.wrench_truth[k], 0.0, atol=1e-9)
    assert (tr.t_tip >= GEOM.t_min - 1e-12).all() and (tr.t_tip <= GEOM.t_max + 1e-12).all()


def test_sheath_friction_by_direction():
    """While a cable shortens (pulled) its FSR reads t_tip e^{+mu Theta}, while it lengthens e^{-mu Theta}."""
    L = _poke(n_down=200)
    with SimRobot(z_test_pad(), PARAMS, seed=0) as r:
        tr = r.run(L)
    k = 150  # mid-descent, well past any reversal transition
    dL = np.sign(L[k] - L[k - 1])
    ratio = tr.t_fsr[k] / tr.t_tip[k]
    expected = np.exp(-dL * GEOM.mu * tr.theta[k])
    assert np.allclose(ratio, expected, rtol=1e-9)


def test_batched_helpers_match_core_math():
    rng = np.random.default_rng(0)
    q = np.zeros((40, 6))
    q[:, :3] = rng.uniform(-0.004, 0.004, (40, 3))
    q[:, 4:] = rng.uniform(-0.05, 0.05, (40, 2))
    A = structure_matrices(q, GEOM)
    th = capstan_angles_batch(q, GEOM)
    for k in range(40):
        assert np.allclose(A[k], structure_matrix(q[k], GEOM), atol=1e-12)
        assert np.allclose(th[k], bending_angles(pose2cables(q[k], GEOM), GEOM) + GEOM.theta0, atol=1e-12)
    t = rng.uniform(0.5, 5.0, (40, 6))
    f = -np.einsum("nij,nj->ni", A, t)
    T = wrenches2tensions(f, A, GEOM.t_min, GEOM.t_max, 2.85)
    for k in range(40):
        assert np.allclose(T[k], wrench2tensions(f[k], A[k], GEOM.t_min, GEOM.t_max, 2.85), atol=1e-9)
    Q = lengths2poses(poses2lengths(q, GEOM), GEOM)
    for k in range(0, 40, 8):
        assert np.allclose(Q[k], lengths2pose(poses2lengths(q[k], GEOM)[0], GEOM), atol=1e-8)


def test_fsr_conductance_is_the_loading_branch_of_the_equivalent_tension():
    from scenes.sim_robot import fsr_conductance
    from teleop.core.sensors import LOADING, default_fsr_calibration

    cal = default_fsr_calibration()
    u = np.linspace(0.0, 5.5, 12)
    assert np.allclose(fsr_conductance(u, cal), cal.reading(u, LOADING), rtol=1e-12, atol=1e-15)


def test_from_url():
    r = open_device("sim://robot?pad=stiffness3&seed=2&substeps=2")
    assert isinstance(r, SimRobot) and r.pad.name == "stiffness3" and r.seed == 2
    with pytest.raises(InputError):
        open_device("sim://robot?pad=nope")
    with pytest.raises(InputError):
        open_device("sim://robot?colour=red")


def test_forward_kinematics_recovers_the_commanded_poses():
    from scenes.pose_follow import PoseFollower, pose_terms
    from scenes.sim_robot import capstan_angles_batch, lengths2poses, structure_matrices
    from teleop.core.kinematics import rotation_zyx

    rng = np.random.default_rng(3)
    q = np.zeros(6)
    q[2] = 0.002
    # a loop-like trajectory (steps of a few um and mrad) and one long jump
    qs = q + np.cumsum(rng.normal(0, 3e-6, (300, 6)) * np.array([1, 1, 1, 0, 300, 300]), axis=0)
    qs = np.vstack([qs, qs[-1] + np.array([0.003, -0.002, 0.002, 0, 0.05, -0.04])])
    L = poses2lengths(qs, GEOM)
    fk = PoseFollower(GEOM, q)
    got = np.array([fk.solve(Lk) for Lk in L])
    ref = lengths2poses(L, GEOM, guess=q)
    # both stop at a 1e-12 m length residual: the poses that made the lengths, to 1e-12 m / ~2.5 mm levers
    for poses in (got, ref):
        assert np.abs(poses2lengths(poses, GEOM) - L).max() < 1e-12
        assert np.abs(poses[:, :3] - qs[:, :3]).max() < 1e-10 and np.abs(poses[:, 4:] - qs[:, 4:]).max() < 1e-8
    A, theta, tip = pose_terms(got[-1].tolist(), GEOM)
    assert np.allclose(A, structure_matrices(got[-1:], GEOM)[0], atol=1e-12)
    assert np.allclose(theta, capstan_angles_batch(got[-1:], GEOM)[0], atol=1e-12)
    assert np.allclose(tip, rotation_zyx(*got[-1, 3:]) @ GEOM.tip, atol=1e-15)
    with pytest.raises(InputError):
        fk.solve(L[-1] + np.array([0.01, 0, 0, 0, 0, 0]))  # no pose has these lengths


@pytest.mark.parametrize("bad, error", [(np.nan, InputError), (0.2, InfeasibleError), (-1.0, InfeasibleError),
                                        ("short", InputError)])
def test_bad_commands_raise_and_change_nothing(bad, error):
    """The lengths are checked in the forward kinematics' kernel call: a bad command raises as
    teleop.core.kinematics.check_lengths and leaves the pose, the commanded lengths and the pose terms as they were."""
    with SimRobot(z_test_pad(), PARAMS, seed=1) as r:
        r.command_lengths(_poke()[3])
        pose, L, target = r.pose.copy(), r.L_cmd.copy(), r._pose_terms()[1].copy()
        cmd = _poke()[4][:5] if bad == "short" else np.where(np.arange(6) == 2, bad, _poke()[4])
        with pytest.raises(error):
            r.command_lengths(cmd)
        assert np.array_equal(r.pose, pose) and np.array_equal(r.L_cmd, L)
        assert np.array_equal(r._pose_terms()[1], target) and np.array_equal(r._fk._q, pose)
