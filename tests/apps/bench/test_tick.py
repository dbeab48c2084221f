"""`teleop bench tick`: JSON keys (docs/formats.md), bad arguments, the bench's tick is the loop's and equals the
reference; no wall-clock assertions."""

import json
from dataclasses import replace

import numpy as np
import pytest

from devices.simulated import OperatorParams, Script, SimulatedStylus
from teleop.apps.bench.tick import _trajectory, bench_tick, make_ticks
from teleop.apps.cli import main
from teleop.core.estimation.estimators import ESTIMATOR_NAMES
from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.tick import LoopTick
from teleop.core.mapping import MappingParams
from teleop.core.rendering import Renderer
from teleop.loop import LoopParams, State, Teleop
from tests.devices._fakes import FakeRobot


def test_bench_tick_json_keys():
    out = bench_tick(ticks=300, warmup=50)
    assert list(out) == ["ticks", "tick_us", "reference_tick_us", "speedup_p50"]
    assert list(out["tick_us"]) == ["p50", "p99", "max"]
    assert list(out["reference_tick_us"]) == ["p50", "p99", "max"]
    assert out["ticks"] == 300
    assert out["speedup_p50"] == round(out["reference_tick_us"]["p50"] / out["tick_us"]["p50"], 3)
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


class DyadicRobot(FakeRobot):
    """The fake robot with frame times k / 1024 s: the loop's estimate period is then exactly its tick."""

    def read(self):
        r = super().read()
        return replace(r, t=r.seq / 1024.0)


def test_the_bench_tick_is_the_loop_tick():
    """The loop (Teleop, robot every tick) and the bench's LoopTick.compute, fed the loop's own stylus samples and
    robot readings, give the same commanded lengths, tensions, wrench and stylus force, bit for bit, through
    the contact of a poke; before the loop enables, the twin runs the stages the loop runs then."""
    dt = 1.0 / 1024.0
    params = LoopParams(rate_hz=1024.0)
    clock = type("Clock", (), {"t": 0.0, "__call__": lambda self: self.t})()
    stylus = SimulatedStylus(Script(kind="pokes", axis=(0.0, 0.0, -1.0), amplitude=0.016, period=1.0, duty=0.6),
                             OperatorParams(tremor=0.0), clock=clock)
    robot = DyadicRobot()
    stylus.open()
    robot.open()
    tp = Teleop(stylus, robot, params)
    assert isinstance(tp.fast, LoopTick) and tp.fast_estimate
    assert tp.fast.estimator is tp.estimator and tp.fast.renderer is tp.renderer
    twin = LoopTick(tp.geom, params.mapping, ReadingEstimator(tp.geom, "dynamic", kalman=KalmanNoise.for_loop(params)),
                    Renderer(tp.renderer.params), cmd_dt=dt)
    calls = {"map": 0, "estimate": 0, "render": 0}
    for stage in calls:  # count the loop's calls of the three stages
        def counted(*a, _f=getattr(tp.fast, stage), _s=stage):
            calls[_s] += 1
            return _f(*a)
        setattr(tp.fast, stage, counted)
    tp.start(0.0)
    enabled, pushed = 0, 0.0
    home = np.array(params.mapping.home, dtype=float)
    for k in range(2500):
        clock.t = k * dt
        was = tp.state
        x = tp.tick(k * dt)
        p, v, r = x.sample.measured_cp, x.sample.measured_cv, x.reading
        if tp.state == State.ENABLED:
            if was != State.ENABLED:  # the loop enabled its renderer and anchored at this tick's sample
                twin.renderer.enable()
                twin.engage(p, L_robot=r.commanded_lengths)
            out = twin.compute(p, v, r.fsr_counts, dt)
            loop = (x.L_cmd, tp.tensions, tp.wrench, x.F)
            assert all(np.array_equal(a, b) for a, b in zip(out, loop)), (k, out, loop)
            enabled += 1
            pushed = max(pushed, float(np.abs(x.F).max()))
        else:
            t, w = twin.estimate(r.fsr_counts, home, dt)
            F = twin.render(*w[:3].tolist(), dt, *v.tolist())[0]
            assert np.array_equal(t, tp.tensions) and np.array_equal(w, tp.wrench) and np.array_equal(F, x.F)
    assert enabled > 2000 and not tp.fault_reason and pushed > 0.1  # the pokes met the pad
    assert calls == {"map": enabled, "estimate": 2500, "render": 2500}
