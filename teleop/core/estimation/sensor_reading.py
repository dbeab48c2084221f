"""Robot readings of the FBG sensor kinds -> tip-side cable tensions -> wrench (the loop's Estimator protocol;
the FSR array is teleop.core.estimation.reading.ReadingEstimator, `make_estimator` picks by kind).

    est = make_estimator(geom, "one", "dynamic", model=ProximalDistalModel(0.84, 1.19), cable=0)
    t, f = est.update(reading, pose, dt)             # reading: devices.base.RobotReading with fbg_pm

Per kind (teleop.core.sensors.SENSOR_KINDS; docs/formats.md "Robot readings: sensor kinds"):
- fbg: every cable's distal FBG, temperature compensated by seed 001 eq 3 (teleop.core.sensors.fbg_tensions:
  F = (dl2 - r dl1) / S), is the cable's tension at the end effector.
- one: the FSR array's proximal tensions (ReadingEstimator's FSR chain, loading/unloading branches) go
  through seed 001 eq 7 (ProximalDistalModel.step: the distal tension stays flat between the pulling line
  Kp Fp + bp and the releasing line Kr Fp + br, a play operator per cable), with Kp, Kr identified on the
  instrumented cable (`identify_one_sensor`, or a `teleop calibrate one-sensor` file); that cable's own
  distal tension is its FBG's (eq 3).
  Rest identification (`update`, while the robot has not moved since the first reading or a reset): eq 7
  says where a cable's distal tension lies only once the cable has been pulled or released onto a line; at
  rest it holds anywhere between the two lines (static friction), so the modelled cables' start cannot come
  from eq 7 (its lower line, Kp Fp, reads a pretensioned sheath in its neutral state, Fd = Fp, Kp-fold low).
  All cables were brought to rest the same way, so at rest the instrumented cable's distal/proximal ratio
  rho = sum Fd / sum Fp over the rest readings (clipped to the band [min(Kp, Kr), max(Kp, Kr)]) is every
  cable's: a modelled cable's eq 7 state is rho times its mean proximal tension at rest. The first commanded
  length change (the robot moves, e.g. once ENABLED) ends it; eq 7 then runs on from that state.
Both give tip-side tensions: no sheath is left between them and the end effector, so the sheath friction
compensation of the named estimators (single, double, dynamic) has nothing to remove; every name runs the
shared rest of the estimate (f = -A t at the commanded pose, the steady-state Kalman: the non_compensated
kernel of teleop.core.estimation.tick). The name is kept so results line up with the FSR estimators.
"""

from __future__ import annotations

import math
from dataclasses import asdict

import numpy as np

from teleop.core.errors import InputError
from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.tick import TickComputer
from teleop.core.geometry import Geometry
from teleop.core.kernels import sensor as KS
from teleop.core.sensors import (FbgParams, FsrCalibration, ProximalDistalModel, check_sensor_kind, fbg_tensions,
                            fit_proximal_distal_origin)


class FbgReadingEstimator:
    """Estimator of sensor kinds "fbg" and "one" (module docstring). `name` is kept for the record."""

    def __init__(self, geom: Geometry, kind: str, name: str = "dynamic", *, fbg: FbgParams = FbgParams(),
                 model: ProximalDistalModel | None = None, cable: int = 0, cal: FsrCalibration | None = None,
                 kalman: KalmanNoise | None = KalmanNoise(), deadband_counts: float = 8.0):
        check_sensor_kind(kind, "estimator")
        if kind == "fsr":
            raise InputError("FbgReadingEstimator: sensor kind 'fsr' is ReadingEstimator's (make_estimator)")
        self.geom, self.kind, self.name = geom, kind, name
        self.n = len(geom.B)
        if kind == "one":
            if model is None:
                raise InputError("sensor kind 'one' needs the eq 7 model of its instrumented cable "
                                 "(identify_one_sensor, or a `teleop calibrate one-sensor` file)")
            if not 0 <= cable < self.n:
                raise InputError(f"sensor kind 'one': cable must be 0..{self.n - 1}, got {cable}")
        self.fbg, self.model, self.cable = fbg, model, int(cable)
        self.kalman_noise = kalman
        # the FSR chain of the proximal tensions (its Kalman and compensation are not used)
        self.fsr = ReadingEstimator(geom, "non_compensated", cal=cal, kalman=None,
                                    deadband_counts=deadband_counts) if kind == "one" else None
        self.tick = TickComputer(geom, "non_compensated", kalman=kalman)
        self._t = np.zeros(self.n)
        self.proximal = np.full(self.n, math.nan)  # one: the last reading's proximal FSR tensions [N]
        # compile (or load) the kernels now, not on the loop's first frame
        z = np.zeros((2, self.n))
        if kind == "fbg":
            KS.fbg_row(z, 1.0, 1.0, self._t)
        else:
            KS.one_sensor_row(np.ones(self.n), np.full(self.n, math.nan), 1.0, 1.0, 0.0, 0.0, z, 0, 1.0, 1.0, self._t)
        self.reset()

    def reset(self) -> None:
        self._fd = np.full(self.n, math.nan)  # eq 7 state per cable: the last distal tension [N]
        # rest identification (module docstring): on until the commanded lengths leave those of its first reading
        self.at_rest = self.kind == "one"
        self._rest_L = None  # commanded lengths [m] of the first rest reading
        self._rest_fp = np.zeros(self.n)  # sums over the rest readings: proximal tensions [N]
        self._rest_fd = 0.0  # and the instrumented cable's distal (FBG) tension [N]
        self._rest_m = 0
        self.rest_ratio = math.nan  # rho: the identified distal/proximal ratio at rest (NaN: none yet)
        if self.fsr is not None:
            self.fsr.reset()
        self.tick.reset()

    @property
    def tensions(self) -> np.ndarray:
        """The last reading's tip-side tensions (n,) [N] (this estimator's buffer; on an FBG cable its eq 3)."""
        return self._t

    def tensions_into(self, fsr_counts, fbg_pm) -> np.ndarray:
        """Tip-side tensions [N] (this estimator's (n,) buffer) of one reading: FSR counts (n,) and Bragg
        shifts (2, n) [pm]; updates the eq 7 state."""
        t = self._t
        if fbg_pm is None:
            raise InputError(f"sensor kind '{self.kind}': the reading has no FBG shifts (fbg_pm); "
                             f"a robot with distal FBGs gives them (sim://robot?sensor={self.kind})")
        fbg = np.ascontiguousarray(fbg_pm, dtype=float)
        p = self.fbg
        if self.kind == "fbg":  # eq 3 per cable (kernel sensor.fbg_force)
            KS.fbg_row(fbg, p.r, p.S_pm_N, t)
            return t
        Fp = self.fsr.tensions_into(np.ascontiguousarray(fsr_counts, dtype=float))
        m = self.model  # eq 7 per cable (kernel sensor.eq7_step = ProximalDistalModel.step), the FBG's on its own
        KS.one_sensor_row(Fp, self._fd, m.Kp, m.Kr, m.bp, m.br, fbg, self.cable, p.r, p.S_pm_N, t)
        self.proximal[:] = Fp
        return t

    #: a commanded length change larger than this [m] ends the rest identification (the robot moved)
    REST_MOVE_M = 1e-6

    def rest_into(self, commanded_lengths, t: np.ndarray) -> np.ndarray:
        """One: the rest identification's step (module docstring) after `tensions_into` gave `t` (n,) [N] for
        a reading with `commanded_lengths` (n,) [m]: while at rest, add the reading to the sums and set each
        modelled cable's eq 7 state and tension in `t` to rho times its mean proximal tension. Returns t."""
        if not self.at_rest:
            return t
        L = np.asarray(commanded_lengths, dtype=float)
        if self._rest_L is None:
            self._rest_L = L.copy()
        elif np.max(np.abs(L - self._rest_L)) > self.REST_MOVE_M:
            self.at_rest = False  # moving: eq 7 runs on from the rest state
            return t
        c, m = self.cable, self.model
        self._rest_fp += self.proximal
        self._rest_fd += t[c]
        self._rest_m += 1
        lo, hi = min(m.Kp, m.Kr), max(m.Kp, m.Kr)
        self.rest_ratio = rho = min(max(self._rest_fd / self._rest_fp[c], lo), hi)
        others = np.arange(self.n) != c
        self._fd[others] = rho * self._rest_fp[others] / self._rest_m
        t[others] = self._fd[others]
        return t

    def update(self, reading, pose, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(tip-side tensions (n,) [N], wrench (6,) [N, N m] in {B}) of a RobotReading at the commanded pose
        (sensor kind one: with the rest identification's step, `rest_into`, on its commanded lengths)."""
        t = self.tensions_into(reading.fsr_counts, reading.fbg_pm)
        if self.kind == "one":
            self.rest_into(reading.commanded_lengths, t)
        out = self.tick.estimate_into(np.ascontiguousarray(pose, dtype=float), t, float(dt))
        return t.copy(), out[1, :6].copy()

    @property
    def compensated(self) -> np.ndarray:
        """(n,) [N] the last update's tip-side tensions (a view of the tick's buffer)."""
        return self.tick.out[2, :self.n]

    def describe(self) -> dict:
        """JSON-able settings for the session metadata."""
        return {"estimator": "FbgReadingEstimator", "sensor": self.kind, "name": self.name, "fbg": asdict(self.fbg),
                "one_sensor": None if self.model is None else asdict(self.model), "cable": self.cable,
                "fsr": None if self.fsr is None else self.fsr.describe()["fsr"],
                "kalman": None if self.kalman_noise is None else asdict(self.kalman_noise)}


def make_estimator(geom: Geometry, kind: str = "fsr", name: str = "dynamic", **kw):
    """The loop's estimator for sensor `kind`: ReadingEstimator (fsr; `kw` as its own) or FbgReadingEstimator
    (fbg, one: `fbg`, `model`, `cable`, `cal`, `kalman` accepted; the FSR estimators' `turn` and `dynamic`
    have nothing to act on and are dropped)."""
    check_sensor_kind(kind, "estimator")
    if kind == "fsr":
        return ReadingEstimator(geom, name, **{k: v for k, v in kw.items() if k not in ("fbg", "model", "cable")})
    return FbgReadingEstimator(geom, kind, name, **{k: v for k, v in kw.items() if k not in ("turn", "dynamic")})


def cable_direction(lengths) -> np.ndarray:
    """(m,) per-sample direction of one cable from its lengths (m,) [m]: +1 hauled in (shortening, the
    seed's pulling phase), -1 paid out, the previous sample's while it holds still (+1 at the start)."""
    d = np.sign(-np.diff(np.asarray(lengths, dtype=float), prepend=np.asarray(lengths, dtype=float)[0]))
    for k in range(d.size):  # carry the last direction over holds
        if d[k] == 0:
            d[k] = d[k - 1] if k else 1.0
    return d


def identify_one_sensor(fsr_tension, fbg_pm, lengths, cable: int = 0, fbg: FbgParams = FbgParams()) -> ProximalDistalModel:
    """Seed 001's identification on the instrumented cable: Kp, Kr (lines through the origin, eqs 4-7) from its
    proximal FSR tension (m,) [N], its Bragg shifts fbg_pm (m, 2, n) [pm] and its commanded lengths (m,) [m]
    (the direction of each sample: teleop.core.sensors.fit_proximal_distal_origin)."""
    fd = fbg_tensions(np.asarray(fbg_pm, dtype=float), fbg)[:, cable]
    return fit_proximal_distal_origin(fsr_tension, fd, cable_direction(lengths))


def estimate_trace(trace, geom: Geometry, dt: float, kind: str, names, *, fbg: FbgParams = FbgParams(),
                   model: ProximalDistalModel | None = None, cable: int = 0, cal: FsrCalibration | None = None,
                   kalman: bool = True, progress=None, tensions_out: np.ndarray | None = None) -> dict:
    """{name: (m, 6) wrench} of a SimTrace (counts, fbg_pm, poses) for sensor kind fbg or one: the numbers of
    FbgReadingEstimator.update reading by reading (every name the same array: module docstring).
    tensions_out: (m, n) array to receive the tip-side tensions [N] if given."""
    est = FbgReadingEstimator(geom, kind, fbg=fbg, model=model, cable=cable, cal=cal,
                              kalman=KalmanNoise(dt=dt) if kalman else None)
    w = np.empty((len(trace.t), 6))
    poses = np.ascontiguousarray(trace.poses, dtype=float)
    for k in range(len(trace.t)):
        t = est.tensions_into(trace.counts[k], trace.fbg_pm[k])
        if tensions_out is not None:
            tensions_out[k] = t
        w[k] = est.tick.estimate_into(poses[k], t, dt)[1, :6]
        if progress is not None and k % 1000 == 999:
            progress(1000)
    return {n: w for n in names}
