"""`teleop session --live`: a real WebSocket client speaking Foxglove's protocol subscribes to every channel
and receives each at its listed rate within 1 % (counted on the messages' own timestamps: the session clock),
every JSON message valid against its advertised schema; a viewer
that stops reading makes the live process drop frames (counted), while the loop and the recorder lose
nothing to it (their counters)."""

import asyncio
import json

import numpy as np

from teleop.loop.live import channels as lc
from teleop.io.recording import read_session
from tests.io.recording._schemas import check_channel
from tests.loop.live._client import receive_until_closed, start_session, subscribe_all


def run_client(port: int, **kw):
    async def go():
        ws, subs = await subscribe_all(port, kw.pop("rcvbuf", None))
        return subs, await receive_until_closed(ws, **kw)
    return asyncio.run(go())


def test_every_channel_arrives_at_its_rate(tmp_path):
    proc, port = start_session(tmp_path, 4.0)
    subs, frames = run_client(port)
    assert proc.wait(120) == 0, proc.stderr.read()
    out = json.loads((tmp_path / "session.json").read_text())
    by_topic = {ch["topic"]: [] for ch in subs.values()}
    for sid, t_ns, payload in frames:
        by_topic[subs[sid]["topic"]].append((t_ns, payload))
    assert set(by_topic) == set(lc.RATES) | {lc.TOPIC_FAULTS}
    for topic, rate in lc.RATES.items():
        msgs = by_topic[topic]
        t = np.array([m[0] for m in msgs], dtype=np.int64) * 1e-9
        assert len(msgs) >= 2, topic
        got = (len(t) - 1) / (t[-1] - t[0])  # messages per second of session time
        assert abs(got - rate) <= 0.01 * rate, (topic, got, rate)
        if rate >= 10:  # no gap: every period of the session the client saw has its message
            assert np.diff(t).max() <= 1.5 / rate, topic
    assert out["live"]["frames_dropped"] == 0 and out["live"]["rows_skipped"] == 0
    for ch in subs.values():  # every JSON channel: a schema Foxglove parses, every message valid against it
        if ch["schemaEncoding"] == "jsonschema":
            assert check_channel(ch["schema"].encode(), [p for _, p in by_topic[ch["topic"]]], ch["topic"]) > 0
    loop = [json.loads(p) for _, p in by_topic["/live/loop"]]
    assert {"state_name", "lateness_us", "tick_us", "estimate_us"} <= set(loop[-1])
    stylus = json.loads(by_topic["/live/stylus"][-1][1])
    assert len(stylus["measured_cp"]) == 3 and len(stylus["servo_cf"]) == 3
    tensions = json.loads(by_topic["/live/tensions"][-1][1])
    assert len(tensions["tensions"]) == 6 and len(tensions["fsr_counts"]) == 6
    # each cable's raw (at the FSR) and friction-compensated (tip-side) tension, both estimated this session
    comp = np.array(tensions["compensated_tensions"])
    assert comp.shape == (6,) and np.isfinite(comp).all() and (comp > 0).all()
    # the lengths the motors measure (home lengths minus the steps hauled in) beside the commanded ones
    cables = json.loads(by_topic["/live/cables"][-1][1])
    measured, commanded = np.array(cables["measured_lengths"]), np.array(cables["commanded_lengths"])
    assert measured.shape == (6,) and np.abs(measured - commanded).max() < 1e-5
    # the state changes (foxglove.Log, protobuf), sent again to a viewer that subscribed after them
    logs = [p for _, p in by_topic[lc.TOPIC_FAULTS]]
    assert any(b"DISABLED -> ALIGNING" in p for p in logs) and any(b"ALIGNING -> ENABLED" in p for p in logs)
    for _, p in by_topic[lc.TOPIC_SCENE]:  # end effector, force, cables and the default sim pad (z60)
        assert all(k in p for k in (b"end_effector", b"force", b"cables", b"pad/z60"))


def test_a_slow_viewer_costs_dropped_frames_not_loop_time(tmp_path):
    rec = tmp_path / "s.mcap"
    proc, port = start_session(tmp_path, 6.0, "--record", str(rec))
    subs, frames = run_client(port, rcvbuf=4096, stall_s=8.0)  # reads nothing until the session has ended
    assert proc.wait(120) == 0, proc.stderr.read()
    out = json.loads((tmp_path / "session.json").read_text())
    live, timing = out["live"], out["timing"]
    assert live["frames_dropped"] > 0  # the slow viewer's oldest frames were dropped, and counted
    assert live["frames_sent"] + live["frames_dropped"] <= live["frames_published"] * len(subs)
    assert out["drops"] == 0  # the recorder on the same ring lost nothing
    s = read_session(rec)
    assert s.complete and len(s.messages("/loop")) == timing["ticks"]
    # the loop did not wait for the viewer: a loop held back by it would be late for the whole stall
    assert timing["deadline_misses"] <= 0.25 * timing["ticks"], timing


def test_a_port_in_use_is_one_line_exit_2(tmp_path):
    import socket
    import subprocess
    import sys

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        for cmd in (["session", "--seconds", "1"], ["bench", "loop", "--seconds", "1"]):
            r = subprocess.run([sys.executable, "-m", "teleop.apps.cli", *cmd, "--live", str(port), "--record",
                                str(tmp_path / "x.mcap")], capture_output=True, text=True, timeout=60)
            assert r.returncode == 2 and r.stderr.count("\n") == 1 and f"--live {port}" in r.stderr, r.stderr
            assert not (tmp_path / "x.mcap").exists()  # nothing started, nothing written
