"""`teleop bench tick`: JSON keys (docs/formats.md), bad arguments, fast tick == reference; no wall-clock assertions."""

import json

import numpy as np
import pytest

from teleop.apps.bench.tick import _trajectory, bench_tick, make_ticks
from teleop.apps.cli import main
from teleop.core.estimation.estimators import ESTIMATOR_NAMES
from teleop.core.mapping import MappingParams


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


@pytest.mark.parametrize("name", ESTIMATOR_NAMES)
def test_full_tick_equals_the_reference_through_every_branch(name):
    """LoopTick (the loop's float path) and ReferenceLoopTick (numpy/scipy/filterpy) give the same lengths,
    tensions, wrench and force on the bench trajectory, which clips at the workspace box, hits the cable speed
    limit and flips the FSR branches."""
    fast, ref = make_ticks(name)
    n, dt = 2500, 1e-3
    p_s, v_s, counts = _trajectory(n, dt, seed=3)
    worst = np.zeros(4)
    clipped = limited = 0
    branches = set()
    for k in range(n):
        L_prev = fast.L_last
        out = fast.compute(p_s[k], v_s[k], counts[k], dt)
        out_ref = ref.compute(p_s[k], v_s[k], counts[k], dt)
        worst = np.maximum(worst, [np.abs(np.asarray(a, dtype=float) - b).max() for a, b in zip(out, out_ref)])
        clipped += abs(fast.pos[0]) >= MappingParams().workspace_max[0]
        limited += np.abs(np.subtract(out[0], L_prev)).max() >= fast.follower.dmax * (1 - 1e-9)
        branches |= set(ref.branch_dir.tolist())
    assert worst[0] < 1e-15 and worst[1] < 1e-12, worst   # lengths [m], tensions [N]
    assert worst[2] < 1e-9 and worst[3] < 1e-8, worst     # wrench, force (the passivity damper divides by v^2 dt)
    assert clipped > 100 and limited > 5
    assert {-1.0, 1.0} <= branches  # loading and unloading FSR branches both used
    assert fast.renderer.state == "engaged" and not fast.renderer.fault


def test_loop_runs_the_benchmarked_parts():
    """Teleop's MAP / ESTIMATE / RENDER stages go through one LoopTick holding the loop's own estimator and
    renderer (so `teleop bench tick` times the code the loop runs)."""
    from teleop.core.estimation.tick import LoopTick
    from teleop.loop.core import Teleop
    from tests.devices._fakes import FakeRobot

    class Stylus:
        spec = type("Spec", (), {"max_force_continuous": 0.88})()

    tp = Teleop(Stylus(), FakeRobot())
    assert isinstance(tp.fast, LoopTick) and tp.fast_estimate
    assert tp.fast.estimator is tp.estimator and tp.fast.renderer is tp.renderer
