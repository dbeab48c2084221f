"""Row layout of a session recording: which numbers of a tick row go to which topic, and their JSON form.

The loop copies one row of float64 numbers per tick (teleop.loop.tap); `Layout` names the columns, groups them
into topics (CRTK names where one fits) and `RowEncoder` turns a row into one JSON message per topic (in the
recorder's and the live server's processes, never in the loop's).
"""

from __future__ import annotations

import json
import zlib
from dataclasses import dataclass, field

import numpy as np
import orjson

PROFILE = "cdpr-teleop"
# topics of a session recording (CRTK names where one fits); readers and exporters use these names
TOPIC_SETPOINT = "/teleop/setpoint"
TOPIC_ROBOT = "/robot/measured"
TOPIC_FORCE = "/haptic/servo_cf"
TOPIC_EVENTS = "/teleop/events"
TOPIC_TIMING = "/loop/timing"
FLOAT, INT = "f", "i"


@dataclass(frozen=True)
class Signal:
    """One recorded quantity: `width` numbers on `topic` under `name` (kind FLOAT or INT)."""

    topic: str
    name: str
    width: int = 1
    kind: str = FLOAT


@dataclass(frozen=True)
class Layout:
    """Column layout of a tick row. Every topic gets `tick` and `t` from the /loop columns.

    Attributes:
        signals: the recorded signals in row order.
        gates: {topic: name} - the topic is written only on ticks where that (INT) field is nonzero.
    """

    signals: tuple
    gates: dict = field(default_factory=dict)

    @property
    def width(self) -> int:
        return sum(s.width for s in self.signals)

    def slices(self) -> dict:
        """{(topic, name): (start, stop)} column ranges."""
        out, i = {}, 0
        for s in self.signals:
            out[(s.topic, s.name)] = (i, i + s.width)
            i += s.width
        return out

    def columns(self) -> dict:
        """{name: slice} for layouts whose signal names are unique across topics (the session's)."""
        out = {name: slice(*ab) for (_topic, name), ab in self.slices().items()}
        if len(out) != len(self.signals):
            raise ValueError("signal names are not unique across topics")
        return out

    def topics(self) -> list:
        seen = []
        for s in self.signals:
            if s.topic not in seen:
                seen.append(s.topic)
        return seen

    def to_json(self) -> str:
        return json.dumps({"signals": [[s.topic, s.name, s.width, s.kind] for s in self.signals],
                           "gates": self.gates})

    @staticmethod
    def from_json(text: str) -> "Layout":
        d = json.loads(text)
        return Layout(tuple(Signal(*s) for s in d["signals"]), dict(d.get("gates", {})))


def json_schema(layout: Layout, topic: str) -> bytes:
    """JSON schema of one topic's messages."""
    props = {"tick": {"type": "integer"}, "t": {"type": "number", "description": "session time [s]"}}
    for s in layout.signals:
        if s.topic != topic:
            continue
        base = {"type": "integer" if s.kind == INT else "number"}
        props[s.name] = base if s.width == 1 else {"type": "array", "items": base, "minItems": s.width,
                                                    "maxItems": s.width}
    return json.dumps({"type": "object", "properties": props}).encode()


def event_schema() -> bytes:
    """JSON schema of a state change on /teleop/events (teleop.loop.core.Event: tick, time, states, reason)."""
    props = {"k": {"type": "integer", "description": "tick"}, "t": {"type": "number", "description": "host time [s]"},
             "src": {"type": "string"}, "dst": {"type": "string"}, "reason": {"type": "string"}}
    return json.dumps({"type": "object", "properties": props}).encode()


class RowEncoder:
    """Row -> {topic: JSON bytes} using a Layout (floats bit-exact; NaN/inf become null)."""

    def __init__(self, layout: Layout):
        sl = layout.slices()
        self.tick = sl[("/loop", "tick")][0]
        self.t = sl[("/loop", "t")][0]
        self.topics = []
        for topic in layout.topics():
            fields = [(s.name, sl[(s.topic, s.name)], s.width, s.kind) for s in layout.signals if s.topic == topic]
            gate = layout.gates.get(topic)
            gate_col = sl[(topic, gate)][0] if gate else None
            self.topics.append((topic, fields, gate_col))

    def encode(self, row: np.ndarray):
        """Yield (topic, tick, t, payload bytes) for one row."""
        vals = row.tolist()
        tick, t = int(vals[self.tick]), vals[self.t]
        for topic, fields, gate in self.topics:
            if gate is not None and not vals[gate]:
                continue
            msg = {"tick": tick, "t": t}
            for name, (a, b), width, kind in fields:
                v = vals[a:b]
                if kind == INT:
                    v = [int(x) if x == x else 0 for x in v]
                msg[name] = v[0] if width == 1 else v
            yield topic, tick, t, orjson.dumps(msg)


def crc_dict(d: dict) -> str:
    """CRC32 (8 hex digits) of a {key: text} dict, as stored beside it in a metadata record."""
    return f"{zlib.crc32(json.dumps(d, sort_keys=True).encode()) & 0xFFFFFFFF:08x}"


def metadata_record(d: dict) -> dict:
    """{key: JSON text} plus "crc32" of the content, as stored in an MCAP Metadata record."""
    enc = {k: json.dumps(v, sort_keys=True, default=str) for k, v in d.items()}
    enc["crc32"] = crc_dict(enc)
    return enc
