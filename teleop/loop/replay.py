"""Replay a recorded session through the loop and check it reproduces: same inputs (recorded stylus samples,
robot readings and tick times) -> the same state changes, cable-length commands and stylus forces, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from devices.replay import ReplayRobot, ReplayStylus
from teleop.core.errors import InputError
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.geometry import Geometry, default_geometry
from teleop.loop.core import Teleop
from teleop.loop.params import LoopParams
from teleop.core.mapping import MappingParams
from teleop.io.recording import read_session
from teleop.io.recording import TOPIC_FORCE, TOPIC_SETPOINT


@dataclass
class ReplayReport:
    """Outcome of a replay.

    Attributes:
        ticks: ticks replayed.
        force_mismatches, command_mismatches, state_mismatches: ticks whose stylus force, length command or
            state differ from the recording.
        max_force_diff: largest |force difference| [N]; max_length_diff: largest |length difference| [m].
        damage: the reader's damage note ('' for an intact file).
    """

    ticks: int
    force_mismatches: int
    command_mismatches: int
    state_mismatches: int
    max_force_diff: float
    max_length_diff: float
    damage: str

    @property
    def reproduced(self) -> bool:
        return self.ticks > 0 and not (self.force_mismatches or self.command_mismatches or self.state_mismatches)


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
    raise InputError(f"recording: estimator '{name}' cannot be rebuilt for replay")


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
    haptic, robot = ReplayStylus(path, s), ReplayRobot(path, s)
    n_f = n_c = n_s = 0
    df = dl = 0.0
    ticks = 0
    with haptic, robot:
        tp = Teleop(haptic, robot, params, geom=geom, estimator=est)
        first_t = loop_msgs[0]["t"] if loop_msgs else 0.0
        tp.start(0.0 if first_t >= 0 else first_t)
        for m in loop_msgs:
            k = m["tick"]
            if k not in forces:
                break  # the recording ends inside this tick's row (damaged tail)
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
    return ReplayReport(ticks, n_f, n_c, n_s, df, dl, s.damage)
