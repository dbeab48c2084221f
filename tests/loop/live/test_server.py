"""teleop.loop.live.server without a session: a viewer's bounded outbox drops its oldest frames and counts them."""

import asyncio

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
