"""A Foxglove WebSocket client on the `websockets` package (what Foxglove's app does on "Open connection")."""

from __future__ import annotations

import asyncio
import json
import re
import socket
import struct
import subprocess
import sys

import websockets

SUBPROTOCOL = "foxglove.websocket.v1"


def start_session(tmp_path, seconds: float, *extra) -> tuple[subprocess.Popen, int]:
    """`teleop session --live 0` in a subprocess; returns (process, port) once it serves."""
    proc = spawn_session(tmp_path, seconds, *extra)
    return proc, served_port(proc)


def spawn_session(tmp_path, seconds: float, *extra) -> subprocess.Popen:
    """`teleop session --live 0 --json tmp_path/session.json` in a subprocess, started (served_port: its port)."""
    return subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", "session", "--live", "0", "--seconds",
                             str(seconds), "--json", str(tmp_path / "session.json"), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def served_port(proc: subprocess.Popen) -> int:
    """The port a spawn_session process serves its live view on, once it does."""
    for line in proc.stdout:
        m = re.match(r"live view: ws://127\.0\.0\.1:(\d+)", line)
        if m:
            return int(m.group(1))
    raise AssertionError(f"no live view line; stderr: {proc.stderr.read()}")


async def subscribe_all(port: int, rcvbuf: int | None = None):
    """Connect, read serverInfo and advertise, subscribe to every channel. Returns (ws, {sub id: channel})."""
    sock = None
    if rcvbuf is not None:  # a small receive window: a viewer on a slow link
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        sock.connect(("127.0.0.1", port))
    ws = await websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[SUBPROTOCOL], sock=sock,
                                  max_size=None, max_queue=4)
    assert ws.subprotocol == SUBPROTOCOL
    info = json.loads(await ws.recv())
    assert info["op"] == "serverInfo"
    adv = json.loads(await ws.recv())
    assert adv["op"] == "advertise"
    subs = {i + 100: ch for i, ch in enumerate(adv["channels"])}
    await ws.send(json.dumps({"op": "subscribe",
                              "subscriptions": [{"id": sid, "channelId": ch["id"]} for sid, ch in subs.items()]}))
    return ws, subs


def parse_frame(frame: bytes) -> tuple[int, int, bytes]:
    """(subscription id, timestamp [ns], payload) of a binary messageData frame."""
    op, sid, t_ns = struct.unpack_from("<BIQ", frame)
    assert op == 0x01
    return sid, t_ns, frame[13:]


async def receive_until_closed(ws, stall_s: float = 0.0) -> list:
    """All binary frames until the server closes; with `stall_s` the client first reads nothing that long."""
    if stall_s:
        await asyncio.sleep(stall_s)
    frames = []
    try:
        async for m in ws:
            if isinstance(m, bytes):
                frames.append(parse_frame(m))
    except websockets.ConnectionClosed:
        pass
    return frames
