"""The robot process starts with the compiled kernels ready: warmed in the parent before the fork, so the
child's first command does not load them (that load stalled a session's robot link ~20 ms after it was
enabled, past the 20 ms stale limit: every default `teleop session` faulted at t = 0.02 s)."""

import time

from scenes.sim_robot import home_pose
from teleop.core.geometry import default_geometry
from teleop.loop import warm
from teleop.core.kinematics import poses2lengths
from teleop.loop.devices_by_url import process_robot


def test_kernels_are_warmed_before_the_fork():
    warm._done.clear()   # as in a fresh process: nothing warmed yet
    with process_robot("sim://robot", rate_hz=500.0) as robot:
        assert warm._done == [True]
        first = robot.read()
        pose = home_pose()
        pose[2] += 1e-3
        robot.command_lengths(poses2lengths(pose[None, :], default_geometry())[0])   # the first motion
        deadline = time.monotonic() + 2.0
        while robot.read().seq <= first.seq + 3 and time.monotonic() < deadline:
            time.sleep(0.001)
        assert robot.read().seq > first.seq + 3
