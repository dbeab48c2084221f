"""Every JSON channel's schema, recorded and live, is one Foxglove Studio and Lichtblick parse (an object with
properties, nested objects for the timing statistics), names every key its messages carry, and every message
validates against it (jsonschema)."""

import io
import json

import numpy as np
from mcap.reader import make_reader

from teleop.io.recording import SecondStats, SessionWriter
from teleop.io.recording.layout import TOPIC_EVENTS, TOPIC_TIMING
from teleop.loop.live import channels as lc
from teleop.loop.live.process import _channel_list
from teleop.loop.tap import session_layout
from tests.io.recording._schemas import check_channel, foxglove_parse
from tests.io.recording.test_recording import META, rows

N = 2600  # rows 1 ms apart: two whole seconds of timing statistics and a part


def session_rows(layout, n=N):
    R = rows(layout, n, seed=3)
    sl = layout.slices()
    R[:, sl[("/loop", "state")][0]] = np.arange(n) * 5 // n  # every state, FAULT last
    return R


def test_recorded_json_channels():
    layout = session_layout({"t_tip": 6})
    buf = io.BytesIO()
    w = SessionWriter(buf, layout, META, t0_ns=1_700_000_000_000_000_000)
    stats = SecondStats(layout)
    for r in session_rows(layout):
        w.write_row(r)
        s = stats.add(r)
        if s is not None:
            w.write_json(TOPIC_TIMING, float(s["second"]), s)
    w.write_json(TOPIC_EVENTS, 0.01, {"k": 10, "t": 0.01, "src": "DISABLED", "dst": "ALIGNING", "reason": ""})
    w.write_json(TOPIC_EVENTS, 2.5, {"k": 2500, "t": 2.5, "src": "ENABLED", "dst": "FAULT",
                                     "reason": "robot telemetry stale: 20.04 ms > 20 ms"})
    w.finish({"drops": 0})
    reader = make_reader(io.BytesIO(buf.getvalue()))
    summary = reader.get_summary()
    payloads = {ch.topic: [] for ch in summary.channels.values() if ch.message_encoding == "json"}
    for _, ch, msg in reader.iter_messages():
        if ch.message_encoding == "json":
            payloads[ch.topic].append(msg.data)
    assert {TOPIC_TIMING, TOPIC_EVENTS, "/loop", "/stylus"} <= set(payloads)
    for ch in summary.channels.values():
        if ch.message_encoding == "json":
            schema = summary.schemas[ch.schema_id]
            assert schema.encoding == "jsonschema"
            assert check_channel(schema.data, payloads[ch.topic], ch.topic) > 0, ch.topic
    timing = json.loads(payloads[TOPIC_TIMING][0])
    assert timing["ticks"] == 1000 and set(timing["lateness_us"]) == {"mean", "p99", "p999", "max"}


def test_live_json_channels():
    layout = session_layout()
    geometry = {"B": np.eye(6, 3).tolist(), "r": np.zeros((6, 3)).tolist(), "L_home": [0.05] * 6,
                "steps_per_m": 102400.0}
    msgs = lc.RowMessages(layout, geometry)
    stats = SecondStats(layout)
    payloads = {topic: [] for topic in (*lc.PLOTS, lc.TOPIC_TIMING, lc.TOPIC_STATS)}
    for k, r in enumerate(session_rows(layout)):
        for topic in lc.PLOTS:
            payloads[topic].append(msgs.plot(topic, r))
        s = stats.add(r)
        if s is not None:
            payloads[lc.TOPIC_TIMING].append(json.dumps(s).encode())
        if k % 1000 == 0:
            payloads[lc.TOPIC_STATS].append(lc.stats_message(k * 1e-3, k, 2 * k, 3 * k, 1))
    chans = _channel_list(layout)
    assert {c.topic for c in chans} == set(lc.RATES) | {lc.TOPIC_FAULTS}
    for c in chans:
        if c.schema_encoding == "jsonschema":
            assert check_channel(c.schema, payloads[c.topic], c.topic) > 0, c.topic
            foxglove_parse(json.loads(c.advert()["schema"]), c.topic)  # as advertised on the wire
    assert "measured_lengths" in json.loads(payloads["/live/cables"][0])
