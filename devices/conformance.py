"""One conformance check per interface, run over every implementation (Gymnasium's check_env idea).

    >>> from devices.conformance import check_haptic, check_robot
    >>> check_haptic(SimulatedStylus())            # raises ConformanceError naming the first broken rule
    >>> check_robot(open_device("sim://robot"))    # open_device: teleop.loop.devices_by_url

The device must be closed when given; the checks open and close it themselves.
"""

from __future__ import annotations

import math

import numpy as np

from devices.base import DeviceSpec, HapticDevice, HapticSample, Robot, RobotReading, RobotSpec


class ConformanceError(AssertionError):
    """A device broke one of the interface's rules."""


def _require(cond, what: str, dev) -> None:
    if not cond:
        raise ConformanceError(f"{type(dev).__name__}: {what}")


def _finite(a, shape) -> bool:
    a = np.asarray(a, dtype=float)
    return a.shape == shape and bool(np.isfinite(a).all())


def _context_rules(dev) -> None:
    _require(not getattr(dev, "is_open", False), "__init__ must not open the device", dev)
    with dev as d:
        _require(d is dev, "__enter__ returns the device", dev)
        _require(getattr(dev, "is_open", True), "is_open after __enter__", dev)
        with dev:  # idempotent: entering an open device is a no-op
            pass
    _require(not getattr(dev, "is_open", False), "closed after __exit__", dev)
    dev.__exit__(None, None, None)  # exiting a closed device is a no-op


def check_haptic(dev, reads: int = 5) -> None:
    """HapticDevice rules: protocol, SI spec, context manager, finite samples, force commands."""
    _require(isinstance(dev, HapticDevice), "implements the HapticDevice protocol", dev)
    spec = dev.spec
    _require(isinstance(spec, DeviceSpec), "spec is a DeviceSpec", dev)
    _require((np.asarray(spec.workspace_min) < np.asarray(spec.workspace_max)).all(), "workspace min < max", dev)
    _require(0 < spec.max_force_continuous <= spec.max_force_peak, "0 < continuous force <= peak force", dev)
    _require(spec.max_stiffness > 0 and spec.rate_hz > 0, "stiffness and rate > 0", dev)
    _context_rules(dev)
    with dev:
        last_t = -math.inf
        for _ in range(reads):
            s = dev.read()
            _require(isinstance(s, HapticSample), "read() returns a HapticSample", dev)
            _require(_finite(s.measured_cp, (3,)), "measured_cp is 3 finite numbers [m]", dev)
            _require(_finite(s.measured_cv, (3,)), "measured_cv is 3 finite numbers [m/s]", dev)
            R = np.asarray(s.orientation, dtype=float)
            _require(_finite(R, (3, 3)) and np.allclose(R @ R.T, np.eye(3), atol=1e-6),
                     "orientation is a rotation matrix", dev)
            _require(isinstance(s.buttons, (int, np.integer)) and s.buttons >= 0, "buttons is a bit mask", dev)
            _require(isinstance(s.operator_present, (bool, np.bool_)), "operator_present is a bool", dev)
            _require(math.isfinite(s.t) and s.t >= last_t, "sample times finite and non-decreasing", dev)
            last_t = s.t
            dev.servo_cf(np.zeros(3))
        dev.servo_cf([0.1, -0.1, 0.05])
        dev.servo_cf(np.array([np.nan, 0.0, 0.0]))  # must not raise and must not apply NaN
        try:
            dev.servo_cf(np.zeros(2))
        except (ValueError, RuntimeError):
            pass
        else:
            raise ConformanceError(f"{type(dev).__name__}: servo_cf of a wrong-shaped force must raise")
        dev.servo_cf(np.zeros(3))
    try:
        dev.read()
    except (ValueError, RuntimeError):
        pass
    else:
        raise ConformanceError(f"{type(dev).__name__}: read() after close() must raise")


def check_robot(robot, reads: int = 5) -> None:
    """Robot rules: protocol, spec, context manager, readings with the documented shapes, commands, stop."""
    _require(isinstance(robot, Robot), "implements the Robot protocol", robot)
    _context_rules(robot)
    with robot:
        spec = robot.spec
        _require(isinstance(spec, RobotSpec), "spec is a RobotSpec", robot)
        _require(0 < spec.l_min < spec.l_max and spec.v_max > 0 and spec.steps_per_m > 0, "spec limits", robot)
        last_seq = -math.inf
        r = None
        for _ in range(reads):
            r = robot.read()
            _require(isinstance(r, RobotReading), "read() returns a RobotReading", robot)
            n = spec.n_cables
            for name in ("fsr_counts", "position_steps", "commanded_lengths"):
                _require(_finite(getattr(r, name), (n,)), f"{name} is {n} finite numbers", robot)
            _require(np.all(np.asarray(r.fsr_counts) >= 0) and np.all(np.asarray(r.fsr_counts) <= spec.adc_max),
                     "fsr_counts within [0, adc_max]", robot)
            _require(isinstance(r.seq, (int, np.integer)) and r.seq >= last_seq, "seq is a non-decreasing int",
                     robot)
            _require(isinstance(r.boot_id, (int, np.integer)) and isinstance(r.status, (int, np.integer)),
                     "boot_id and status are ints", robot)
            _require(r.wrench_truth is None or _finite(r.wrench_truth, (6,)), "wrench_truth None or 6 numbers",
                     robot)
            last_seq = r.seq
            robot.command_lengths(np.asarray(r.commanded_lengths, dtype=float))
        for bad in (np.full(n, np.nan), np.zeros(n - 1)):
            try:
                robot.command_lengths(bad)
            except (ValueError, RuntimeError):
                pass
            else:
                raise ConformanceError(f"{type(robot).__name__}: a NaN or wrong-sized length command must raise")
        robot.stop()
        robot.read()
