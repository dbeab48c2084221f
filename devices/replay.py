"""`replay://FILE`: a recorded session played back as a device.

``replay://session.mcap`` (or ``replay:///abs/path.mcap``) is the stylus of the session: each read()
returns the next recorded /stylus sample (or, after `sync(tick)`, the sample of that tick); the forces it
is commanded are kept in `commanded` for comparison. ``?device=robot`` gives the robot side: each read()
returns the recorded /robot/measured reading (same sequence, counts, status, boot id, extras), and the
commanded lengths are kept. ``?timing=clock`` plays the stylus against the wall clock instead (for driving
a live robot with a recorded hand motion).
"""

from __future__ import annotations

import time

import numpy as np

from devices.base import TOUCH_SPEC, ContextDevice, DeviceError, DeviceSpec, HapticSample, RobotReading, RobotSpec
from teleop.core.errors import InputError
from teleop.io.recording import TOPIC_ROBOT, read_session


def _load(path: str):
    s = read_session(path)
    if not s.records:
        raise InputError(f"{path}: no messages could be read ({s.damage or 'empty recording'})")
    return s


def _spec_from(meta: dict, key: str, cls, default):
    d = (meta.get("session", {}).get("configuration", {}) or {}).get(key)
    if not isinstance(d, dict):
        return default
    try:
        return cls(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in d.items()
                      if k in cls.__dataclass_fields__})
    except TypeError:
        return default


def sample_from(m: dict) -> HapticSample:
    """HapticSample from a /stylus message."""
    return HapticSample(t=float(m["t_device"]), measured_cp=np.array(m["measured_cp"], dtype=float),
                        orientation=np.array(m["orientation"], dtype=float).reshape(3, 3),
                        measured_cv=np.array(m["measured_cv"], dtype=float), buttons=int(m["buttons"]),
                        operator_present=bool(m["operator_present"]))


def reading_from(m: dict) -> RobotReading:
    """RobotReading from a /robot/measured message (extras from its x_* fields)."""
    w = np.array(m["wrench_truth"], dtype=float)
    extras = {k[2:]: np.array(v, dtype=float) if isinstance(v, list) else float(v)
              for k, v in m.items() if k.startswith("x_")}
    return RobotReading(t=float(m["t_robot"]), seq=int(m["seq"]), fsr_counts=np.array(m["fsr_counts"], dtype=float),
                        position_steps=np.array(m["position_steps"], dtype=float),
                        commanded_lengths=np.array(m["commanded_lengths"], dtype=float), status=int(m["status"]),
                        boot_id=int(m["boot_id"]), wrench_truth=None if np.isnan(w).all() else w, extras=extras)


class _Player(ContextDevice):
    def __init__(self, path: str, session=None):
        self.path = path
        self.session = session
        self.is_open = False
        self.items: list = []
        self.by_tick: dict = {}

    def _messages(self, topic: str) -> list:
        if self.session is None:
            self.session = _load(self.path)
        msgs = self.session.messages(topic)
        if not msgs:
            raise InputError(f"{self.path}: recording has no {topic} messages")
        return msgs

    def close(self) -> None:
        self.is_open = False

    def sync(self, tick: int) -> None:
        """Play the item recorded at loop tick `tick` next (a replay keeps both devices on the same tick)."""
        self.i = self.by_tick.get(int(tick), -1)

    def _next(self):
        if not self.is_open:
            raise DeviceError(f"replay {self.path}: read() before open()")
        if self.i < 0:
            raise DeviceError(f"replay {self.path}: nothing recorded for this tick")
        if self.i >= len(self.items):
            raise DeviceError(f"replay {self.path}: end of recording ({len(self.items)} items)")
        item = self.items[self.i]
        self.i += 1
        return item


class ReplayStylus(_Player):
    """The recorded stylus (HapticDevice)."""

    def __init__(self, path: str, session=None, timing: str = "sequence", spec: DeviceSpec | None = None):
        super().__init__(path, session)
        if timing not in ("sequence", "clock"):
            raise InputError(f"replay://{path}: timing must be 'sequence' or 'clock', got '{timing}'")
        self.timing = timing
        self._spec = spec
        self.spec = spec or TOUCH_SPEC
        self.commanded: list = []

    def open(self) -> None:
        msgs = self._messages("/stylus")
        self.items = [sample_from(m) for m in msgs]
        self.ticks = np.array([m["tick"] for m in msgs])
        self.times = np.array([m["t"] for m in msgs], dtype=float)
        self.by_tick = {int(k): i for i, k in enumerate(self.ticks)}
        if self._spec is None:
            self.spec = _spec_from(self.session.metadata, "haptic_spec", DeviceSpec, TOUCH_SPEC)
        self.i = 0
        self.t0 = time.perf_counter()
        self.commanded = []
        self.is_open = True

    def read(self) -> HapticSample:
        if self.timing == "clock" and self.is_open:
            self.i = int(np.clip(np.searchsorted(self.times, time.perf_counter() - self.t0 + self.times[0],
                                                 side="right") - 1, 0, len(self.items) - 1))
        return self._next()

    def servo_cf(self, force) -> None:
        if not self.is_open:
            raise DeviceError(f"replay {self.path}: servo_cf() before open()")
        F = np.asarray(force, dtype=float)
        if F.shape != (3,):
            raise DeviceError(f"replay {self.path}: force must have 3 components, got shape {F.shape}")
        self.commanded.append(F.copy())


class ReplayRobot(_Player):
    """The recorded robot (Robot): recorded readings out, commanded lengths kept in `commanded`."""

    def __init__(self, path: str, session=None):
        super().__init__(path, session)
        self.spec = RobotSpec()
        self.commanded: list = []
        self.stops = 0

    def open(self) -> None:
        msgs = self._messages(TOPIC_ROBOT)
        self.items = [reading_from(m) for m in msgs]
        self.by_tick = {int(m["tick"]): i for i, m in enumerate(msgs)}
        self.spec = _spec_from(self.session.metadata, "robot_spec", RobotSpec, RobotSpec())
        self.i = 0
        self.commanded = []
        self.is_open = True

    def read(self) -> RobotReading:
        return self._next()

    def command_lengths(self, lengths) -> None:
        if not self.is_open:
            raise DeviceError(f"replay {self.path}: command before open()")
        L = np.asarray(lengths, dtype=float)
        if L.shape != (6,) or not np.isfinite(L).all():
            raise DeviceError(f"replay {self.path}: lengths must be 6 finite numbers")
        self.commanded.append(L.copy())

    def stop(self) -> None:
        self.stops += 1


def from_url(parsed, options: dict):
    """Factory for ``replay://FILE[?device=stylus|robot&timing=sequence|clock]``."""
    path = (parsed.netloc or "") + (parsed.path or "")
    if not path:
        raise InputError("replay:// needs a file, e.g. replay://session.mcap or replay:///abs/session.mcap")
    unknown = set(options) - {"device", "timing"}
    if unknown:
        raise InputError(f"replay://{path}: unknown option(s) {', '.join(sorted(unknown))} (expected device, timing)")
    device = str(options.get("device", "stylus"))
    if device == "stylus":
        return ReplayStylus(path, timing=str(options.get("timing", "sequence")))
    if device == "robot":
        return ReplayRobot(path)
    raise InputError(f"replay://{path}: device must be 'stylus' or 'robot', got '{device}'")
