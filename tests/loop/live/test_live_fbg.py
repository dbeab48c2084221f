"""The live view's FBG channel (/live/fbg) for sessions of the FBG sensor kinds: advertised with a schema Foxglove
parses and every message validates against, only when the session's rows carry the recording's FBG channel,
paced at its rate over the rows that hold an FBG reading; and from a real `teleop session --live` with
`sim://robot?sensor=fbg`, received by a Foxglove WebSocket client at that rate."""

import asyncio
import json
from types import SimpleNamespace

import numpy as np
import pytest

from teleop.io.recording.sensors import GATE, TOPIC_FBG
from teleop.loop.live import channels as lc
from teleop.loop.live.process import _channel_list
from teleop.loop.sensor_tap import with_fbg_channel
from teleop.loop.tap import session_layout
from tests.io.recording._schemas import check_channel, foxglove_parse
from tests.io.recording.test_recording import rows
from tests.loop.live._client import receive_until_closed, start_session, subscribe_all

GEOMETRY = {"B": np.eye(6, 3).tolist(), "r": np.zeros((6, 3)).tolist(), "L_home": [0.05] * 6,
            "steps_per_m": 102400.0}
KINDS = {"fbg": SimpleNamespace(kind="fbg", n=6), "one": SimpleNamespace(kind="one", n=6, cable=2)}


def fbg_layout(kind):
    return with_fbg_channel(session_layout(), KINDS[kind])


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_fbg_channel_schema_and_messages(kind):
    layout = fbg_layout(kind)
    chans = {c.topic: c for c in _channel_list(layout)}
    assert set(chans) == set(lc.rates(layout)) | {lc.TOPIC_FAULTS}
    assert lc.TOPIC_FBG_LIVE in chans and lc.rates(layout)[lc.TOPIC_FBG_LIVE] == lc.RATE_FBG
    R = rows(layout, 300, seed=5)
    msgs = lc.RowMessages(layout, GEOMETRY)
    payloads = [msgs.plot(lc.TOPIC_FBG_LIVE, r) for r in R]
    c = chans[lc.TOPIC_FBG_LIVE]
    assert check_channel(c.schema, payloads, c.topic) == len(payloads)
    foxglove_parse(json.loads(c.advert()["schema"]), c.topic)
    m = json.loads(payloads[0])
    recorded = {s.name for s in layout.signals if s.topic == TOPIC_FBG} - {GATE}
    assert set(m) == recorded | {"tick", "t"}
    k = 6 if kind == "fbg" else 1
    for name in lc.FBG_PER_SENSOR:  # a list per FBG, also for the one instrumented cable
        assert isinstance(m[name], list) and len(m[name]) == k, (name, m[name])
    if kind == "one":
        assert len(m["proximal"]) == 6 and isinstance(m["rest_ratio"], float)


def test_fsr_sessions_have_no_fbg_channel():
    layout = session_layout()
    assert lc.plots(layout) == lc.PLOTS and lc.rates(layout) == lc.RATES and not lc.gate_columns(layout)
    assert lc.TOPIC_FBG_LIVE not in {c.topic for c in _channel_list(layout)}


def test_fbg_channel_paced_over_the_rows_with_an_fbg_reading():
    """Rows 1 ms apart, an FBG reading on every third: /live/fbg at 100 Hz of session time, each message on a
    row that carries one; the other plots at their own rate on every row."""
    layout = fbg_layout("fbg")
    n = 3000
    R = np.zeros((n, layout.width))
    sl = layout.slices()
    R[:, sl[("/loop", "t")][0]] = np.arange(n) * 1e-3 + 3e-8 * np.sin(np.arange(n))  # jitter of tens of ns
    gate = sl[(TOPIC_FBG, GATE)][0]
    R[::3, gate] = 1
    sched = lc.Schedule(layout)
    due = {topic: [] for topic in sched.pacers}
    for k, r in enumerate(R):
        for topic in sched.due(r, float(r[sl[("/loop", "t")][0]])):
            due[topic].append(k)
    fbg = np.array(due[lc.TOPIC_FBG_LIVE])
    assert (fbg % 3 == 0).all() and len(fbg) == n // 10  # 3 s at 100 Hz
    assert set(np.diff(fbg)) <= {9, 12}  # the first FBG row at or after each 10 ms deadline
    assert len(due["/live/tensions"]) == n // 10 and len(due[lc.TOPIC_SCENE]) == n // 100


def test_live_session_with_fbg_sensors_publishes_the_fbg_channel(tmp_path):
    proc, port = start_session(tmp_path, 3.0, "--robot", "sim://robot?sensor=fbg")

    async def go():
        ws, subs = await subscribe_all(port)
        return subs, await receive_until_closed(ws)
    subs, frames = asyncio.run(go())
    assert proc.wait(120) == 0, proc.stderr.read()
    ch = next(c for c in subs.values() if c["topic"] == lc.TOPIC_FBG_LIVE)
    got = [(t_ns, p) for sid, t_ns, p in frames if subs[sid]["topic"] == lc.TOPIC_FBG_LIVE]
    t = np.array([g[0] for g in got], dtype=np.int64) * 1e-9
    rate = (len(t) - 1) / (t[-1] - t[0])  # messages per second of session time
    assert abs(rate - lc.RATE_FBG) <= 0.01 * lc.RATE_FBG, rate
    # every row of this robot holds an FBG reading: the same rows as the other 100 Hz plots (a loop late on a
    # loaded machine stretches the session time between two rows for every channel alike)
    ticks = [json.loads(p)["tick"] for _, p in got]
    assert ticks == [json.loads(p)["tick"] for sid, _, p in frames if subs[sid]["topic"] == "/live/tensions"]
    assert check_channel(ch["schema"].encode(), [p for _, p in got], ch["topic"]) == len(got)
    last = json.loads(got[-1][1])
    assert last["fbg_cable"] == list(range(6))
    # each cable's distal tension, seed 001 eq 3 on the FBG shifts: near the 2.85 N pretension (0.37 N noise)
    force = np.array([json.loads(p)["fbg_force"] for _, p in got])
    assert force.shape[1] == 6 and 1.5 < np.median(force) < 4.5
