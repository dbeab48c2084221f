"""`teleop recover`: a recording whose recorder was killed (SIGKILL: no summary, no footer, a half-written last
record) becomes a complete, indexed MCAP that pip mcap's default reader and its seeking (indexed) reader read,
holding every message that was flushed; a cut at any byte gives a readable file or one clear line; bad input is
one line, exit 2, nothing written."""

import io
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from mcap.reader import SeekingReader, make_reader
from mcap.records import Message
from mcap.stream_reader import StreamReader

from teleop.core.errors import InputError
from teleop.io.recording import Recorder, parse_session, read_session
from teleop.io.recording.recover import RECOVERED, recover_bytes
from teleop.loop.tap import session_layout
from tests.io.recording.test_recording import SMALL, write_file

META = {"configuration": {}, "calibration": {}, "firmware_version": "test", "software_version": "test"}


def flushed_messages(data: bytes) -> int:
    """Messages pip mcap's streaming reader returns before the damage (what was flushed whole)."""
    n = 0
    try:
        for rec in StreamReader(io.BytesIO(data), validate_crcs=True, record_size_limit=len(data)).records:
            n += isinstance(rec, Message)
    except Exception:  # noqa: BLE001 - the truncated tail ends the count
        pass
    return n


def cli(*args):
    return subprocess.run([sys.executable, "-m", "teleop.apps.cli", "recover", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def killed_recording(path, ticks=700):
    """A Recorder fed `ticks` session rows 1 ms apart, then killed with SIGKILL mid-write."""
    layout = session_layout()
    rec = Recorder(path, layout, META, capacity=4096, flush_interval=0.1).start()
    while not path.exists() or path.stat().st_size == 0:
        time.sleep(0.002)
    rec.set_t0(time.time_ns())
    sl = layout.slices()
    row = np.zeros(layout.width)
    for k in range(ticks):
        row[sl[("/loop", "tick")][0]], row[sl[("/loop", "t")][0]] = k, k * 1e-3
        rec.push(row)
        time.sleep(0.0005)
    os.kill(rec.proc.pid, signal.SIGKILL)
    rec.proc.join()
    rec.proc = None


def test_recover_a_killed_recording(tmp_path):
    src, out = tmp_path / "killed.mcap", tmp_path / "fixed.mcap"
    killed_recording(src)
    data = src.read_bytes()
    with pytest.raises(Exception):  # what the issue saw: pip mcap's default reader cannot read it
        with open(src, "rb") as fh:
            sum(1 for _ in make_reader(fh).iter_messages())
    r = cli(src, "--out", out)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    n = flushed_messages(data)
    assert n > 0
    before = read_session(src)  # the project's own reader keeps as much: the last whole chunk too
    assert len(before.records) + sum(before.views.values()) == n and not before.complete
    with open(out, "rb") as fh:
        reader = make_reader(fh)
        assert isinstance(reader, SeekingReader)  # the indexed reader
        summary = reader.get_summary()
        assert summary.statistics.message_count == n and summary.chunk_indexes
        assert sum(1 for _ in reader.iter_messages()) == n
        meta = {m.name: m for m in reader.iter_metadata()}
    assert {"session", RECOVERED} <= set(meta)
    s = read_session(out)
    assert s.complete and s.is_intact
    ticks = [m["tick"] for m in s.messages("/loop")]
    assert ticks == list(range(len(ticks)))  # the flushed prefix, in order
    assert src.read_bytes() == data  # the input untouched


def test_every_cut_recovers_or_says_why():
    _, _, data = write_file(12, flush_every=3, layout=SMALL)
    full = flushed_messages(data)
    for cut in sorted(set(range(0, 200)) | set(range(200, len(data), 7)) | set(range(len(data) - 100, len(data) + 1))):
        buf = io.BytesIO()
        try:
            rep = recover_bytes(data[:cut], buf, "cut.mcap")
        except InputError as exc:  # no header survived (or not even the magic): one line
            assert "\n" not in str(exc) and cut < 100
            continue
        out = buf.getvalue()
        n = sum(1 for _ in make_reader(io.BytesIO(out)).iter_messages())
        assert n == rep.messages == flushed_messages(data[:cut]) <= full
        s = parse_session(data[:cut])
        assert len(s.records) + sum(s.views.values()) == n
        assert rep.complete == (rep.stopped == "") and (n == full if rep.complete else rep.stopped)
    assert rep.complete and n == full


def test_bad_input_is_one_line_exit_2(tmp_path):
    src = tmp_path / "a.mcap"
    src.write_bytes(write_file(5, layout=SMALL)[2][:300])
    text = tmp_path / "notes.txt"
    text.write_text("not a recording\n")
    for args in ((tmp_path / "missing.mcap", "--out", tmp_path / "x.mcap"), (text, "--out", tmp_path / "x.mcap"),
                 (src, "--out", src), (src,), (src, "--out", tmp_path)):
        r = cli(*args)
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and "Traceback" not in r.stderr, (args, r.stderr)
    assert not (tmp_path / "x.mcap").exists() and sorted(p.name for p in tmp_path.iterdir()) == ["a.mcap",
                                                                                              "notes.txt"]
