"""devices.wrappers.BacklashCompensatedRobot on the simulated robot with play."""

import numpy as np
import pytest

from devices.wrappers import BacklashCompensatedRobot, LoggedDevice
from scenes.sim_robot import SimRobot, SimRobotParams
from teleop.core.kinematics import poses2lengths

W = 0.5e-3
DT = 1e-3


def _sine_poses(n=1200):
    t = np.arange(n) * DT
    q = np.zeros((n, 6))
    q[:, 0] = 2e-3 * np.sin(2 * np.pi * 1.0 * t)
    q[:, 1] = 1e-3 * np.sin(2 * np.pi * 0.7 * t)
    return q


class _Clock:
    """The commands' simulated time [s] (a wall clock would make the wanted rate depend on the machine's load)."""

    def __init__(self):
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def _pose_error(robot, q, clock=None):
    err = []
    with robot:
        L = poses2lengths(q, robot.geom)
        for k in range(len(q)):
            if clock is not None:
                clock.t = k * DT
            robot.command_lengths(L[k])
            robot.read()
            err.append(np.linalg.norm(robot.pose[:3] - q[k, :3]))
    return float(np.sqrt(np.mean(np.square(err[300:]))))


def test_compensation_cuts_the_pose_error_of_the_play():
    q = _sine_poses()
    plain = _pose_error(SimRobot(params=SimRobotParams(backlash=W)), q)
    clock = _Clock()
    comp = _pose_error(BacklashCompensatedRobot(SimRobot(params=SimRobotParams(backlash=W)), W, DT, clock=clock), q,
                       clock)
    assert plain > 0.1e-3
    assert comp < plain / 5


def test_commands_keep_the_speed_and_length_limits():
    inner = LoggedDevice(SimRobot(params=SimRobotParams(backlash=W)))
    robot = BacklashCompensatedRobot(inner, W, DT)
    q = _sine_poses(800)
    with robot:
        spec = robot.spec
        L = poses2lengths(q, robot.geom)
        for k in range(len(q)):
            robot.command_lengths(L[k])
            r = robot.read()
            # the loop sees its own commands; the motor's steps show what the motor was sent
            np.testing.assert_array_equal(r.commanded_lengths, L[k])
            np.testing.assert_allclose(r.position_steps, np.rint((robot.L_home - inner.log[-2][1]) * spec.steps_per_m),
                                       atol=1)
    sent = np.array([a for name, a in inner.log if name == "command_lengths"])
    assert np.abs(np.diff(sent, axis=0)).max() <= spec.v_max * DT * (1 + 1e-9)
    assert sent.min() >= spec.l_min and sent.max() <= spec.l_max
    assert np.abs(sent - L).max() == pytest.approx(W / 2, rel=1e-6)    # half the play ahead, no more
    assert robot.compensation["width_mm"] == [0.5] * 6


def test_a_bad_command_still_reaches_the_robot_check():
    with BacklashCompensatedRobot(SimRobot(params=SimRobotParams(backlash=W)), W, DT) as robot:
        with pytest.raises(Exception, match="6 finite numbers"):
            robot.command_lengths([np.nan] * 6)


def test_readings_carry_lengths_the_loop_can_anchor_on():
    """After a FAULT reset the loop anchors on the reading's commanded lengths (Teleop.anchor, lengths2pose):
    through the compensation those are the loop's own, a pose's; the motor's (half the play apart) are none."""
    from teleop.core.errors import InfeasibleError
    from teleop.core.kinematics import lengths2pose

    q = _sine_poses(400)
    inner = SimRobot(params=SimRobotParams(backlash=W))
    with BacklashCompensatedRobot(inner, W, DT) as robot:
        L = poses2lengths(q, robot.geom)
        for k in range(len(q)):
            robot.command_lengths(L[k])
            r = robot.read()
        np.testing.assert_allclose(lengths2pose(r.commanded_lengths, robot.geom, guess=q[-1]), q[-1], atol=1e-9)
        with pytest.raises(InfeasibleError):
            lengths2pose(inner.L_cmd, robot.geom, guess=q[-1])
