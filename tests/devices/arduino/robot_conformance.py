"""A standard check sequence for any devices.base.Robot (Gymnasium check_env style), reusable by every
backend's tests:

    from arduino.robot_conformance import check_robot   # tests/devices is on sys.path under pytest
    check_robot(make_robot, prepare=lambda r: r.home(lengths))

Covers: protocol membership, __init__ touches nothing, open/read/command/read/stop/close, readings'
shapes and types, bad commands (NaN, inf, wrong shape, outside the spec's limits) refused with
ValueError, close twice, re-open after close, `with` on an already open device.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from devices.base import Robot, RobotReading


def _check_reading(reading, n: int, t_prev: float | None) -> float:
    assert isinstance(reading, RobotReading), f"read() returned {type(reading).__name__}, not RobotReading"
    assert math.isfinite(reading.t), "reading.t must be finite"
    if t_prev is not None:
        assert reading.t >= t_prev, f"reading.t went backwards ({reading.t} < {t_prev})"
    assert isinstance(reading.seq, (int, np.integer))
    for name in ("fsr_counts", "position_steps", "commanded_lengths"):
        value = np.asarray(getattr(reading, name))
        assert value.shape == (n,), f"reading.{name} has shape {value.shape}, expected ({n},)"
    assert np.all(np.asarray(reading.fsr_counts) >= 0)
    assert isinstance(reading.status, (int, np.integer))
    return reading.t


def check_robot(make: Callable[[], Robot], prepare: Callable[[Robot], None] | None = None,
                lengths=None) -> None:
    """Run the standard sequence on fresh instances from `make`; raises AssertionError on a violation.

    Args:
        make: builds an unopened robot.
        prepare: called after open, before commanding (e.g. homing); None when not needed.
        lengths: (n,) a safe cable-length command [m]; default the middle of the spec's range.
    """
    robot = make()
    assert isinstance(robot, Robot), f"{type(robot).__name__} does not follow devices.base.Robot"
    spec = robot.spec
    n = spec.n_cables
    target = np.full(n, 0.5 * (spec.l_min + spec.l_max)) if lengths is None else np.asarray(lengths, float)
    assert not getattr(robot, "is_open", False), "__init__ must not open the device"

    with robot as r:
        assert r is robot and robot.is_open
        t = _check_reading(robot.read(), n, None)
        if prepare is not None:
            prepare(robot)
        robot.command_lengths(target)
        t = _check_reading(robot.read(), n, t)
        for bad in (np.full(n, np.nan), np.full(n, np.inf), np.zeros(n + 1),
                    np.full(n, spec.l_max + 0.01), np.full(n, spec.l_min - 0.001)):
            try:
                robot.command_lengths(bad)
            except ValueError:
                pass
            else:
                raise AssertionError(f"command_lengths({bad.tolist()}) was accepted")
        robot.stop()
        _check_reading(robot.read(), n, t)
    assert not robot.is_open
    robot.close()  # closing twice is harmless
    assert not robot.is_open

    robot.open()  # re-open after close; `with` on an open device neither reopens nor fails
    with robot as r:
        assert r is robot and robot.is_open
        _check_reading(robot.read(), n, None)
    assert not robot.is_open
