"""Replay reproduces a session bit for bit; the session / replay / export / bench loop commands end to end."""

import json
import os
import sys

import numpy as np
import pytest


from tests.devices._fakes import LinearEstimator, record_session  # noqa: E402

from teleop.apps.cli import main  # noqa: E402
from teleop.loop.replay import replay_session  # noqa: E402
from teleop.io.recording import read_session  # noqa: E402


def test_replay_reproduces_bit_exact_and_detects_differences(tmp_path):
    path = tmp_path / "s.mcap"
    tp = record_session(path, ticks=700)
    assert {e.dst for e in tp.events} >= {"ENABLED"}
    rep = replay_session(str(path), estimator=LinearEstimator())
    assert rep.reproduced and rep.ticks == 700 and rep.max_force_diff == 0.0
    s = read_session(path)
    assert np.abs(s.array("/haptic/servo_cf", "servo_cf")).max() > 0.05  # forces were actually rendered

    class Biased(LinearEstimator):
        def update(self, reading, pose, dt):
            t, f = super().update(reading, pose, dt)
            return t, f + np.array([0.0, 0.0, 1e-9, 0, 0, 0])

    rep = replay_session(str(path), estimator=Biased())
    assert not rep.reproduced and rep.force_mismatches > 0


def test_session_replay_export_commands_default_simulation(tmp_path, capsys):
    rec, csv = tmp_path / "s.mcap", tmp_path / "s.csv"
    assert main(["session", "--seconds", "1.0", "--record", str(rec)]) == 0
    s = read_session(rec)
    assert s.is_intact and len(s.messages("/loop")) > 500
    meta = s.metadata["session"]
    for key in ("configuration", "calibration", "firmware_version", "software_version"):
        assert meta[key]
    assert s.metadata["session_end"]["timing"]["ticks"] == len(s.messages("/loop"))
    assert s.messages("/loop/timing")
    assert main(["replay", str(rec)]) == 0
    assert "reproduced" in capsys.readouterr().out
    assert main(["export", str(rec), "--csv", str(csv), "--cable", "2"]) == 0
    lines = csv.read_text().splitlines()
    header = next(line for line in lines if not line.startswith("#"))
    assert header.split(",")[:2] == ["t_s", "motor_pos_mm"] and "motor_force_N" in header
    assert "bend_angle_deg" in header and len(lines) > 300  # one row per 500 Hz telemetry frame


@pytest.mark.parametrize("argv, msg", [
    (["replay", "{tmp}/nope.mcap"], "file not found"),
    (["replay", "{tmp}/bad.mcap"], "not an MCAP recording"),
    (["export", "{tmp}/bad.mcap", "--csv", "{tmp}/o.csv"], "not an MCAP recording"),
    (["export", "{tmp}/bad.mcap", "--csv", "{tmp}/o.csv", "--cable", "9"], "--cable"),
    (["session", "--record", "{tmp}/x.txt"], ".mcap"),
    (["session", "--haptic", "warp://", "--seconds", "1"], "unknown scheme"),
    (["session", "--robot", "sim://robot?pad=moon", "--seconds", "1"], "unknown pad"),
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, argv, msg):
    (tmp_path / "bad.mcap").write_bytes(b"not a recording at all")
    assert main([a.format(tmp=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    # "teleop: error:" from the command, "teleop replay: error: argument file:" from the argument check
    assert err.count("\n") == 1 and err.startswith("teleop") and ": error: " in err and msg in err
    assert not (tmp_path / "o.csv").exists()


def test_bench_loop_json_has_the_design_keys(tmp_path):
    out = tmp_path / "loop.json"
    assert main(["bench", "loop", "--seconds", "0.5", "--rate", "1000", "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert {"rate_hz", "ticks", "tick_us", "lateness_us", "deadline_misses", "stages_us"} <= set(d)
    assert set(d["tick_us"]) == {"p50", "p99", "max"} and set(d["lateness_us"]) == {"p50", "p99", "p999", "max"}
    assert set(d["stages_us"]) == {"read", "map", "robot", "estimate", "render", "write", "record"}
    assert d["ticks"] == 500 and d["recording"]["on"]
