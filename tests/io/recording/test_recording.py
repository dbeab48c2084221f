"""Recording (docs/safety.md): bit-exact round trip with metadata, damaged files (every truncation, bit
flips) never crash the reader and give back an intact prefix, a slow or full disk only drops rows (counted,
alarmed, bounded memory) without changing the loop side's timing, and the writer shares no interpreter lock
with the loop (shown with counters and process ids; time figures belong to `teleop bench loop`)."""

import errno
import hashlib
import io
import json
import multiprocessing as mp
import os
import signal
import time

import numpy as np
import orjson
import pytest

from teleop.core.errors import InputError
from teleop.loop.tap import session_layout
from teleop.io.recording import INT, Layout, Recorder, Ring, Signal, SessionWriter, parse_session, read_session
from teleop.io.recording.ring import DROPS, FLUSHES, HEAD, TAIL, WRITTEN

META = {"configuration": {"loop": {"rate_hz": 1000.0}}, "calibration": {"fsr": [1.5, 2.5]},
        "firmware_version": "cdpr-fw 1.2.3", "software_version": "cdpr-teleop test"}


def rows(layout: Layout, n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    R = rng.normal(size=(n, layout.width)) * 10.0 ** rng.integers(-9, 4, size=(n, layout.width))
    sl = layout.slices()
    for (topic, name), (a, b) in sl.items():
        sig = next(s for s in layout.signals if s.topic == topic and s.name == name)
        if sig.kind == "i":
            R[:, a:b] = rng.integers(0, 1000, size=(n, b - a))
    R[:, sl[("/loop", "tick")][0]] = np.arange(n)
    R[:, sl[("/loop", "t")][0]] = np.arange(n) * 1e-3
    R[:, sl[("/robot/measured", "new")][0]] = np.arange(n) % 2
    return R


SMALL = Layout((Signal("/loop", "tick", 1, INT), Signal("/loop", "t"), Signal("/loop", "state", 1, INT),
                 Signal("/robot/measured", "new", 1, INT), Signal("/stylus", "measured_cp", 3)),
                {"/robot/measured": "new"})


def write_file(n: int = 20, flush_every: int = 5, finish: bool = True, layout=None):
    layout = layout or session_layout({"t_tip": 6})
    buf = io.BytesIO()
    w = SessionWriter(buf, layout, META, t0_ns=1_700_000_000_000_000_000)
    R = rows(layout, n)
    for i, r in enumerate(R):
        w.write_row(r)
        if (i + 1) % flush_every == 0:
            w.flush()
    w.write_json("/teleop/events", 0.01, {"src": "DISABLED", "dst": "ALIGNING", "reason": ""})
    if finish:
        w.finish({"drops": 0, "timing": {"lateness_us": {"p50": 1.0}}})
    return layout, R, buf.getvalue()


def test_round_trip_bit_exact_with_metadata():
    layout, R, data = write_file(40)
    s = parse_session(data)
    assert s.is_intact and s.complete
    sl = layout.slices()
    for topic in ("/stylus", "/estimation", "/haptic/servo_cf"):
        msgs = s.messages(topic)
        assert len(msgs) == 40
        for m, r in zip(msgs, R):
            for s_ in layout.signals:
                if s_.topic != topic:
                    continue
                a, b = sl[(topic, s_.name)]
                want = r[a:b].tolist() if s_.kind == "f" else [int(v) for v in r[a:b]]
                got = m[s_.name] if s_.width > 1 else [m[s_.name]]
                assert got == want  # floats compared exactly: bit-exact
    assert len(s.messages("/robot/measured")) == 20  # gated on `new`
    meta = s.metadata["session"]
    assert meta["firmware_version"] == "cdpr-fw 1.2.3" and meta["calibration"] == {"fsr": [1.5, 2.5]}
    assert meta["software_version"] and meta["configuration"]["loop"]["rate_hz"] == 1000.0
    assert s.metadata["session_end"]["drops"] == 0


def all_messages(s):
    return [(tp, lt, seq, m) for tp, lt, seq, m in s.records]


def test_truncation_at_every_byte_offset_never_crashes_and_keeps_a_prefix():
    _, _, data = write_file(10, flush_every=2, layout=SMALL)
    full = all_messages(parse_session(data))
    seen = set()
    for cut in range(len(data)):
        try:
            s = parse_session(data[:cut])
        except InputError:
            assert cut < 8  # only a cut inside the magic is "not an MCAP file"
            continue
        got = all_messages(s)
        assert got == full[:len(got)]  # intact, in sequence
        assert s.damage and not s.complete
        seen.add(len(got))
    assert len(seen) > 4  # whole chunks come back as the file grows


def test_bit_flips_detected_and_prefix_intact():
    _, _, data = write_file(10, flush_every=2, layout=SMALL)
    full = all_messages(parse_session(data))
    rng = np.random.default_rng(1)
    for _ in range(3000):
        b = bytearray(data)
        for _k in range(int(rng.integers(1, 4))):
            i = int(rng.integers(0, len(b)))
            b[i] ^= 1 << int(rng.integers(0, 8))
        if bytes(b) == data:
            continue
        try:
            s = parse_session(bytes(b))
        except InputError:
            continue  # magic damaged: clean one-line error
        got = all_messages(s)
        assert got == full[:len(got)]
        assert s.damage  # every damaged byte is covered by a CRC (chunks, data section, summary, metadata)


def test_garbage_and_non_mcap_files(tmp_path):
    p = tmp_path / "x.mcap"
    p.write_bytes(b"hello, not mcap")
    with pytest.raises(InputError, match="not an MCAP"):
        read_session(p)
    with pytest.raises(InputError, match="not found"):
        read_session(tmp_path / "missing.mcap")
    s = parse_session(b"\x89MCAP0\r\n" + bytes([0x06]) + (2**63).to_bytes(8, "little") + b"\0" * 64)
    assert "exceeds" in s.damage and not s.records  # a huge declared length allocates nothing


def test_ring_push_pop_and_drop_counting():
    ring = Ring(4, 8)
    for i in range(8):
        assert ring.push(np.full(4, float(i)))
    assert not ring.push(np.zeros(4)) and ring.ctrl[2] == 1  # full: dropped, counted
    out = ring.pop()
    assert out[:, 0].tolist() == list(range(8))
    assert ring.push(np.full(4, 9.0)) and ring.pop()[0, 0] == 9.0


class SlowStream(io.BytesIO):
    """A disk that takes `delay` seconds per write (after the header)."""

    def __init__(self, delay):
        super().__init__()
        self.delay, self.n = delay, 0

    def write(self, b):
        self.n += 1
        if self.n > 3:
            time.sleep(self.delay)
        return super().write(b)


class FullDisk(io.BytesIO):
    def __init__(self):
        super().__init__()
        self.n = 0

    def write(self, b):
        self.n += 1
        if self.n > 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        return super().write(b)


@pytest.mark.parametrize("disk", ["slow", "full"])
def test_slow_or_full_disk_drops_and_alarms_never_blocks(tmp_path, disk):
    layout = session_layout()
    factory = (lambda: SlowStream(5.0)) if disk == "slow" else FullDisk
    rec = Recorder(tmp_path / "s.mcap", layout, META, capacity=64, flush_interval=0.01,
                   stream_factory=factory).start()
    R = rows(layout, 2000)
    ok = 0
    for i, r in enumerate(R):
        ok += rec.push(r)  # never blocks: the loop side is a memory copy
        if i % 100 == 0:
            time.sleep(0.02)  # let the recorder reach its stalled write
    assert rec.drops == len(R) - ok and rec.drops >= len(R) - 64 - 300
    assert rec.alarm and ("behind" in rec.alarm or "stopped" in rec.alarm)
    assert rec.ring.data.nbytes == 64 * layout.width * 8  # memory bounded by the ring
    rec.ring.ctrl[4] = 1
    rec.proc.kill()
    rec.proc.join()
    rec.proc = None


def test_files_open_with_the_reference_mcap_reader_bit_exact():
    """The mcap package's own indexed reader gives back every message of ours: same topics, log times,
    sequence numbers and payloads; floats equal to the rows written (bit-exact)."""
    from mcap.reader import make_reader

    layout, R, data = write_file(30)
    ours = parse_session(data)
    reader = make_reader(io.BytesIO(data))
    everything = list(reader.iter_messages())
    theirs = [(ch.topic, m.log_time, m.sequence, json.loads(m.data)) for _, ch, m in everything
              if ch.message_encoding == "json"]
    key = lambda r: (r[1], r[0], r[2])  # noqa: E731 - the indexed reader orders by log time
    assert sorted(theirs, key=key) == sorted(ours.records, key=key)
    sl = layout.slices()
    stylus = [m for tp, _, _, m in theirs if tp == "/stylus"]
    assert len(stylus) == 30
    a, b = sl[("/stylus", "measured_cp")]
    assert [m["measured_cp"] for m in stylus] == [r[a:b].tolist() for r in R]
    assert {m.name for m in make_reader(io.BytesIO(data)).iter_metadata()} == {"session", "session_end"}
    summary = make_reader(io.BytesIO(data)).get_summary()
    assert summary.statistics.message_count == len(everything)  # the library wrote a summary: seekable
    # the views in Foxglove's schemas: a Log per state change, FrameTransforms every 10 ms of session time
    views = {(ch.topic, sc.name, sc.encoding) for sc, ch, _ in everything if ch.message_encoding == "protobuf"}
    assert views == {("/teleop/log", "foxglove.Log", "protobuf"), ("/tf", "foxglove.FrameTransforms", "protobuf")}
    assert ours.views == {"/teleop/log": 1, "/tf": 3}  # rows 1 ms apart over 30 ms: t = 0, 10, 20 ms


def test_old_recordings_stay_readable():
    """A recording by the hand-written writer this package replaced reads back to the same records."""
    here = os.path.join(os.path.dirname(__file__), "data")
    s = read_session(os.path.join(here, "session_v1_handwriter.mcap"))
    with open(os.path.join(here, "session_v1_handwriter.expected.json")) as fh:
        want = json.load(fh)
    got = hashlib.sha256(orjson.dumps([[t, lt, seq, m] for t, lt, seq, m in s.records],
                                      option=orjson.OPT_SORT_KEYS)).hexdigest()
    assert s.is_intact and s.complete == want["complete"]
    assert len(s.records) == want["records"] and got == want["sha256_records"]
    assert sorted(set(s.topics.values())) == want["topics"] and sorted(s.metadata) == want["metadata_keys"]


def python_busy(seconds: float) -> int:
    """Hold the interpreter for `seconds` [s] of pure-Python work (a CPU-bound writer: encoding, compression)."""
    end, i = time.perf_counter() + seconds, 0
    while time.perf_counter() < end:
        i += 1
    return i


class GatedStream(io.BytesIO):
    """A disk whose writes run in the recorder process; records that process id in `box[0]`. While
    `box[1]` is 1 every write holds the interpreter for 20 ms (CPU-bound writer); while `box[2]` is 1 every
    write blocks (stalled disk) until it is cleared."""

    def __init__(self, box, path=None):
        super().__init__()
        self.box, self.n, self.path = box, 0, path

    def close(self):
        if self.path is not None and not self.closed:  # keep what reached the "disk"
            with open(self.path, "wb") as fh:
                fh.write(self.getvalue())
        super().close()

    def write(self, b):
        self.box[0] = os.getpid()
        self.n += 1
        if self.n > 3:
            if self.box[1]:
                python_busy(0.020)
            while self.box[2]:
                time.sleep(0.001)
        return super().write(b)


def push_all(rec, row, n: int) -> int:
    """Push n rows (ticks k = 0..n-1 on the rows' own clock, 1 ms apart); returns how many were accepted."""
    ok = 0
    for k in range(n):
        row[0], row[1] = k, k * 1e-3
        ok += rec.push(row)
    return ok


def test_writer_runs_in_another_process_and_never_holds_the_loop_back(tmp_path):
    """The recorder writes from its own process (so it shares no interpreter lock with the loop). While it
    holds its interpreter in every write, or is frozen (SIGSTOP), the loop side's pushes all return: the ring
    takes what it has room for, the rest is dropped and counted, nothing waits. Time figures of the push
    belong to `teleop bench loop` (record_us), not here."""
    layout = session_layout()
    box = mp.get_context("fork").RawArray("q", 3)
    cap = 512
    rec = Recorder(tmp_path / "s.mcap", layout, META, capacity=cap, flush_interval=0.005,
                   stream_factory=lambda: GatedStream(box, tmp_path / "s.mcap")).start()
    row = rows(layout, 1)[0]
    try:
        box[1] = 1  # the writer now spends its time in Python inside write()
        assert push_all(rec, row, 200) == 200
        while rec.ring.ctrl[WRITTEN] < 200:
            time.sleep(0.005)
        assert box[0] == rec.proc.pid != os.getpid()  # the disk writes happen in the recorder process
        os.kill(rec.proc.pid, signal.SIGSTOP)  # the writer frozen: the loop side must not notice
        try:
            free = cap - int(rec.ring.ctrl[HEAD] - rec.ring.ctrl[TAIL])
            accepted = push_all(rec, row, 3 * cap)
        finally:
            os.kill(rec.proc.pid, signal.SIGCONT)
        assert accepted == free and rec.drops == 3 * cap - free and "behind" in rec.alarm
        box[1] = 0
    finally:
        rec.close({})
    s = read_session(tmp_path / "s.mcap")
    assert s.complete and len(s.messages("/loop")) == 200 + free  # what was accepted is all there


def test_stalled_disk_drops_and_counts_then_recovers(tmp_path):
    """A stalled disk: every push returns, the ring fills, the overflow is dropped and counted with an alarm,
    memory stays the ring's; when the disk comes back the rows held in the ring are written:
    rows written + rows dropped == rows pushed."""
    layout = session_layout()
    box = mp.get_context("fork").RawArray("q", 3)
    rec = Recorder(tmp_path / "s.mcap", layout, META, capacity=256, flush_interval=0.005,
                   stream_factory=lambda: GatedStream(box)).start()
    row = rows(layout, 1)[0]
    try:
        assert push_all(rec, row, 100) == 100
        while rec.ring.ctrl[WRITTEN] < 100:
            time.sleep(0.005)
        assert rec.drops == 0 and not rec.alarm
        box[2] = 1  # the disk stalls
        while box[0] == 0 or rec.ring.ctrl[FLUSHES] == 0:
            time.sleep(0.005)
        pushed = 2000
        accepted = push_all(rec, row, pushed)
        assert rec.drops == pushed - accepted > 0 and "behind" in rec.alarm
        assert rec.ring.data.nbytes == 256 * layout.width * 8
        box[2] = 0
    finally:
        box[2] = 0
        rec.close({})
    assert rec.ring.ctrl[WRITTEN] + rec.ring.ctrl[DROPS] == 100 + pushed


def test_lossy_cursor_never_holds_the_producer_and_counts_what_it_missed():
    """The live view's reader: rows it was lapped on (or that may have been overwritten while copied) are
    skipped and counted; the rows it returns are exactly the ones pushed, in order."""
    from teleop.io.recording import Cursor

    ring = Ring(2, 8, gated=False)  # no recorder: the producer overwrites the oldest row
    cur = Cursor(ring, start=0)
    for k in range(10):
        assert ring.push(np.array([k, -k], dtype=float))
    got = cur.read()
    assert got[:, 0].tolist() == list(range(3, 10)) and cur.skipped == 3  # row 2's slot is the next to be written
    assert len(cur.read()) == 0 and cur.skipped == 3
    gated = Ring(2, 4)  # with a recorder: the cursor reads beside it and never frees or blocks a slot
    cur = Cursor(gated)
    for k in range(6):
        gated.push(np.array([k, 0.0]))
    assert gated.ctrl[2] == 2 and cur.read()[:, 0].tolist() == [0.0, 1.0, 2.0, 3.0] and cur.skipped == 0
    assert gated.pop()[:, 0].tolist() == [0.0, 1.0, 2.0, 3.0]  # the recorder still gets every row it kept
