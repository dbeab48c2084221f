"""Crash-safe session recording in MCAP (viewable in Foxglove / PlotJuggler) and a reader that never crashes.

Data path: the loop copies one row of numbers per tick into a shared-memory ring (`Recorder.push`, no
syscall, no lock, no allocation); a separate recorder *process* (so no interpreter lock is shared with the
loop) turns rows into JSON messages on a few channels and writes them in small zstd chunks, flushed every
`flush_interval` (0.1 s), so a SIGKILL loses at most about that much. When the disk is slow or full the ring
fills, the loop's pushes are dropped and counted (memory stays bounded) and an alarm is raised. The
recorder process also computes the per-second timing statistics (/loop/timing) from the rows, and notices
when the loop process dies (it then drains the ring and finishes the file).

Metadata records: "session" (configuration, calibration, firmware and software version, start time) and
"session_end" (drops, final timing summary), each with a CRC32 of its content. Chunks carry CRC32s and the
data section and summary have CRCs, so `read_session` detects any damaged byte and returns the intact
prefix (it reads the file itself, with bounded allocations; truncated or bit-flipped files never crash it).
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import struct
import time
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import orjson

from teleop.errors import InputError

MAGIC = b"\x89MCAP0\r\n"
PROFILE = "cdpr-teleop"
# topics of a session recording (CRTK names where one fits); readers and exporters use these names
TOPIC_SETPOINT = "/teleop/setpoint"
TOPIC_ROBOT = "/robot/measured"
TOPIC_FORCE = "/haptic/servo_cf"
TOPIC_EVENTS = "/teleop/events"
TOPIC_TIMING = "/loop/timing"
FLOAT, INT = "f", "i"


# ------------------------------------------------------------------------------------------------------------
# Row layout
# ------------------------------------------------------------------------------------------------------------

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


class RowEncoder:
    """Row -> {topic: JSON bytes} using a Layout (runs in the recorder process)."""

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


# ------------------------------------------------------------------------------------------------------------
# Writer (recorder process side)
# ------------------------------------------------------------------------------------------------------------

def _crc_dict(d: dict) -> str:
    return f"{zlib.crc32(json.dumps(d, sort_keys=True).encode()) & 0xFFFFFFFF:08x}"


def metadata_record(d: dict) -> dict:
    """{key: JSON text} plus "crc32" of the content, as stored in an MCAP Metadata record."""
    enc = {k: json.dumps(v, sort_keys=True, default=str) for k, v in d.items()}
    enc["crc32"] = _crc_dict(enc)
    return enc


class McapWriter:
    """Minimal MCAP writer (spec v0): header, zstd chunks holding schemas, channels and messages, metadata,
    a data-section CRC and a footer. No indexes or summary (optional in the spec; readers then scan), so a
    message costs one struct.pack and a list append - the recorder keeps up with 1 kHz x 6 channels.
    """

    def __init__(self, stream, profile: str = PROFILE, library: str = "cdpr-teleop recorder"):
        import zstandard

        self.stream = stream
        self.zstd = zstandard.ZstdCompressor(level=3)
        self.crc = 0
        self.parts: list = []
        self.n_messages = 0
        self.t_min = self.t_max = 0
        self._write(MAGIC)
        self._write(_rec(0x01, _mstr(profile) + _mstr(library)))

    def _write(self, b: bytes) -> None:
        self.crc = zlib.crc32(b, self.crc)
        self.stream.write(b)

    def add_schema(self, sid: int, name: str, encoding: str, data: bytes) -> None:
        self.parts.append(_rec(0x03, struct.pack("<H", sid) + _mstr(name) + _mstr(encoding)
                                  + struct.pack("<I", len(data)) + data))

    def add_channel(self, cid: int, sid: int, topic: str, encoding: str) -> None:
        self.parts.append(_rec(0x04, struct.pack("<HH", cid, sid) + _mstr(topic) + _mstr(encoding)
                                  + struct.pack("<I", 0)))

    def add_message(self, cid: int, seq: int, log_time: int, data: bytes) -> None:
        # opcode, record length, channel id, sequence, log time, publish time, payload
        self.parts.append(struct.pack("<BQHIQQ", 0x05, 22 + len(data), cid, seq & 0xFFFFFFFF, log_time, log_time)
                          + data)
        if self.n_messages == 0 or log_time < self.t_min:
            self.t_min = log_time
        self.t_max = max(self.t_max, log_time)
        self.n_messages += 1

    def flush(self) -> None:
        """Write the open chunk (if any) and flush the stream: everything so far survives a crash."""
        if self.parts:
            raw = b"".join(self.parts)
            comp = self.zstd.compress(raw)
            body = (struct.pack("<QQQI", self.t_min, self.t_max, len(raw), zlib.crc32(raw)) + _mstr("zstd")
                    + struct.pack("<Q", len(comp)) + comp)
            self._write(_rec(0x06, body))
            self.parts = []
            self.n_messages = 0
        self.stream.flush()

    def add_metadata(self, name: str, data: dict) -> None:
        self.flush()
        m = b"".join(_mstr(k) + _mstr(v) for k, v in data.items())
        self._write(_rec(0x0C, _mstr(name) + struct.pack("<I", len(m)) + m))
        self.stream.flush()

    def finish(self) -> None:
        self.flush()
        self._write(_rec(0x0F, struct.pack("<I", self.crc & 0xFFFFFFFF)))
        self.stream.write(_rec(0x02, struct.pack("<QQI", 0, 0, 0)) + MAGIC)
        self.stream.flush()


def _mstr(s: str) -> bytes:
    b = s.encode("utf-8")
    return struct.pack("<I", len(b)) + b


def _rec(op: int, body: bytes) -> bytes:
    return struct.pack("<BQ", op, len(body)) + body


class SessionWriter:
    """One session's MCAP file: JSON messages per topic (floats bit-exact; NaN/inf stored as null), small
    zstd chunks with CRCs, metadata records with their own CRC, a data-section CRC."""

    def __init__(self, stream, layout: Layout, metadata: dict, t0_ns: int):
        self.stream = stream
        self.t0_ns = int(t0_ns)
        self.w = McapWriter(stream)
        self.encoder = RowEncoder(layout)
        self.channels = {}
        extra = ((TOPIC_EVENTS, b'{"type": "object"}'), (TOPIC_TIMING, b'{"type": "object"}'))
        topics = [(t, json_schema(layout, t)) for t in layout.topics()] + list(extra)
        for i, (topic, schema) in enumerate(topics, start=1):
            self.w.add_schema(i, topic, "jsonschema", schema)
            self.w.add_channel(i, i, topic, "json")
            self.channels[topic] = i
        self.event_seq = 0
        self.w.flush()  # schemas and channels in the first chunk
        self.w.add_metadata("session", metadata_record(metadata))

    def log_time(self, t: float) -> int:
        return max(0, self.t0_ns + int(round(t * 1e9)))

    def write_row(self, row: np.ndarray) -> None:
        ch, add = self.channels, self.w.add_message
        for topic, tick, t, payload in self.encoder.encode(row):
            add(ch[topic], tick, self.log_time(t), payload)

    def write_json(self, topic: str, t: float, obj: dict) -> None:
        self.event_seq += 1
        self.w.add_message(self.channels[topic], self.event_seq, self.log_time(t),
                           json.dumps(obj, default=str).encode())

    def flush(self) -> None:
        self.w.flush()

    def finish(self, end_metadata: dict) -> None:
        self.w.add_metadata("session_end", metadata_record(end_metadata))
        self.w.finish()


class SecondStats:
    """Per-second timing statistics from the rows' /loop columns (recorder side)."""

    def __init__(self, layout: Layout):
        sl = layout.slices()
        self.cols = {s.name: sl[("/loop", s.name)][0] for s in layout.signals
                     if s.topic == "/loop" and s.name.endswith("_us")}
        self.t_col = sl[("/loop", "t")][0]
        self.rows = []
        self.second = 0

    def add(self, row: np.ndarray):
        """Add a row; returns a stats dict when a whole second has been collected."""
        out = None
        sec = int(row[self.t_col])
        if sec != self.second and self.rows:
            out = self.summary()
            self.rows = []
        self.second = sec
        self.rows.append(row[[c for c in self.cols.values()]].copy())
        return out

    def summary(self) -> dict:
        a = np.array(self.rows)
        out = {"second": self.second, "ticks": len(a)}
        for j, name in enumerate(self.cols):
            v = a[:, j]
            out[name] = {"mean": round(float(v.mean()), 3), "p99": round(float(np.percentile(v, 99)), 3),
                         "p999": round(float(np.percentile(v, 99.9)), 3), "max": round(float(v.max()), 3)}
            if name == "lateness_us":
                out["misses"] = int((v > 500.0).sum())
        return out


# ------------------------------------------------------------------------------------------------------------
# Shared-memory ring and the recorder process
# ------------------------------------------------------------------------------------------------------------

HEAD, TAIL, DROPS, STATUS, STOP, WRITTEN, FLUSHES, T0_NS = range(8)
OK, ALARM_FULL, ALARM_ERROR = 0, 1, 2


class Ring:
    """Single-producer single-consumer ring of float64 rows in shared memory.

    ctrl (int64): head (rows pushed), tail (rows consumed), drops, status, stop flag, rows written, flushes.
    """

    def __init__(self, width: int, capacity: int, ctx=None):
        ctx = ctx or mp.get_context("fork")
        self.width, self.capacity = int(width), int(capacity)
        self.raw = ctx.RawArray("d", self.width * self.capacity)
        self.ctrl_raw = ctx.RawArray("q", 8)
        self.attach()

    def attach(self) -> None:
        self.data = np.frombuffer(self.raw, dtype=np.float64).reshape(self.capacity, self.width)
        self.ctrl = np.frombuffer(self.ctrl_raw, dtype=np.int64)

    def __getstate__(self):
        return {"width": self.width, "capacity": self.capacity, "raw": self.raw, "ctrl_raw": self.ctrl_raw}

    def __setstate__(self, d):
        self.__dict__.update(d)
        self.attach()

    def push(self, row: np.ndarray) -> bool:
        """Copy a row in (producer); False (and a drop counted) when the ring is full."""
        c = self.ctrl
        head = int(c[HEAD])
        if head - int(c[TAIL]) >= self.capacity:
            c[DROPS] += 1
            if c[STATUS] == OK:
                c[STATUS] = ALARM_FULL
            return False
        self.data[head % self.capacity] = row
        c[HEAD] = head + 1
        return True

    def pop(self, max_rows: int = 1 << 30) -> np.ndarray:
        """Copy out the rows pushed since the last pop (consumer)."""
        c = self.ctrl
        tail, head = int(c[TAIL]), int(c[HEAD])
        n = min(head - tail, max_rows)
        if n <= 0:
            return np.zeros((0, self.width))
        idx = (np.arange(tail, tail + n) % self.capacity)
        out = self.data[idx].copy()
        c[TAIL] = tail + n
        return out


def _recorder_main(path: str, layout_json: str, ring: Ring, conn, metadata: dict, t0_ns: int,
                   flush_interval: float, parent_pid: int, stream_factory=None) -> None:
    """Recorder process: drain the ring into the MCAP file until stopped or the loop process is gone."""
    layout = Layout.from_json(layout_json)
    ctrl = ring.ctrl
    try:  # never inherit a real-time policy from the loop: the recorder must yield to it ...
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    except (AttributeError, OSError):
        pass
    try:  # ... but keep up with the other time-sharing processes where the OS lets us
        os.nice(-10)
    except OSError:
        pass
    try:
        stream = stream_factory() if stream_factory is not None else open(path, "wb")
        writer = SessionWriter(stream, layout, metadata, t0_ns)
    except OSError as exc:
        ctrl[STATUS] = ALARM_ERROR
        _send_status(conn, f"recording failed to start: {exc}")
        return
    stats = SecondStats(layout)
    last_flush = time.monotonic()
    end_meta: dict = {}
    try:
        while True:
            stopping = bool(ctrl[STOP]) or os.getppid() != parent_pid
            rows = ring.pop(2000)
            if len(rows) and ctrl[T0_NS]:
                writer.t0_ns = int(ctrl[T0_NS])  # wall-clock time of session time 0, set by the loop at start
            for row in rows:
                writer.write_row(row)
                s = stats.add(row)
                if s is not None:
                    writer.write_json(TOPIC_TIMING, float(s["second"]), s)
            ctrl[WRITTEN] += len(rows)
            while conn.poll():
                try:
                    kind, obj = json.loads(conn.recv_bytes())
                except (EOFError, OSError, ValueError):
                    break
                if kind == "event":
                    writer.write_json(TOPIC_EVENTS, float(obj.get("t", 0.0)), obj)
                elif kind == "end":
                    end_meta = obj
            now = time.monotonic()
            if now - last_flush >= flush_interval:
                writer.flush()
                ctrl[FLUSHES] += 1
                last_flush = now
            if stopping and ctrl[HEAD] == ctrl[TAIL]:
                break
            if len(rows) == 0:
                time.sleep(0.005)
        if stats.rows:
            s = stats.summary()
            writer.write_json(TOPIC_TIMING, float(s["second"]), s)
        end_meta.setdefault("drops", int(ctrl[DROPS]))
        end_meta.setdefault("rows_written", int(ctrl[WRITTEN]))
        writer.finish(end_meta)
        stream.close()
    except OSError as exc:  # disk full, I/O error: stop writing, raise the alarm; the loop goes on
        ctrl[STATUS] = ALARM_ERROR
        _send_status(conn, f"recording stopped: {exc}")


def _send_status(conn, text: str) -> None:
    try:
        conn.send_bytes(json.dumps(["status", text]).encode())
    except (OSError, ValueError):
        pass


class Recorder:
    """Loop-side handle of the recorder process.

    Args:
        path: output .mcap file.
        layout: row layout.
        metadata: session metadata (JSON-able dict).
        capacity: ring rows (bounded memory: capacity x width x 8 bytes).
        flush_interval: chunk flush period [s] (the most a crash can lose, plus the drain lag).
        t0_ns: wall-clock time [ns since epoch] of session time 0.
        stream_factory: for tests, a callable returning the output stream (e.g. a slow or full disk).
    """

    def __init__(self, path, layout: Layout, metadata: dict, capacity: int = 16384, flush_interval: float = 0.1,
                 t0_ns: int | None = None, stream_factory=None):
        self.path = str(path)
        self.layout = layout
        self.metadata = metadata
        self.flush_interval = flush_interval
        self.t0_ns = time.time_ns() if t0_ns is None else int(t0_ns)
        self.ctx = mp.get_context("fork")
        self.ring = Ring(layout.width, capacity, self.ctx)
        self.stream_factory = stream_factory
        self.proc = None
        self.status_text = ""

    def start(self) -> "Recorder":
        Path(self.path).parent.mkdir(parents=True, exist_ok=True)
        self.rx, self.tx = self.ctx.Pipe(duplex=False)
        self.back_rx, self.back_tx = self.ctx.Pipe(duplex=False)
        self.proc = self.ctx.Process(
            target=_recorder_main, name="teleop-recorder", daemon=False,
            args=(self.path, self.layout.to_json(), self.ring, self.rx, self.metadata, self.t0_ns,
                  self.flush_interval, os.getpid(), self.stream_factory))
        self.proc.start()
        os.set_blocking(self.tx.fileno(), False)
        self.event_drops = 0
        return self

    def set_t0(self, t0_ns: int) -> None:
        """Wall-clock time [ns since epoch] of session time 0 (call before the first push)."""
        self.t0_ns = int(t0_ns)
        self.ring.ctrl[T0_NS] = self.t0_ns

    def push(self, row: np.ndarray) -> bool:
        """Loop side: copy one tick row into the ring (never blocks)."""
        return self.ring.push(row)

    def event(self, obj: dict) -> None:
        """Send a state-change event (non-blocking; dropped and counted if the pipe is full)."""
        try:
            self.tx.send_bytes(json.dumps(["event", obj], default=str).encode())
        except (BlockingIOError, OSError, ValueError):
            self.event_drops += 1

    @property
    def drops(self) -> int:
        return int(self.ring.ctrl[DROPS])

    @property
    def alarm(self) -> str:
        """'' when healthy, else a one-line alarm."""
        st = int(self.ring.ctrl[STATUS])
        if st == OK:
            return ""
        if st == ALARM_FULL:
            return f"recording falling behind (slow disk?): {self.drops} ticks dropped"
        return f"recording stopped (I/O error): {self.drops} ticks dropped"

    def close(self, end_metadata: dict | None = None, timeout: float = 30.0) -> None:
        """Stop: the recorder drains the ring, writes `end_metadata` and the summary, and exits."""
        if self.proc is None:
            return
        if end_metadata is not None:
            os.set_blocking(self.tx.fileno(), True)
            try:
                self.tx.send_bytes(json.dumps(["end", end_metadata], default=str).encode())
            except OSError:
                pass
        self.ring.ctrl[STOP] = 1
        self.proc.join(timeout)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join()
        self.proc = None


# ------------------------------------------------------------------------------------------------------------
# Reader
# ------------------------------------------------------------------------------------------------------------

class _Damage(Exception):
    pass


_MAX_CHUNK = 256 * 1024 * 1024


class _Buf:
    """Bounds-checked little-endian reads from a bytes slice."""

    __slots__ = ("b", "i", "end")

    def __init__(self, b: bytes, start: int = 0, end: int | None = None):
        self.b, self.i, self.end = b, start, len(b) if end is None else end

    def take(self, n: int) -> bytes:
        if n < 0 or self.i + n > self.end:
            raise _Damage("field runs past the end of its record")
        v = self.b[self.i:self.i + n]
        self.i += n
        return v

    def u8(self):
        return self.take(1)[0]

    def u16(self):
        return struct.unpack("<H", self.take(2))[0]

    def u32(self):
        return struct.unpack("<I", self.take(4))[0]

    def u64(self):
        return struct.unpack("<Q", self.take(8))[0]

    def string(self) -> str:
        try:
            return self.take(self.u32()).decode("utf-8")
        except UnicodeDecodeError:
            raise _Damage("invalid UTF-8 string") from None

    def str_map(self) -> dict:
        n = self.u32()
        sub = _Buf(self.take(n))
        out = {}
        while sub.i < sub.end:
            k = sub.string()
            out[k] = sub.string()
        return out

    def rest(self) -> bytes:
        return self.take(self.end - self.i)


@dataclass
class Session:
    """A session read back.

    Attributes:
        path: file name.
        metadata: {record name: {key: decoded JSON value}} ("session", "session_end").
        topics: {channel id: topic}.
        records: [(topic, log_time_ns, sequence, message dict)] in file order.
        damage: '' when the file is complete and every CRC matches, else what was wrong and where.
        complete: the footer was reached (the recording was closed properly).
        intact_bytes: length of the prefix that was parsed without damage.
    """

    path: str
    metadata: dict = field(default_factory=dict)
    topics: dict = field(default_factory=dict)
    records: list = field(default_factory=list)
    damage: str = ""
    complete: bool = False
    intact_bytes: int = 0

    @property
    def is_intact(self) -> bool:
        return not self.damage

    def messages(self, topic: str) -> list:
        return [m for tp, _, _, m in self.records if tp == topic]

    def array(self, topic: str, name: str) -> np.ndarray:
        """Values of one field over the topic's messages, as an array ((N,) or (N, width))."""
        return np.array([m[name] for m in self.messages(topic)], dtype=float)


def read_session(path) -> Session:
    """Read a recording; never raises on damage (see Session.damage), only on a file that is not MCAP."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{p}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{p}: is a directory, expected an .mcap recording") from None
    return parse_session(data, str(p))


def parse_session(data: bytes, name: str = "<bytes>") -> Session:
    """Parse MCAP bytes into a Session, stopping at the first damaged record (the intact prefix is kept)."""
    if len(data) < len(MAGIC) or data[:len(MAGIC)] != MAGIC:
        raise InputError(f"{name}: not an MCAP recording (bad magic bytes at offset 0)")
    s = Session(path=name)
    schemas, pos, n = {}, len(MAGIC), len(data)
    in_summary = False
    while True:
        if pos == n:
            s.damage = s.damage or f"file ends at byte {n} before the footer (recording interrupted)"
            break
        if pos + 9 > n:
            s.damage = f"truncated record header at byte {pos}"
            break
        op = data[pos]
        length = struct.unpack_from("<Q", data, pos + 1)[0]
        end = pos + 9 + length
        if op == 0 or op > 0x0F:
            s.damage = f"unknown record opcode 0x{op:02x} at byte {pos}"
            break
        if end > n:
            s.damage = f"record 0x{op:02x} at byte {pos} truncated ({length} bytes declared, {n - pos - 9} present)"
            break
        try:
            if op == 0x02:  # footer
                _footer(data, pos, end, n)
                s.complete = True
                s.intact_bytes = n
                break
            if op == 0x0F:  # data end: check the data section CRC
                crc = _Buf(data, pos + 9, end).u32()
                if crc and crc != zlib.crc32(data[:pos]) & 0xFFFFFFFF:
                    raise _Damage("data section CRC mismatch")
                in_summary = True
            elif not in_summary:
                _record(op, _Buf(data, pos + 9, end), s, schemas)
        except _Damage as exc:
            s.damage = f"record 0x{op:02x} at byte {pos}: {exc}"
            break
        pos = end
        s.intact_bytes = pos
    return s


def _footer(data: bytes, pos: int, end: int, n: int) -> None:
    b = _Buf(data, pos + 9, end)
    summary_start, offsets, crc = b.u64(), b.u64(), b.u32()
    if end + len(MAGIC) != n or data[end:] != MAGIC:
        raise _Damage("bad trailing magic after the footer")
    if not crc and (summary_start or offsets):  # nothing to check the offsets against: they must be absent
        raise _Damage("footer points to a summary without a CRC")
    if crc:
        if not 0 < summary_start <= pos:
            raise _Damage("summary start outside the file")
        if zlib.crc32(data[summary_start:pos + 9 + 16]) & 0xFFFFFFFF != crc:
            raise _Damage("summary CRC mismatch")


def _record(op: int, b: _Buf, s: Session, schemas: dict, in_chunk: bool = False) -> None:
    if op == 0x01:  # header
        profile = b.string()
        b.string()
        if profile not in (PROFILE, ""):
            s.metadata.setdefault("_profile", profile)
    elif op == 0x03:  # schema
        sid = b.u16()
        schemas[sid] = (b.string(), b.string())
    elif op == 0x04:  # channel
        cid, _sid, topic = b.u16(), b.u16(), b.string()
        b.string()
        b.str_map()
        s.topics[cid] = topic
    elif op == 0x05:  # message
        cid, seq, log_time, _pub = b.u16(), b.u32(), b.u64(), b.u64()
        if cid not in s.topics:
            raise _Damage(f"message on unknown channel {cid}")
        try:
            msg = json.loads(b.rest())
        except ValueError:
            raise _Damage("message is not valid JSON") from None
        s.records.append((s.topics[cid], log_time, seq, msg))
    elif op == 0x06 and not in_chunk:  # chunk: validate fully, then take its records
        _chunk(b, s, schemas)
    elif op == 0x0C:  # metadata
        name, m = b.string(), b.str_map()
        crc = m.pop("crc32", None)
        if crc is not None and crc != _crc_dict(m):
            raise _Damage(f"metadata '{name}' CRC mismatch")
        try:
            s.metadata[name] = {k: json.loads(v) for k, v in m.items()}
        except ValueError:
            raise _Damage(f"metadata '{name}' is not JSON") from None
    elif op == 0x07 and not in_chunk:  # message index: carries nothing we need, but must be well formed
        b.u16()
        n = b.u32()
        if n % 16 or b.end - b.i != n:
            raise _Damage("malformed message index")
    else:  # a data section written by SessionWriter holds nothing else: anything else is damage
        raise _Damage(f"unexpected record 0x{op:02x} in the data section")


def _chunk(b: _Buf, s: Session, schemas: dict) -> None:
    b.u64()
    b.u64()
    size, crc, comp = b.u64(), b.u32(), b.string()
    payload = b.take(b.u64())
    if size > _MAX_CHUNK or size > 2000 * len(payload) + 4096:
        raise _Damage(f"implausible chunk size {size}")
    if comp == "":
        raw = payload
    elif comp == "zstd":
        import zstandard

        try:
            declared = zstandard.frame_content_size(payload)
            if declared not in (size, -1):  # a damaged frame header must not size an allocation
                raise _Damage(f"zstd frame declares {declared} bytes, chunk {size}")
            raw = zstandard.ZstdDecompressor().decompress(payload, max_output_size=size)
        except (zstandard.ZstdError, MemoryError) as exc:
            raise _Damage(f"zstd: {type(exc).__name__}: {exc}") from None
    elif comp == "lz4":
        import lz4.frame

        try:
            raw = lz4.frame.decompress(payload)
        except RuntimeError as exc:
            raise _Damage(f"lz4: {exc}") from None
    else:
        raise _Damage(f"unknown compression '{comp}'")
    if len(raw) != size:
        raise _Damage("chunk size mismatch")
    if crc and zlib.crc32(raw) & 0xFFFFFFFF != crc:
        raise _Damage("chunk CRC mismatch")
    staged = Session(path=s.path, topics=dict(s.topics))
    staged_schemas = dict(schemas)
    i = 0
    while i < len(raw):
        if i + 9 > len(raw):
            raise _Damage("truncated record inside chunk")
        op = raw[i]
        ln = struct.unpack_from("<Q", raw, i + 1)[0]
        if i + 9 + ln > len(raw):
            raise _Damage("record runs past the end of its chunk")
        if op not in (0x03, 0x04, 0x05):
            raise _Damage(f"unexpected record 0x{op:02x} inside chunk")
        _record(op, _Buf(raw, i + 9, i + 9 + ln), staged, staged_schemas, in_chunk=True)
        i += 9 + ln
    s.topics.update(staged.topics)
    schemas.update(staged_schemas)
    s.records.extend(staged.records)
