"""The simulated robot with per-cable play (sim://robot?backlash_mm=W)."""

import numpy as np
import pytest

from teleop.loop.devices_by_url import open_device
from scenes.sim_robot import SimRobot, SimRobotParams
from teleop.core.errors import InputError
from teleop.core.kinematics import pose2lengths, poses2lengths
from teleop.core.physics.backlash import backlash

W = 0.5e-3


def _poses(n=600, amp=2e-3):
    t = np.arange(n) * 1e-3
    q = np.zeros((n, 6))
    q[:, 0] = amp * np.sin(2 * np.pi * 2.0 * t)
    q[:, 2] = 0.5 * amp * np.sin(2 * np.pi * 3.0 * t)
    return q


def test_the_pose_follows_the_realized_lengths_of_the_play():
    q = _poses()
    with SimRobot(params=SimRobotParams(backlash=W)) as robot:
        L = poses2lengths(q, robot.geom)
        real = np.column_stack([backlash(np.r_[robot.L_home[i], L[:, i]], W)[1:] for i in range(6)])
        got = []
        for k in range(len(L)):
            robot.command_lengths(L[k])
            r = robot.read()
            got.append(robot.pose.copy())
            # the motor reports what it was told (its steps), not the cable behind the play
            np.testing.assert_array_equal(r.commanded_lengths, L[k])
        got = np.array(got)
    # the pose is the least-squares pose of the realized lengths: its lengths sit within the play of them
    back = poses2lengths(got, robot.geom)
    assert np.abs(back - real).max() < W / 2
    assert np.abs(back - L).max() > W / 4      # and the play shows: the commanded pose is missed
    err = np.linalg.norm(got[100:, :3] - q[100:, :3], axis=1)
    assert 0.1e-3 < np.sqrt(np.mean(err ** 2)) < 2 * W


def test_a_motion_inside_the_play_moves_nothing():
    with SimRobot(params=SimRobotParams(backlash=W)) as robot:
        q0 = robot.pose.copy()
        for k in range(200):
            q = np.zeros(6)
            q[2] = 0.1e-3 * np.sin(2 * np.pi * k / 50)        # lengths change by < W/2
            robot.command_lengths(pose2lengths(q, robot.geom))
            robot.read()
            np.testing.assert_allclose(robot.pose, q0, atol=1e-12)


def test_batch_run_and_per_reading_path_agree_with_play():
    q = _poses(400)
    with SimRobot(params=SimRobotParams(backlash=W), seed=2) as a, SimRobot(params=SimRobotParams(backlash=W), seed=2) as b:
        L = poses2lengths(q, a.geom)
        tr = a.run(L[:200])
        tr2 = a.run(L[200:])                          # the play carries over between batches
        poses = []
        for k in range(len(L)):
            b.command_lengths(L[k])
            b.read()
            poses.append(b.pose.copy())
    np.testing.assert_allclose(np.vstack([tr.poses, tr2.poses]), np.array(poses), atol=1e-9)


def test_without_play_nothing_changes():
    q = _poses(100)
    with SimRobot() as robot:
        L = poses2lengths(q, robot.geom)
        for k in range(len(L)):
            robot.command_lengths(L[k])
            np.testing.assert_allclose(robot.pose, q[k], atol=1e-9)


def test_url_option():
    robot = open_device("sim://robot?backlash_mm=0.3")
    assert robot.params.backlash == pytest.approx(0.3e-3)
    for bad in ("abc", "-1", "nan"):
        with pytest.raises(InputError, match="backlash"):
            open_device(f"sim://robot?backlash_mm={bad}")
