"""Replay a recorded session through the loop and check it reproduces: same inputs (recorded stylus samples,
robot readings and tick times) -> the same state changes, cable-length commands, estimate (tensions, wrench)
and stylus forces, bit for bit.

Sessions of the FBG sensor kinds (`sim://robot?sensor=fbg|one`) replay too: their estimator
(teleop.core.estimation.sensor_reading.FbgReadingEstimator) is rebuilt from the recorded settings and each
recorded robot reading gets back its Bragg shifts from the session's /sensors/fbg channel (`FbgReplayRobot`),
so the shifts run through the same estimator (seed 001 eq 3, and for `one` the rest identification and eq 7)
as in the session. The recording's floats are bit-exact (teleop.io.recording.layout.RowEncoder), so no
tolerance is needed: any difference is a replay that does not reproduce.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from devices.replay import ReplayRobot, ReplayStylus
from teleop.core.errors import InputError
from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.sensor_reading import FbgReadingEstimator
from teleop.core.geometry import Geometry, default_geometry
from teleop.loop.core import Teleop
from teleop.loop.params import LoopParams
from teleop.core.mapping import MappingParams
from teleop.core.sensors import FbgParams, FsrCalibration, ProximalDistalModel
from teleop.io.recording import read_session
from teleop.io.recording import TOPIC_FORCE, TOPIC_SETPOINT
from teleop.io.recording.sensors import TOPIC_FBG


@dataclass
class ReplayReport:
    """Outcome of a replay.

    Attributes:
        ticks: ticks replayed.
        force_mismatches, command_mismatches, state_mismatches: ticks whose stylus force, length command or
            state differ from the recording.
        max_force_diff: largest |force difference| [N]; max_length_diff: largest |length difference| [m].
        damage: the reader's damage note ('' for an intact file).
        estimate_mismatches: ticks whose estimate (/estimation tensions or measured_cf) differs from the
            recording; max_wrench_diff: largest |wrench difference| [N, N m] (0 when /estimation is absent).
    """

    ticks: int
    force_mismatches: int
    command_mismatches: int
    state_mismatches: int
    max_force_diff: float
    max_length_diff: float
    damage: str
    estimate_mismatches: int = 0
    max_wrench_diff: float = 0.0

    @property
    def reproduced(self) -> bool:
        return self.ticks > 0 and not (self.force_mismatches or self.command_mismatches or self.state_mismatches
                                       or self.estimate_mismatches)


def params_from(conf: dict) -> LoopParams:
    """LoopParams from a recording's configuration["loop"]."""
    d = dict(conf)
    m = d.pop("mapping", {})
    try:
        mapping = MappingParams(**{k: np.array(v) if isinstance(v, list) else v for k, v in m.items()})
        return LoopParams(mapping=mapping, **d)
    except TypeError as exc:
        raise InputError(f"recording configuration: loop parameters not understood ({exc})") from None


def geometry_from(conf: dict | None) -> Geometry:
    if not conf:
        return default_geometry()
    return Geometry(**{k: np.array(v) if isinstance(v, list) else v for k, v in conf.items()})


def estimator_from(desc: dict, geom: Geometry):
    """Rebuild the recorded estimator (by its describe() name)."""
    name = desc.get("estimator")
    if name == "ReadingEstimator":
        return ReadingEstimator.rebuild(desc, geom)
    if name == "FbgReadingEstimator":
        return fbg_estimator_from(desc, geom)
    raise InputError(f"recording: estimator '{name}' cannot be rebuilt for replay")


def _tuples(d: dict) -> dict:
    return {k: tuple(v) if isinstance(v, list) else v for k, v in d.items()}


def fbg_estimator_from(desc: dict, geom: Geometry) -> FbgReadingEstimator:
    """The FbgReadingEstimator a session recorded (its describe(): sensor kind, name, FBG parameters, the eq 7
    model and instrumented cable of kind one, its FSR calibration, the Kalman noise). The FSR chain's deadband
    is the constructor's unless the description carries `deadband_counts`."""
    try:
        kw = {} if desc.get("deadband_counts") is None else {"deadband_counts": float(desc["deadband_counts"])}
        return FbgReadingEstimator(
            geom, desc["sensor"], desc.get("name", "dynamic"), fbg=FbgParams(**desc["fbg"]),
            model=None if desc.get("one_sensor") is None else ProximalDistalModel(**desc["one_sensor"]),
            cable=int(desc.get("cable", 0)),
            cal=None if desc.get("fsr") is None else FsrCalibration(**_tuples(desc["fsr"])),
            kalman=None if desc.get("kalman") is None else KalmanNoise(**desc["kalman"]), **kw)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"recording: FBG estimator settings not understood ({type(exc).__name__}: {exc})") from None


class FbgReplayRobot(ReplayRobot):
    """The recorded robot with its FBG readings: each /robot/measured reading gets back the Bragg shifts the
    session recorded for its tick on TOPIC_FBG, as `fbg_pm` (2, n) [pm] (row 0 FBG1, row 1 FBG2; NaN on a cable
    without an FBG, as the robot gave them)."""

    def open(self) -> None:
        super().open()
        fbg = {int(m["tick"]): m for m in self._messages(TOPIC_FBG)}
        self.fbg_missing = set()  # ticks with a reading but no FBG message (a recording cut inside their row)
        for k, i in self.by_tick.items():
            m = fbg.get(k)
            if m is None:
                self.fbg_missing.add(k)
                continue
            rd = self.items[i]
            pm = np.full((2, len(rd.fsr_counts)), math.nan)
            cables = np.atleast_1d(np.asarray(m["fbg_cable"], dtype=np.int64))  # a width-1 field is a number
            pm[0, cables] = m["fbg_dl1_pm"]
            pm[1, cables] = m["fbg_dl2_pm"]
            self.items[i] = replace(rd, fbg_pm=pm)


def _differs(a: np.ndarray, b: np.ndarray) -> bool:
    """True when a and b differ anywhere (NaN in both places counts as equal)."""
    return bool(((a != b) & ~(np.isnan(a) & np.isnan(b))).any())


def replay_session(path: str, estimator=None, session=None) -> ReplayReport:
    """Run the loop over a recording, tick by tick, and compare with what was recorded."""
    s = session if session is not None else read_session(path)
    meta = s.metadata.get("session")
    if meta is None:
        raise InputError(f"{path}: no session metadata (damaged at: {s.damage or 'unknown'})")
    conf = meta.get("configuration", {})
    params = params_from(conf.get("loop", {}))
    geom = geometry_from(conf.get("geometry"))
    est = estimator if estimator is not None else estimator_from(meta.get("calibration", {}), geom)
    loop_msgs = s.messages("/loop")
    forces = {m["tick"]: m["servo_cf"] for m in s.messages(TOPIC_FORCE)}
    commands = {m["tick"]: m["servo_jp"] for m in s.messages(TOPIC_SETPOINT) if m["commanded"]}
    estimates = {m["tick"]: (m["tensions"], m["measured_cf"]) for m in s.messages("/estimation")}
    # an FBG estimator reads the recorded shifts (a recording without /sensors/fbg: one clear line at open)
    robot_cls = FbgReplayRobot if isinstance(est, FbgReadingEstimator) else ReplayRobot
    haptic, robot = ReplayStylus(path, s), robot_cls(path, s)
    n_f = n_c = n_s = n_e = 0
    df = dl = dw = 0.0
    ticks = 0
    with haptic, robot:
        tp = Teleop(haptic, robot, params, geom=geom, estimator=est)
        first_t = loop_msgs[0]["t"] if loop_msgs else 0.0
        tp.start(0.0 if first_t >= 0 else first_t)
        for m in loop_msgs:
            k = m["tick"]
            if k not in forces or k in getattr(robot, "fbg_missing", ()):
                break  # the recording ends inside this tick's row (damaged tail; the FBG channel is its last)
            haptic.sync(k)
            robot.sync(k)
            tp.k = k
            x = tp.tick(m["t"])
            ticks += 1
            f = np.array(forces[k])
            d = float(np.max(np.abs(x.F - f)))
            df = max(df, d)
            n_f += bool((x.F != f).any())
            rec = commands.get(k)
            if (rec is None) != (x.L_cmd is None):
                n_c += 1
            elif rec is not None:
                dd = float(np.max(np.abs(x.L_cmd - np.array(rec))))
                dl = max(dl, dd)
                n_c += bool(dd != 0.0)
            n_s += int(tp.state) != int(m["state"])
            est = estimates.get(k)
            if est is not None:
                w = np.asarray(tp.wrench, dtype=float)
                rw = np.array(est[1], dtype=float)  # null (a NaN recorded) reads back as NaN
                dw = max(dw, float(np.nanmax(np.abs(w - rw), initial=0.0)))
                n_e += _differs(np.asarray(tp.tensions, dtype=float), np.array(est[0], dtype=float)) or _differs(w, rw)
    return ReplayReport(ticks, n_f, n_c, n_s, df, dl, s.damage, n_e, dw)
