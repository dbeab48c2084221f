"""In-test fakes: a robot (Robot protocol) with fault injection - an ideal CDPR that reaches commanded lengths
at once, with a pad at z >= z_pad of stiffness k and linear "FSR" counts (1 count = 0.01 N) - and the
matching linear estimator, so loop tests exercise the loop, not the sensor model."""

from __future__ import annotations

import numpy as np

from devices.base import ContextDevice, DeviceError, RobotReading, RobotSpec
from teleop.core.geometry import default_geometry
from teleop.core.kinematics import length_jacobian, pose2lengths, structure_matrix
from teleop.core.tension import wrench2tensions

N_PER_COUNT = 0.01


class FakeRobot(ContextDevice):
    """Ideal robot. Fault injection attributes: `frozen` (telemetry seq stops), `boot_id`, `status`,
    `fail_read` / `fail_command` (exceptions), `nan_counts`, `tension_offset` (6,) [N], `stuck` (cable index
    whose tension rises with paid-out length)."""

    def __init__(self, z_pad: float = 0.002, k_pad: float = 300.0, pretension: float = 1.0, seed: int = 0):
        self.spec = RobotSpec(name="fake CDPR")
        self.geom = default_geometry()
        self.z_pad, self.k_pad, self.pretension = z_pad, k_pad, pretension
        self.seed = seed
        self.is_open = False
        self.L0 = pose2lengths(np.zeros(6), self.geom)
        self.Jp_pinv = np.linalg.pinv(length_jacobian(np.zeros(6), self.geom)[:, :3])
        self.frozen = False
        self.silent = False
        self.boot_id = 7
        self.status = 1
        self.fail_read = None
        self.fail_command = None
        self.nan_counts = False
        self.tension_offset = np.zeros(6)
        self.stuck = None
        self.commands = []
        self.stops = 0

    def open(self):
        self.L = self.L0.copy()
        self.L_stuck0 = self.L0.copy()
        self.seq = 0
        self.t = 0.0
        self.is_open = True

    def close(self):
        self.is_open = False

    def command_lengths(self, lengths):
        if self.fail_command is not None:
            raise self.fail_command
        L = np.asarray(lengths, dtype=float)
        if L.shape != (6,) or not np.isfinite(L).all():
            raise DeviceError(f"bad length command {L}")
        self.commands.append(L.copy())
        self.L = L

    def stop(self):
        self.stops += 1

    def position(self):
        return self.Jp_pinv @ (self.L - self.L0)

    def tensions(self):
        p = self.position()
        f = np.zeros(6)
        if p[2] > self.z_pad:
            f[2] = -self.k_pad * (p[2] - self.z_pad)  # the pad pushes the tool back (-z)
        key = (tuple(np.round(p, 9)), f[2])
        if key != getattr(self, "_key", None):  # tension distribution only when something changed
            A = structure_matrix(np.r_[p, 0.0, 0.0, 0.0], self.geom)  # the fake holds the home orientation
            self._key, self._t = key, wrench2tensions(f, A, 0.05, 9.0, t_ref=self.pretension)
        t = self._t.copy()
        if self.stuck is not None:
            t[self.stuck] += 400.0 * max(0.0, self.L[self.stuck] - self.L_stuck0[self.stuck])
        return t + self.tension_offset

    def read(self):
        if self.fail_read is not None:
            raise self.fail_read
        if self.silent:
            return None
        if not self.frozen:
            self.seq += 1
            self.t += 0.001
        t = self.tensions()
        counts = np.clip(np.round(t / N_PER_COUNT), 0, self.spec.adc_max)
        if self.nan_counts:
            counts = counts * np.nan
        steps = np.round(self.L * self.spec.steps_per_m)
        return RobotReading(t=self.t, seq=self.seq, fsr_counts=counts, position_steps=steps,
                            commanded_lengths=self.L.copy(), status=self.status, boot_id=self.boot_id,
                            extras={"tensions_true": t})


class LinearEstimator:
    """counts * 0.01 N -> tensions; f = -A t at the pose (the fake robot's sensor model inverted)."""

    def __init__(self, geom=None):
        self.geom = geom or default_geometry()
        self.resets = 0

    def reset(self):
        self.resets += 1

    def update(self, reading, pose, dt):
        t = np.asarray(reading.fsr_counts, dtype=float) * N_PER_COUNT
        return t, -(structure_matrix(pose, self.geom) @ t)

    def describe(self):
        return {"estimator": "linear", "N_per_count": N_PER_COUNT}


def record_session(path, ticks: int = 400, robot=None, script=None, params=None):
    """Record `ticks` ticks of the loop on a manual clock straight into an MCAP file (no process, no pacing):
    sim stylus + fake robot + linear estimator. Returns the Teleop."""
    from devices.simulated import OperatorParams, Script, SimulatedStylus
    from teleop.loop import Teleop
    from teleop.loop.tap import RowTap, numeric_extras, session_layout
    from teleop.io.recording import SessionWriter

    class Clock:
        t = 0.0

        def __call__(self):
            return self.t

    clock = Clock()
    stylus = SimulatedStylus(script or Script(kind="pokes", axis=(0.0, 0.0, -1.0), amplitude=0.016, period=0.4),
                             OperatorParams(), seed=3, clock=clock)
    robot = robot or FakeRobot(z_pad=0.001)
    with stylus, robot, open(path, "wb") as fh:
        tp = Teleop(stylus, robot, params, estimator=LinearEstimator())
        first = robot.read()
        extras = numeric_extras(first)
        layout = session_layout(extras)
        meta = {"configuration": {"loop": tp.params.as_dict(), "haptic_spec": vars(stylus.spec),
                                  "robot_spec": vars(robot.spec)},
                "calibration": tp.estimator.describe(), "firmware_version": "fake", "software_version": "test"}
        w = SessionWriter(fh, layout, meta, t0_ns=0)
        tp.tap = RowTap(layout, w.write_row, extras)
        tp.start(0.0)
        for k in range(ticks):
            clock.t = k * 1e-3
            tp.tick(k * 1e-3)
            if k % 50 == 49:
                w.flush()
        w.finish({"drops": 0})
    return tp
