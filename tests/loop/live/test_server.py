"""teleop.loop.live.server without a session: a viewer's bounded outbox drops its oldest frames and counts them."""

import asyncio
import json

import websockets

from teleop.loop.live.server import ChannelInfo, FoxgloveServer, Viewer


def test_outbox_drops_oldest_and_counts():
    async def go():
        v = Viewer(ws=None, backlog=3)
        for k in range(5):
            v.offer(bytes([k]))
        return v
    v = asyncio.run(go())
    assert list(v.outbox) == [b"\x02", b"\x03", b"\x04"] and v.dropped == 2


def test_publish_reaches_subscribers_only():
    async def go():
        srv = FoxgloveServer([ChannelInfo(1, "/a", "json", "a", b"{}", "jsonschema"),
                              ChannelInfo(2, "/b", "json", "b", b"{}", "jsonschema")], backlog=8)
        a, b = Viewer(ws=None, backlog=8), Viewer(ws=None, backlog=8)
        srv.viewers += [a, b]
        srv._command(a, '{"op": "subscribe", "subscriptions": [{"id": 7, "channelId": 1}]}')
        srv._command(b, '{"op": "subscribe", "subscriptions": [{"id": 9, "channelId": 2}]}')
        srv._command(b, "not json")  # ignored
        srv.publish(1, 123, b"x")
        srv._command(a, '{"op": "unsubscribe", "subscriptionIds": [7]}')
        srv.publish(1, 124, b"y")
        return a, b
    a, b = asyncio.run(go())
    assert list(a.outbox) == [b"\x01\x07\x00\x00\x00" + (123).to_bytes(8, "little") + b"x"] and not b.outbox


def test_a_normal_disconnect_is_not_a_drop():
    """Frames still queued for a viewer that closes its connection are not counted as dropped."""
    async def go():
        queued = []

        def flood(viewer, channel_id):  # queue frames the moment the viewer subscribes
            for k in range(200):
                srv.publish(channel_id, k, b"x" * 100)
            queued.append(len(viewer.outbox))

        srv = FoxgloveServer([ChannelInfo(1, "/a", "json", "a", b'{"type": "object", "properties": {}}',
                                          "jsonschema")], backlog=512, on_subscribe=flood)
        port = await srv.start("127.0.0.1", 0)
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.websocket.v1"]) as ws:
            await ws.recv()
            await ws.recv()
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": 1}]}))
        for _ in range(200):  # the server notices the close
            if not srv.viewers:
                break
            await asyncio.sleep(0.01)
        await srv.close()
        return srv, queued
    srv, queued = asyncio.run(go())
    assert queued == [200] and not srv.viewers
    assert srv.dropped == 0 and srv.sent < 200  # it left with frames queued: none of them counted as dropped
