"""Raw robot readings -> (tensions, wrench): the loop-facing estimator (teleop.loop.compute.Estimator protocol).

    est = ReadingEstimator(geom, "dynamic")          # or non_compensated | single | double (needs turn=...)
    t, f = est.update(reading, pose, dt)             # reading: devices.base.RobotReading
    desc = est.describe(); est2 = ReadingEstimator.rebuild(desc, geom)   # stored with sessions, for replay

FSR counts -> tensions with the branch from the reading's direction (teleop.sensors.FsrConverter), then the
fast per-tick estimate of `TickComputer.estimate` (capstan / turn / friction compensation, f = -A t,
steady-state Kalman) at the commanded pose. Cable lengths come from the pose (inverse kinematics), i.e.
the lengths the loop commands.
"""

from __future__ import annotations

from dataclasses import asdict, fields

import numpy as np

from teleop.estimation.estimators import DynamicParams
from teleop.estimation.kalman import KalmanNoise
from teleop.estimation.tick import TickComputer
from teleop.estimation.turn import AxisTurnFit, TurnCompensation
from teleop.geometry import Geometry
from teleop.sensors import FsrCalibration, FsrConverter, default_fsr_calibration


class ReadingEstimator:
    """One of the four named estimators behind the loop's reading interface (see module docstring)."""

    def __init__(self, geom: Geometry, name: str = "dynamic", *, cal: FsrCalibration | None = None,
                 turn: TurnCompensation | None = None, dynamic: DynamicParams = DynamicParams(),
                 kalman: KalmanNoise | None = KalmanNoise(), deadband_counts: float = 8.0):
        self.geom = geom
        self.name = name
        self.cal = cal if cal is not None else default_fsr_calibration()
        self.turn, self.dynamic, self.kalman_noise = turn, dynamic, kalman
        self.deadband_counts = float(deadband_counts)
        self.converter = FsrConverter(self.cal, n=len(geom.B), deadband_counts=deadband_counts)
        self.tick = TickComputer(geom, name, turn=turn, dynamic=dynamic, kalman=kalman)

    def reset(self) -> None:
        self.converter.reset()
        self.tick.reset()

    def update(self, reading, pose, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(tensions (6,) [N] at the FSRs, wrench (6,) [N, N m] in {B})."""
        t = self.converter.update(reading.fsr_counts)
        _, w = self.tick.estimate(pose, t, dt)
        return t, np.array(w)

    def describe(self) -> dict:
        """JSON-able settings (calibration, estimator, noise model, fits) for the session metadata."""
        cal = {f.name: getattr(self.cal, f.name) for f in fields(self.cal) if f.init}
        cal = {k: list(v) if isinstance(v, tuple) else v for k, v in cal.items()}
        turn = None if self.turn is None else [
            {"axis": f.axis, "duration": f.duration, "deadband": f.deadband,
             "forward": [list(c) for c in f.forward], "backward": [list(c) for c in f.backward]}
            for f in self.turn.axes]
        return {"estimator": "ReadingEstimator", "name": self.name, "fsr": cal,
                "deadband_counts": self.deadband_counts, "dynamic": asdict(self.dynamic),
                "kalman": None if self.kalman_noise is None else asdict(self.kalman_noise), "turn": turn}

    @staticmethod
    def rebuild(desc: dict, geom: Geometry) -> "ReadingEstimator":
        """The estimator a session recorded (`describe()` output)."""
        cal = FsrCalibration(**{k: tuple(v) if isinstance(v, list) else v for k, v in desc["fsr"].items()})
        turn = None if desc.get("turn") is None else TurnCompensation(tuple(
            AxisTurnFit(axis=int(f["axis"]), duration=float(f["duration"]), deadband=float(f["deadband"]),
                        forward=tuple(tuple(c) for c in f["forward"]),
                        backward=tuple(tuple(c) for c in f["backward"])) for f in desc["turn"]))
        kal = None if desc.get("kalman") is None else KalmanNoise(**desc["kalman"])
        return ReadingEstimator(geom, desc["name"], cal=cal, turn=turn, dynamic=DynamicParams(**desc["dynamic"]),
                                kalman=kal, deadband_counts=float(desc["deadband_counts"]))
