"""The live view's process: reads the loop's shared-memory ring (a lossy Cursor, never holding the loop or the
recorder back), builds the channels of teleop.loop.live.channels at their rates and serves them to Foxglove.

It runs at a lower priority than the recorder (nice +5, never real-time): when the machine is short of CPU
the viewer falls behind, the rows it missed are skipped and counted, and the loop does not notice. A viewer
that reads slowly has its oldest frames dropped (and counted) by teleop.loop.live.server.
"""

from __future__ import annotations

import asyncio
import json
import multiprocessing as mp
import os
import time

from foxglove.messages import FrameTransforms, Log, SceneUpdate

from teleop.io.recording.foxglove import fault_log
from teleop.loop.live import channels as lc
from teleop.loop.live.server import ChannelInfo, FoxgloveServer
from teleop.io.recording.layout import Layout
from teleop.io.recording.recorder import drain_pipe, time_sharing
from teleop.io.recording.ring import HEAD, T0_NS, Cursor, Ring
from teleop.io.recording.stats import SecondStats, timing_schema
from teleop.io.stop_signals import ignore_stop_signals

# shared counters of the live process (int64)
PORT, SKIPPED, DROPPED, SENT, CLIENTS, STOP, READY, PUBLISHED, FAILED = range(9)
N_STATS = 9
MAX_EVENTS = 200  # state changes kept to send a viewer that subscribes late


def _channel_list(layout: Layout) -> list:
    out = []

    def add(topic, encoding, name, schema, schema_encoding):
        out.append(ChannelInfo(len(out) + 1, topic, encoding, name, schema, schema_encoding))

    for topic in lc.plots(layout):
        add(topic, "json", topic.strip("/").replace("/", "."), lc.plot_schema(layout, topic), "jsonschema")
    for topic, cls in ((lc.TOPIC_TF, FrameTransforms), (lc.TOPIC_SCENE, SceneUpdate), (lc.TOPIC_FAULTS, Log)):
        sc = cls.get_schema()
        add(topic, "protobuf", sc.name, bytes(sc.data), "protobuf")
    add(lc.TOPIC_TIMING, "json", "live.timing", timing_schema(layout), "jsonschema")
    add(lc.TOPIC_STATS, "json", "live.stats", lc.stats_schema(), "jsonschema")
    return out


async def _serve(layout: Layout, ring: Ring, conn, host: str, port: int, st, scene: dict, parent_pid: int,
                 backlog: int) -> None:
    chans = _channel_list(layout)
    cid = {c.topic: c.id for c in chans}
    events: list = []  # (t_ns, Log payload)

    def resend(viewer, channel_id):
        if channel_id == cid[lc.TOPIC_FAULTS]:
            for t_ns, payload in events:
                server.send_to(viewer, channel_id, t_ns, payload)

    server = FoxgloveServer(chans, backlog=backlog, on_subscribe=resend)
    st[PORT] = await server.start(host, port)
    st[READY] = 1
    msgs = lc.RowMessages(layout, scene.get("geometry"), scene.get("pads"))
    stats = SecondStats(layout)
    cursor = Cursor(ring, start=int(ring.ctrl[HEAD]))
    t_col = layout.slices()[("/loop", "t")][0]
    schedule = lc.Schedule(layout)
    plot_topics = set(lc.plots(layout))
    published = 0

    def subscribed(topic):
        c = cid[topic]
        return any(c in v.subs for v in server.viewers)

    def send(topic, t_ns, payload):
        nonlocal published
        server.publish(cid[topic], t_ns, payload)
        published += 1

    while not st[STOP] and os.getppid() == parent_pid:
        rows = cursor.read(2000)
        t0_ns = int(ring.ctrl[T0_NS]) or time.time_ns()
        for row in rows:
            t = float(row[t_col])
            t_ns = t0_ns + int(round(t * 1e9))
            s = stats.add(row)
            if s is not None and subscribed(lc.TOPIC_TIMING):
                send(lc.TOPIC_TIMING, t_ns, json.dumps(s).encode())
            for topic in schedule.due(row, t):
                if not subscribed(topic):
                    continue
                if topic in plot_topics:
                    send(topic, t_ns, msgs.plot(topic, row))
                elif topic == lc.TOPIC_TF:
                    send(topic, t_ns, msgs.transforms(row, t_ns))
                elif topic == lc.TOPIC_SCENE:
                    send(topic, t_ns, msgs.scene(row, t_ns))
                elif topic == lc.TOPIC_STATS:
                    send(topic, t_ns, lc.stats_message(t, cursor.skipped, server.dropped, server.sent,
                                                       len(server.viewers)))
        for kind, obj in drain_pipe(conn):
            if kind == "event":
                t_ns = t0_ns + int(round(float(obj.get("t", 0.0)) * 1e9))
                payload = fault_log(obj, t_ns)
                events.append((t_ns, payload))
                del events[:-MAX_EVENTS]
                send(lc.TOPIC_FAULTS, t_ns, payload)
        st[SKIPPED], st[DROPPED], st[SENT] = cursor.skipped, server.dropped, server.sent
        st[CLIENTS], st[PUBLISHED] = len(server.viewers), published
        await asyncio.sleep(0.005 if len(rows) < 100 else 0)
    # let the viewers' writers send what is queued (bounded: a stalled viewer is not waited for)
    deadline = time.monotonic() + 0.5
    while any(v.outbox for v in server.viewers) and time.monotonic() < deadline:
        await asyncio.sleep(0.01)
    st[SKIPPED], st[DROPPED], st[SENT] = cursor.skipped, server.dropped, server.sent
    await server.close()


def _live_main(layout_json: str, ring: Ring, conn, host: str, port: int, st, scene: dict, parent_pid: int,
               backlog: int) -> None:
    ignore_stop_signals()  # the group's SIGINT/SIGTERM/SIGHUP: the loop process closes the view
    time_sharing(5)  # behind the loop, the robot process and the recorder
    try:
        asyncio.run(_serve(Layout.from_json(layout_json), ring, conn, host, port, st, scene, parent_pid, backlog))
    except OSError as exc:  # taken since the CLI checked it: the session goes on without a live view
        print(f"teleop: warning: live view: cannot serve on {host}:{port}: {exc.strerror or exc}", flush=True)
        st[FAILED] = 1
        st[READY] = 1


class LiveView:
    """Loop-side handle of the live view process.

    Args:
        layout: row layout of the ring.
        ring: the shared-memory ring the loop pushes into (the recorder's, or one of its own).
        host, port: where to serve (port 0: any free port; see `.port` after start).
        scene: {"geometry": {"B", "r"}, "pads": [...]} for the 3D scene (teleop.loop.live.channels.RowMessages).
        backlog: frames queued per viewer before the oldest is dropped.
    """

    def __init__(self, layout: Layout, ring: Ring, host: str = "127.0.0.1", port: int = 8765,
                 scene: dict | None = None, backlog: int = 256):
        self.layout, self.ring = layout, ring
        self.host, self.requested_port = host, int(port)
        self.scene = scene or {}
        self.backlog = int(backlog)
        self.ctx = mp.get_context("fork")
        self.st = self.ctx.RawArray("q", N_STATS)
        self.proc = None
        self.event_drops = 0

    def start(self, timeout: float = 10.0) -> "LiveView":
        rx, self.tx = self.ctx.Pipe(duplex=False)
        self.proc = self.ctx.Process(target=_live_main, name="teleop-live", daemon=False,
                                     args=(self.layout.to_json(), self.ring, rx, self.host, self.requested_port,
                                           self.st, self.scene, os.getpid(), self.backlog))
        self.proc.start()
        os.set_blocking(self.tx.fileno(), False)
        deadline = time.monotonic() + timeout
        while not self.st[READY] and self.proc.is_alive() and time.monotonic() < deadline:
            time.sleep(0.01)
        return self

    @property
    def port(self) -> int:
        return int(self.st[PORT])

    @property
    def failed(self) -> bool:
        return bool(self.st[FAILED]) or (self.proc is not None and not self.st[READY])

    def event(self, obj: dict) -> None:
        """Send a state change (non-blocking; dropped and counted if the pipe is full)."""
        try:
            self.tx.send_bytes(json.dumps(["event", obj], default=str).encode())
        except (BlockingIOError, OSError, ValueError):
            self.event_drops += 1

    def stats(self) -> dict:
        """The live view's counters: rows skipped (it fell behind the ring), frames dropped for slow viewers."""
        s = self.st
        return {"port": int(s[PORT]), "rows_skipped": int(s[SKIPPED]), "frames_dropped": int(s[DROPPED]),
                "frames_sent": int(s[SENT]), "frames_published": int(s[PUBLISHED]), "viewers": int(s[CLIENTS]),
                "event_drops": self.event_drops}

    def close(self, timeout: float = 5.0) -> dict:
        if self.proc is None:
            return self.stats()
        self.st[STOP] = 1
        self.proc.join(timeout)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join()
        self.proc = None
        return self.stats()
