"""The experimenter's live screen for `teleop blind-test --operator human --live`: trial, pad, answers and the
participant's force, over the same Foxglove WebSocket server as the session's live view.

Channels: /blind/trial (JSON: participant, question, the zones and slots being compared, the pad under each
slot - the coordinator's knowledge, never shown to the participant), /blind/answers (foxglove.Log: every
answer and the ratings), /blind/scene (foxglove.SceneUpdate: the pad's areas, the two being compared
highlighted, labelled with their material), /blind/force (JSON: the stylus force [N] and position [m] of
the loop, relayed from the session's own live view when a real stylus runs one).

The server runs on an asyncio loop in a thread of the study process (the study waits on the coordinator's
keyboard, not on a clock); `on_step` is the hook teleop.apps.protocols.blind.human calls.
"""

from __future__ import annotations

import asyncio
import json
import struct
import threading
import time

import websockets
from foxglove.messages import (Color, CylinderPrimitive, Log, LogLevel, Pose, Quaternion, SceneEntity, SceneUpdate,
                               TextPrimitive, Vector3)

from teleop.io.recording.foxglove import stamp
from teleop.loop.live.server import SUBPROTOCOL, ChannelInfo, FoxgloveServer

SLOTS = "ABCDEFGH"
TOPIC_TRIAL, TOPIC_ANSWERS, TOPIC_SCENE, TOPIC_FORCE = "/blind/trial", "/blind/answers", "/blind/scene", "/blind/force"
RATE_FORCE = 50.0  # relayed force messages per second (at most)


class StudyLiveView:
    """Serve the study's progress to Foxglove.

    Args:
        host, port: where to serve (port 0: any free port; `.port` after start).
        centres: (n, 2) slot centres [m] on the pad (slot i = area i), for the 3D scene.
        labels: {area name: label} of the pads.
        relay_port: the session's live view port whose /live/stylus is relayed as /blind/force (None: none).
    """

    def __init__(self, host: str, port: int, centres, labels: dict, relay_port: int | None = None):
        self.host, self.requested_port = host, int(port)
        self.centres = [tuple(map(float, c)) for c in centres]
        self.labels = dict(labels)
        self.relay_port = relay_port
        self.port = 0
        self.layout: list = []
        self.compare: tuple = ()
        self.trial: dict = {}
        self.answers: list = []  # (t_ns, Log payload), resent to a viewer that subscribes late
        self.relayed = 0
        self._ready = threading.Event()

    def start(self, timeout: float = 10.0) -> "StudyLiveView":
        chans = [ChannelInfo(1, TOPIC_TRIAL, "json", "blind.trial", b'{"type": "object"}', "jsonschema"),
                 ChannelInfo(2, TOPIC_ANSWERS, "protobuf", Log.get_schema().name, bytes(Log.get_schema().data),
                             "protobuf"),
                 ChannelInfo(3, TOPIC_SCENE, "protobuf", SceneUpdate.get_schema().name,
                             bytes(SceneUpdate.get_schema().data), "protobuf"),
                 ChannelInfo(4, TOPIC_FORCE, "json", "blind.force", b'{"type": "object"}', "jsonschema")]
        self.cid = {c.topic: c.id for c in chans}
        self.server = FoxgloveServer(chans, name="cdpr-teleop blind test", on_subscribe=self._resend)
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self._run, name="teleop-study-live", daemon=True)
        self.thread.start()
        if not self._ready.wait(timeout) or not self.port:
            raise OSError(f"live view: cannot serve on {self.host}:{self.requested_port}")
        return self

    def _run(self) -> None:
        asyncio.set_event_loop(self.loop)
        try:
            self.port = self.loop.run_until_complete(self.server.start(self.host, self.requested_port))
        except OSError:
            self._ready.set()
            return
        self._ready.set()
        if self.relay_port:
            self.loop.create_task(self._relay())
        self.loop.run_forever()

    def _resend(self, viewer, channel_id) -> None:
        now = time.time_ns()
        if channel_id == self.cid[TOPIC_ANSWERS]:
            for t_ns, payload in self.answers:
                self.server.send_to(viewer, channel_id, t_ns, payload)
        elif channel_id == self.cid[TOPIC_TRIAL] and self.trial:
            self.server.send_to(viewer, channel_id, now, json.dumps(self.trial).encode())
        elif channel_id == self.cid[TOPIC_SCENE] and self.layout:
            self.server.send_to(viewer, channel_id, now, self._scene(now))

    def on_step(self, event: dict) -> None:
        """Hook for teleop.apps.protocols.blind.human.run_human_study (called from the study's thread)."""
        self.loop.call_soon_threadsafe(self._step, dict(event))

    def _step(self, ev: dict) -> None:
        now = time.time_ns()
        kind = ev.get("kind")
        if kind == "participant":
            self.layout, self.compare = list(ev["layout"]), ()
        elif kind == "compare":
            self.compare = (ev["new_slot"], ev["ref_slot"])
        self.trial = {**self.trial, **ev, "pads": {SLOTS[i]: self.labels.get(a, a) for i, a in enumerate(self.layout)}}
        self.server.publish(self.cid[TOPIC_TRIAL], now, json.dumps(self.trial).encode())
        if kind in ("answer", "ratings"):
            if kind == "answer":
                text = (f"participant {ev['participant']}: zone {ev['new_zone']} vs zone {ev['ref_zone']}: "
                        f"{ev['answer']}")
            else:
                text = f"participant {ev['participant']}: ratings {ev['ratings']} for zones {ev['ranking_zones']}"
            payload = Log(timestamp=stamp(now), level=LogLevel.Info, message=text, name="blind-test", file="",
                          line=0).encode()
            self.answers.append((now, payload))
            self.server.publish(self.cid[TOPIC_ANSWERS], now, payload)
        if self.layout:
            self.server.publish(self.cid[TOPIC_SCENE], now, self._scene(now))

    def _scene(self, t_ns: int) -> bytes:
        ident = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
        entities = []
        for i, (x, y) in enumerate(self.centres[:len(self.layout)]):
            active = i in self.compare
            color = Color(r=1.0, g=0.6, b=0.0, a=1.0) if active else Color(r=0.6, g=0.6, b=0.7, a=0.8)
            pose = Pose(position=Vector3(x=x, y=y, z=0.0), orientation=ident)
            label = f"{SLOTS[i]}: {self.labels.get(self.layout[i], self.layout[i])}"
            entities.append(SceneEntity(
                timestamp=stamp(t_ns), frame_id="pad", id=f"slot/{SLOTS[i]}",
                cylinders=[CylinderPrimitive(pose=pose, size=Vector3(x=0.018, y=0.018, z=0.004), bottom_scale=1.0,
                                             top_scale=1.0, color=color)],
                texts=[TextPrimitive(pose=Pose(position=Vector3(x=x, y=y, z=0.008), orientation=ident),
                                     billboard=True, font_size=14.0, scale_invariant=True,
                                     color=Color(r=1.0, g=1.0, b=1.0, a=1.0), text=label)]))
        return SceneUpdate(entities=entities).encode()

    async def _relay(self) -> None:
        """Relay the session's /live/stylus (force, position) as /blind/force, at most RATE_FORCE per second."""
        while True:
            try:
                async with websockets.connect(f"ws://127.0.0.1:{self.relay_port}", subprotocols=[SUBPROTOCOL],
                                              max_size=None) as ws:
                    json.loads(await ws.recv())
                    adv = json.loads(await ws.recv())
                    ch = next(c for c in adv["channels"] if c["topic"] == "/live/stylus")
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": ch["id"]}]}))
                    last = 0
                    async for m in ws:
                        if isinstance(m, bytes) and len(m) > 13:
                            t_ns = struct.unpack_from("<Q", m, 5)[0]
                            if t_ns - last >= 1e9 / RATE_FORCE:
                                last = t_ns
                                self.server.publish(self.cid[TOPIC_FORCE], t_ns, m[13:])
                                self.relayed += 1
            except (OSError, websockets.WebSocketException, StopIteration, ValueError):
                await asyncio.sleep(0.5)  # the session is starting or restarting: try again

    def close(self) -> None:
        if not self.thread.is_alive():
            return

        async def stop():
            await self.server.close()
        fut = asyncio.run_coroutine_threadsafe(stop(), self.loop)
        try:
            fut.result(5)
        finally:
            for task in asyncio.all_tasks(self.loop):
                self.loop.call_soon_threadsafe(task.cancel)
            self.loop.call_soon_threadsafe(self.loop.stop)
            self.thread.join(5)
