"""`teleop bench loop`: its JSON keys plus the period histogram, the budget verdict and the PNG, on a
short run (the budget itself needs --seconds 60: a benchmark, never asserted here)."""

import json

from teleop.apps.cli import main
from teleop.io.recording import TOPIC_TIMING, read_session

DESIGN_KEYS = {"rate_hz", "ticks", "tick_us", "lateness_us", "deadline_misses", "stages_us"}


def test_bench_loop_json_histogram_verdict_and_plot(tmp_path, capsys):
    path, png, rec = tmp_path / "loop.json", tmp_path / "loop.png", tmp_path / "loop.mcap"
    assert main(["bench", "loop", "--seconds", "0.4", "--no-realtime", "--robot-rt", "0", "--json", str(path),
                 "--plot", str(png), "--record", str(rec)]) == 0
    out = capsys.readouterr().out
    data = json.loads(path.read_text())
    assert DESIGN_KEYS <= set(data)
    assert list(data["tick_us"]) == ["p50", "p99", "max"] and list(data["lateness_us"]) == ["p50", "p99", "p999", "max"]
    h = data["period_histogram"]
    assert sum(h["counts"]) + h["overflow"] == data["ticks"] - 1
    assert set(data["period_us"]) == {"mean", "p50", "p99", "p999", "max", "min"}
    b = data["budget"]
    assert not b["conclusive"] and any("--seconds 60" in w for w in b["why_not"])
    assert b["pass"] == (b["miss_fraction"] <= 0.001)
    assert "period histogram" in out and "not conclusive: needs --seconds 60" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    session = read_session(rec)  # the statistics and the histogram are stored in the session file
    assert session.is_intact and session.metadata["session_end"]["timing"]["period_histogram"] == h
    per_second = session.messages(TOPIC_TIMING)
    assert per_second and {"mean", "p99", "p999", "max"} <= set(per_second[0]["lateness_us"])
    assert "misses" in per_second[0]
