"""The recorder process and its loop-side handle.

The loop copies one row per tick into a shared-memory Ring (`Recorder.push`: no syscall, no lock, no
allocation); a separate recorder *process* (so no interpreter lock is shared with the loop) turns rows into
JSON messages and writes them with SessionWriter. It closes a chunk (`flush`) whenever `flush_interval` has
passed on either clock: the monotonic clock, or the session time of the rows it has written (so a crash
loses at most about `flush_interval` of rows even when the recorder catches up on a backlog). When the disk
is slow or full the ring fills, the loop's pushes are dropped and counted (memory stays bounded) and an alarm
is raised. The recorder also computes the per-second timing statistics (/loop/timing) from the rows, and
notices when the loop process dies: it then drains the ring and finishes the file, its `session_end` naming
the last state the rows carried, the last fault reason it was sent and why the session ended (`interrupted`).

ctrl counters a test or the loop can read (teleop.io.recording.ring): rows pushed, popped, dropped, written,
made durable (written before the last completed flush), flushes.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import time
from pathlib import Path

import numpy as np

from teleop.io.recording.foxglove import STATE_NAMES
from teleop.io.recording.layout import TOPIC_EVENTS, TOPIC_TIMING, Layout
from teleop.io.recording.ring import (ALARM_ERROR, ALARM_FULL, DROPS, DURABLE, FLUSHES, HEAD, OK, STATUS, STOP,
                                   T0_NS, TAIL, WRITTEN, Ring)
from teleop.io.recording.stats import SecondStats
from teleop.io.recording.writer import SessionWriter
from teleop.io.stop_signals import ignore_stop_signals


def time_sharing(nice: int) -> None:
    """Leave any real-time policy inherited from the loop (a helper process must yield to it), at `nice`."""
    try:
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    except (AttributeError, OSError):
        pass
    try:
        os.nice(nice)
    except OSError:
        pass


def drain_pipe(conn):
    """Yield the (kind, obj) messages waiting on a loop-to-helper pipe (JSON [kind, obj]); never blocks."""
    while conn.poll():
        try:
            kind, obj = json.loads(conn.recv_bytes())
        except (EOFError, OSError, ValueError):
            return
        yield kind, obj


def _recorder_main(path: str, layout_json: str, ring: Ring, conn, metadata: dict, t0_ns: int,
                   flush_interval: float, parent_pid: int, stream_factory=None) -> None:
    """Recorder process: drain the ring into the MCAP file until stopped or the loop process is gone."""
    ignore_stop_signals()  # the group's SIGINT/SIGTERM/SIGHUP: the loop process closes the recording in order
    layout = Layout.from_json(layout_json)
    ctrl = ring.ctrl
    time_sharing(-10)  # behind the loop, ahead of the other time-sharing processes where the OS lets us
    try:
        stream = stream_factory() if stream_factory is not None else open(path, "wb")
        writer = SessionWriter(stream, layout, metadata, t0_ns)
    except OSError as exc:
        ctrl[STATUS] = ALARM_ERROR
        _send_status(conn, f"recording failed to start: {exc}")
        return
    stats = SecondStats(layout)
    t_col = layout.slices()[("/loop", "t")][0]
    state_col = (layout.slices().get(("/loop", "state")) or (None,))[0]
    last_flush = time.monotonic()
    t_flushed = None  # session time of the last row written before the last flush [s]
    end_meta = None  # the loop's session_end, once it sends one
    last_row, fault_reason = None, ""
    orphaned = False
    try:
        while True:
            orphaned = orphaned or os.getppid() != parent_pid
            stopping = bool(ctrl[STOP]) or orphaned
            rows = ring.pop(2000)
            if len(rows) and ctrl[T0_NS]:
                writer.t0_ns = int(ctrl[T0_NS])  # wall-clock time of session time 0, set by the loop at start
            for row in rows:
                writer.write_row(row)
                s = stats.add(row)
                if s is not None:
                    writer.write_json(TOPIC_TIMING, float(s["second"]), s)
                t_row = row[t_col]
                ctrl[WRITTEN] += 1
                if t_flushed is None:
                    t_flushed = t_row
                elif t_row - t_flushed >= flush_interval:  # the rows' own clock
                    writer.flush()
                    ctrl[FLUSHES] += 1
                    ctrl[DURABLE] = ctrl[WRITTEN]
                    t_flushed, last_flush = t_row, time.monotonic()
            if len(rows):
                last_row = rows[-1]
            for kind, obj in drain_pipe(conn):
                if kind == "event":
                    writer.write_json(TOPIC_EVENTS, float(obj.get("t", 0.0)), obj)
                    if obj.get("dst") == "FAULT":
                        fault_reason = str(obj.get("reason", ""))
                elif kind == "end":
                    end_meta = obj
            now = time.monotonic()
            if now - last_flush >= flush_interval:  # the monotonic clock (an idle or slow producer)
                writer.flush()
                ctrl[FLUSHES] += 1
                ctrl[DURABLE] = ctrl[WRITTEN]
                last_flush = now
                if len(rows):
                    t_flushed = rows[-1][t_col]
            if stopping and ctrl[HEAD] == ctrl[TAIL]:
                break
            if len(rows) == 0:
                time.sleep(0.005)
        if stats.rows:
            s = stats.summary()
            writer.write_json(TOPIC_TIMING, float(s["second"]), s)
        if end_meta is None:  # no end record from the loop: if it died, what the rows and events tell
            end_meta = _end_without_loop(last_row, state_col, t_col, fault_reason, parent_pid) if orphaned else {}
        end_meta.setdefault("drops", int(ctrl[DROPS]))
        end_meta.setdefault("rows_written", int(ctrl[WRITTEN]))
        writer.finish(end_meta)
        ctrl[DURABLE] = ctrl[WRITTEN]
        stream.close()
    except OSError as exc:  # disk full, I/O error: stop writing, raise the alarm; the loop goes on
        ctrl[STATUS] = ALARM_ERROR
        _send_status(conn, f"recording stopped: {exc}")


def _end_without_loop(row, state_col, t_col, fault_reason: str, parent_pid: int) -> dict:
    """session_end written by the recorder itself when the loop process died without sending one: the state
    of the last row written, the last fault's reason, and why the session ended."""
    state = "unknown"
    if row is not None and state_col is not None:
        k = int(row[state_col])
        state = STATE_NAMES[k] if 0 <= k < len(STATE_NAMES) else str(k)
    why = f"loop process {parent_pid} ended without closing the recording (killed or crashed)"
    return {"final_state": state, "fault_reason": fault_reason, "interrupted": why,
            "t_last": float(row[t_col]) if row is not None else None, "closed_by": "recorder"}


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
