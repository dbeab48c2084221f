"""A session recording (MCAP, teleop.io.recording) exported to the interchange CSV and read back."""

import numpy as np
import pytest

from teleop.io.recording_io import read_interchange
from teleop.io.session_export import cable_columns, export_session
from teleop.io.recording import INT, Layout, SessionWriter, Signal, read_session
from teleop.io.recording.sensors import GATE, TOPIC_FBG, fbg_signals
from teleop.apps.cli import main
from teleop.loop.tap import session_layout


def test_session_export_round_trip(tmp_path):
    layout = Layout((Signal("/loop", "tick", 1, INT), Signal("/loop", "t"),
                     Signal("/robot/measured", "commanded_lengths", 6), Signal("/estimation", "tensions", 6)))
    t = np.arange(300) * 1e-3
    lengths = 0.05 + 2e-3 * np.sin(2 * np.pi * 2 * t)[:, None] * np.arange(1, 7)
    tensions = 3 + np.cos(2 * np.pi * t)[:, None] * np.arange(1, 7)
    path = tmp_path / "s.mcap"
    with open(path, "wb") as fh:
        w = SessionWriter(fh, layout, {"config": "test"}, 0)
        for k in range(t.size):
            w.write_row(np.concatenate([[k, t[k]], lengths[k], tensions[k]]))
        w.finish({"drops": 0})
    out = export_session(path, tmp_path / "s.csv", cable_columns(2), {"load": "external"})
    rec = read_interchange(out)
    assert rec.metadata["load"] == "external"
    np.testing.assert_allclose(rec.t, t, atol=1e-9)
    np.testing.assert_allclose(rec.channels["motor_pos"], lengths[:, 2], atol=1e-9)
    np.testing.assert_allclose(rec.channels["motor_force"], tensions[:, 2], rtol=1e-8)


def test_teleop_export_writes_the_fbg_columns_of_a_one_sensor_session(tmp_path, capsys):
    """`teleop export` of a session with the FBG channel (sensor one on cable 0): the instrumented cable gets
    its FBG shifts and eq 3 tension, every cable its tip-side estimate, and motor_force_N is the proximal FSR
    tension the one-sensor model read (not the estimate, which is tip-side)."""
    base = session_layout()
    layout = Layout(tuple(base.signals) + tuple(fbg_signals(1, True)), {**base.gates, TOPIC_FBG: GATE})
    cols = layout.columns()
    m = 50
    t = np.arange(m) * 1e-3
    rng = np.random.default_rng(0)
    proximal = 2.85 + 0.1 * rng.standard_normal((m, 6))
    tip = 0.9 * proximal
    dl1, dl2 = 5.0 + t, 34.12 * tip[:, 0] + 2.28 * (5.0 + t)
    path = tmp_path / "one.mcap"
    with open(path, "wb") as fh:
        w = SessionWriter(fh, layout, {"configuration": {"robot": "sim://robot?sensor=one"}}, 0)
        for k in range(m):
            r = np.zeros(layout.width)
            vals = {"tick": k, "t": t[k], "new": 1, "t_robot": t[k], "seq": k + 1, "commanded_lengths": [0.3] * 6,
                    "tensions": tip[k], GATE: 1, "fbg_cable": 0, "fbg_dl1_pm": dl1[k], "fbg_dl2_pm": dl2[k],
                    "fbg_force": tip[k, 0], "proximal": proximal[k], "rest": 1, "rest_ratio": 0.9}
            for name, v in vals.items():
                r[cols[name]] = v
            w.write_row(r)
        w.finish({"drops": 0})
    assert len(read_session(path).messages(TOPIC_FBG)) == m
    for cable, fbg in ((1, True), (2, False)):
        out = tmp_path / f"c{cable}.csv"
        assert main(["export", str(path), "--csv", str(out), "--cable", str(cable)]) == 0
        lines = [ln for ln in out.read_text().splitlines() if not ln.startswith("#")]
        header = lines[0].split(",")
        data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
        assert ({"fbg_dl1_pm", "fbg_dl2_pm", "fbg_force_N"} <= set(header)) == fbg
        assert "est_tip_force_N" in header and len(data) == m
        col = {h: data[:, j] for j, h in enumerate(header)}
        np.testing.assert_allclose(col["motor_force_N"], proximal[:, cable - 1])
        np.testing.assert_allclose(col["est_tip_force_N"], tip[:, cable - 1])
        if fbg:
            np.testing.assert_allclose(col["fbg_force_N"], tip[:, 0])
            np.testing.assert_allclose(col["fbg_dl2_pm"], dl2)
    capsys.readouterr()
