"""`teleop bench tick`: JSON keys (DESIGN.md) and bad arguments; no wall-clock assertions."""

import json

from teleop.bench.tick import bench_tick
from teleop.cli import main


def test_bench_tick_json_keys():
    out = bench_tick(ticks=300, warmup=50)
    assert list(out) == ["ticks", "tick_us", "reference_tick_us", "speedup_p50"]
    assert list(out["tick_us"]) == ["p50", "p99", "max"]
    assert list(out["reference_tick_us"]) == ["p50", "p99", "max"]
    assert out["ticks"] == 300 and out["speedup_p50"] > 0
    assert out["tick_us"]["p50"] <= out["tick_us"]["p99"] <= out["tick_us"]["max"]


def test_cli_writes_the_json(tmp_path, capsys):
    path = tmp_path / "tick.json"
    assert main(["bench", "tick", "--ticks", "1000", "--estimator", "single", "--json", str(path)]) == 0
    data = json.loads(path.read_text())
    assert data["ticks"] == 1000 and set(data) == {"ticks", "tick_us", "reference_tick_us", "speedup_p50"}


def test_cli_bad_arguments_exit_2(capsys):
    assert main(["bench", "tick", "--ticks", "5"]) == 2
    assert main(["bench", "tick", "--estimator", "magic"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("teleop: error: --") for line in err)


def test_cpu_clock_option():
    out = bench_tick(ticks=200, warmup=20, clock="cpu")
    assert out["tick_us"]["p50"] > 0 and out["reference_tick_us"]["p50"] > 0


def test_cli_realtime_option_runs(tmp_path, capsys):
    """SCHED_FIFO when the OS allows it, else the bench still runs and says what it got."""
    assert main(["bench", "tick", "--ticks", "1000", "--realtime", "10", "--json", str(tmp_path / "t.json")]) == 0
    assert "scheduling: SCHED_" in capsys.readouterr().err
