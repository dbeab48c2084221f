"""Raw robot readings -> (tensions, wrench): the loop-facing estimator (teleop.loop.compute.Estimator protocol).

    est = ReadingEstimator(geom, "dynamic")          # or non_compensated | single | double (needs turn=...)
    t, f = est.update(reading, pose, dt)             # reading: devices.base.RobotReading
    desc = est.describe(); est2 = ReadingEstimator.rebuild(desc, geom)   # stored with sessions, for replay

FSR counts -> tensions with the branch from the reading's direction (the numbers of
teleop.core.sensors.FsrConverter, computed here on plain floats), then the fast per-tick estimate of
`TickComputer.estimate` (capstan / turn / friction compensation, f = -A t, steady-state Kalman) at the
commanded pose. Cable lengths come from the pose (inverse kinematics), i.e. the lengths the loop commands.
`update_arrays` is the loop's hot path (LoopTick.estimate; `dynamic` in one compiled call); `update_floats` takes
and gives lists; `update` wraps it in numpy for the protocol.
"""

from __future__ import annotations

from dataclasses import asdict, fields

import numpy as np

from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.estimators import DynamicParams
from teleop.core.estimation.tick import TickComputer
from teleop.core.estimation.turn import AxisTurnFit, TurnCompensation
from teleop.core.geometry import Geometry
from teleop.core.kernels.estimate import counts_tensions
from teleop.core.kernels.jit import bind, f64c
from teleop.core.sensors import LOADING, UNLOADING, FsrCalibration, default_fsr_calibration


# the counts the compiled path takes as they are (an ADC's integers, or floats; the kernels are warmed for both)
_COUNT_DTYPES = (np.dtype(np.int64), np.dtype(np.float64))


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
        self.n = len(geom.B)
        self.tick = TickComputer(geom, name, turn=turn, dynamic=dynamic, kalman=kalman)
        # an ADC gives integer counts: the tension of every count on each branch, computed once by the same
        # per-float conversion (`_tension1`), so a tick looks it up (non-integer counts still compute it)
        n_counts = int(self.cal.adc_max) + 1 if 0 < self.cal.adc_max <= 65535 else 0
        self._table = np.array([[self._tension1(float(c), b) for c in range(n_counts)] for b in (LOADING, UNLOADING)],
                               dtype=float).reshape(2, n_counts)
        self._counts = np.zeros(self.n)
        self._t = np.zeros(self.n)
        self._counts_call = self._counts_dtype = None  # update_arrays' kernel bound to the counts' dtype
        self._fixed, self._fixed_of = None, (None, None, None)  # its fixed arguments and the states they hold
        self.reset()

    def __getstate__(self) -> dict:
        """Pickled without the bound kernel (compiled code does not pickle; bound again at the next call)."""
        return {**self.__dict__, "_counts_call": None, "_counts_dtype": None, "_fixed": None,
                "_fixed_of": (None, None, None)}

    def _tension1(self, v: float, branch: int) -> float:
        """Tension [N] of `v` counts on `branch` (FsrCalibration.counts_tension1)."""
        return self.cal.counts_tension1(v, branch)

    def reset(self) -> None:
        # FSR reading direction per cable (+1 rising, -1 falling, 0 not yet moved), extreme since the last flip
        self._fsr = np.zeros((2, self.n))
        self._fsr[1] = np.nan
        self.tick.reset()

    def tensions_into(self, counts: np.ndarray) -> np.ndarray:
        """Tensions [N] (the estimator's (n,) buffer) from raw FSR counts (n,) float64; updates the branch state.

        The numbers of teleop.core.sensors.FsrConverter.update: a Schmitt trigger on the counts picks the loading or
        unloading branch (teleop.core.kernels.estimate.counts_tensions); an integer count looks its tension up in the
        table, any other goes through counts -> conductance -> FsrCalibration.tension1.
        """
        t = self._t
        if counts_tensions(counts, self._fsr, self.deadband_counts, self._table, t):
            self._off_table(counts, t)
        return t

    def _off_table(self, counts: np.ndarray, t: np.ndarray) -> None:
        """The tensions counts_tensions left NaN (counts off the table) by the per-float conversion, on the branch
        it chose."""
        for i in np.flatnonzero(np.isnan(t)):
            t[i] = self._tension1(float(counts[i]), UNLOADING if self._fsr[0, i] < 0.0 else LOADING)

    def tensions(self, counts) -> list:
        """Tensions [N] (list) from raw FSR counts (any sequence of floats); updates the branch state."""
        self._counts[:] = counts
        return self.tensions_into(self._counts).tolist()

    def update_arrays(self, counts: np.ndarray, pose: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(tensions (n,) [N], wrench (6,) [N, N m] in {B}) from counts (n,) and pose (6,) float64 arrays: the
        loop's hot path. The results are this estimator's buffers (overwritten by the next update)."""
        tc = self.tick
        pose = f64c(pose)
        if tc.counts_kernel is None:
            t = self.tensions_into(np.ascontiguousarray(counts, dtype=float))
            return t, tc.estimate_into(pose, t, float(dt))[1, :6]
        dt = float(dt)
        a = self._fixed  # the kernel's fixed arguments held together (built again when reset replaced a state)
        if a is None or self._fsr is not self._fixed_of[0] or tc.st is not self._fixed_of[1] \
                or self.deadband_counts != self._fixed_of[2]:
            a = self._fixed = tc.counts_kernel[0](self._fsr, float(self.deadband_counts), self._table, self._t, tc.cab,
                                                  tc.c, tc.st, tc.kf, tc.turn, tc.coefs, tc.out)
            self._fixed_of = (self._fsr, tc.st, self.deadband_counts)
        call = self._counts_call  # the kernel bound to the counts' dtype (jit.bind), the other arguments ours
        if type(counts) is np.ndarray and counts.dtype is self._counts_dtype and counts.ndim == 1 \
                and counts.flags.c_contiguous:
            c = counts  # the usual case: the bound dtype (told by identity, before any comparison)
        else:
            c = counts if type(counts) is np.ndarray and counts.dtype in _COUNT_DTYPES and counts.ndim == 1 \
                and counts.flags.c_contiguous else np.ascontiguousarray(counts, dtype=float).reshape(-1)
            if c.dtype is not self._counts_dtype:
                call = self._counts_call = bind(tc.counts_kernel[1], c, a, pose, dt)
                self._counts_dtype = c.dtype
        # tensions_into and estimate_into in one compiled call (kernel estimate.counts_dynamic_fixed)
        if call(c, a, pose, dt):
            self._off_table(c, self._t)  # some counts off the table: converted here, then the estimate
            tc.estimate_into(pose, self._t, dt)
        return self._t, tc.out[1, :6]

    @property
    def compensated(self) -> np.ndarray:
        """(n,) [N] the last update's friction-compensated tip-side tensions (a view of the tick's buffer)."""
        return self.tick.out[2, :len(self.geom.B)]

    def update_floats(self, counts, pose, dt: float) -> tuple[list, list]:
        """(tensions [N], wrench [N, N m] in {B}) as lists of 6 floats from counts and pose (sequences)."""
        self._counts[:] = counts
        t = self.tensions_into(self._counts)
        tc = self.tick
        tc._pose[:] = pose
        out = tc.estimate_into(tc._pose, t, float(dt))
        return t.tolist(), out[1, :6].tolist()

    def update(self, reading, pose, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(tensions (6,) [N] at the FSRs, wrench (6,) [N, N m] in {B})."""
        t, w = self.update_floats(np.asarray(reading.fsr_counts, dtype=float).tolist(),
                                  np.asarray(pose, dtype=float).tolist(), dt)
        return np.array(t), np.array(w)

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
