"""`teleop bench sim`: JSON keys and the consistency of its numbers, seeded determinism of the simulated
trajectory, bad flags. No wall-clock assertions (the factors' values depend on the machine)."""

import json

import pytest

from teleop.apps.bench.sim import BUDGET_FACTOR, STAGES, CallTimer, bench_sim
from teleop.apps.cli import main

KEYS = ["seed", "pad", "rate_hz", "robot_rate_hz", "substeps", "simulated_s", "wall_s", "cpu_s", "realtime_factor",
        "realtime_factor_cpu", "budget_factor", "pass", "ticks", "readings", "physics_steps", "stages_timed",
        "pybullet_timed", "stages", "trajectory", "batch"]


def _factor_ok(factor, simulated, spent):
    return factor == pytest.approx(simulated / spent, rel=1e-3, abs=2e-3)


def test_cli_json_keys_and_consistent_values(tmp_path, capsys):
    path = tmp_path / "sim.json"
    assert main(["bench", "sim", "--seconds", "2", "--seed", "3", "--stages", "--json", str(path)]) == 0
    out = json.loads(path.read_text())
    assert list(out) == KEYS
    assert out["simulated_s"] == 2.0 and out["ticks"] == 2000 and out["readings"] == 2000
    assert out["physics_steps"] == 2000 and out["seed"] == 3 and out["budget_factor"] == BUDGET_FACTOR
    assert _factor_ok(out["realtime_factor"], out["simulated_s"], out["wall_s"])
    assert _factor_ok(out["realtime_factor_cpu"], out["simulated_s"], out["cpu_s"])
    assert out["pass"] == (out["realtime_factor"] >= BUDGET_FACTOR)
    # the stages partition the wall time
    assert list(out["stages"]) == list(STAGES)
    assert sum(s["wall_s"] for s in out["stages"].values()) == pytest.approx(out["wall_s"], abs=1e-4)
    assert sum(s["fraction"] for s in out["stages"].values()) == pytest.approx(1.0, abs=1e-3)
    assert out["stages_timed"] and out["pybullet_timed"]
    for name in ("kinematics", "pybullet_step", "physics_other", "cable_sensor", "estimate", "stylus"):
        st = out["stages"][name]
        assert st["wall_s"] > 0 and 0 < st["per_tick_us"]["p50"] <= st["per_tick_us"]["p99"]
    # the loop ran engaged and poked the pad
    tr = out["trajectory"]
    assert tr["final_state"] == "ENABLED" and tr["fault_reason"] == ""
    assert tr["contacts"] >= 1 and tr["peak_contact_force_N"] > 0.1 and tr["enabled_s"] > 1.9
    # the batched path replays the same commanded lengths: same time, same counts up to a rounding flip
    b = out["batch"]
    assert b["simulated_s"] == 2.0 and b["readings"] == 2000
    assert _factor_ok(b["realtime_factor"], b["simulated_s"], b["wall_s"])
    assert _factor_ok(b["realtime_factor_cpu"], b["simulated_s"], b["cpu_s"])
    assert sum(s["wall_s"] for s in b["stages"].values()) == pytest.approx(b["wall_s"], abs=1e-5)
    assert list(b["stages"]) == ["pybullet_step", "physics_other", "arrays"]
    assert b["stages"]["pybullet_step"]["wall_s"] > 0
    assert b["counts_max_abs_diff_vs_loop"] <= 1
    text = capsys.readouterr().out
    assert "loop" in text and "batch" in text and ("PASS" in text or "FAIL" in text)


def test_same_seed_same_trajectory_other_seed_differs():
    a = bench_sim(1.0, seed=5, batch=False)
    b = bench_sim(1.0, seed=5, batch=False)
    c = bench_sim(1.0, seed=6, batch=False)
    assert a["trajectory"] == b["trajectory"]
    assert a["trajectory"]["sha256"] != c["trajectory"]["sha256"]


def test_substeps_and_untimed_robot():
    out = bench_sim(0.5, seed=0, substeps=2, batch=False, stages=False)
    assert out["simulated_s"] == 0.5 and out["ticks"] == 500
    assert out["readings"] == 250 and out["physics_steps"] == 500 and out["robot_rate_hz"] == 500.0
    st = out["stages"]
    assert not out["stages_timed"]
    for name in ("kinematics", "pybullet_step", "physics_other", "cable_sensor"):
        assert st[name]["wall_s"] == 0
    assert st["robot_io"]["wall_s"] > 0  # the whole robot stage
    assert sum(s["wall_s"] for s in st.values()) == pytest.approx(out["wall_s"], abs=1e-4)


def test_meter_counts_nested_calls_once():
    m = CallTimer()
    inner = m.wrap(lambda: 1)
    outer = m.wrap(lambda: inner() + 1)
    assert outer() == 2 and inner() == 1
    assert m.calls == 2 and m.ns > 0


@pytest.mark.parametrize("argv, flag", [
    (["--seconds", "0"], "--seconds"), (["--seconds", "-1"], "--seconds"), (["--seconds", "nan"], "--seconds"),
    (["--seconds", "0.0005"], "--seconds"), (["--seconds", "0.003", "--substeps", "2"], "--seconds"),
    (["--substeps", "0"], "--substeps"), (["--pad", "moon"], "--pad"), (["--depth-mm", "0"], "--depth-mm"),
    (["--period-s", "-2"], "--period-s"), (["--seed", "-1"], "--seed"), (["--seconds", "x"], "--seconds"),
])
def test_bad_flags_exit_2(argv, flag, tmp_path, capsys):
    """Our own checks return 2 through teleop.apps.cli (InputError); argparse's type errors exit 2 (SystemExit)."""
    path = tmp_path / "sim.json"
    try:
        code = main(["bench", "sim", *argv, "--json", str(path)])
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "error" in err[0] and flag in err[0]
    assert not path.exists()


def test_vs_matched_reports_the_ratio_of_the_two_loop_factors(tmp_path, capsys):
    path = tmp_path / "sim.json"
    assert main(["bench", "sim", "--seconds", "0.3", "--plant", "distributed", "--vs-matched", "--no-batch",
                 "--json", str(path)]) == 0
    out = json.loads(path.read_text())
    v = out["vs_matched"]
    assert out["plant"] == "distributed" and list(v) == ["realtime_factor", "realtime_factor_cpu", "wall_s", "cpu_s",
                                                         "ratio", "ratio_cpu"]
    assert _factor_ok(v["realtime_factor"], out["simulated_s"], v["wall_s"])
    assert v["ratio"] == pytest.approx(v["wall_s"] / out["wall_s"], rel=1e-3)
    assert v["ratio_cpu"] == pytest.approx(v["cpu_s"] / out["cpu_s"], rel=1e-3)
    assert "matched plant's loop right after" in capsys.readouterr().out
    assert "vs_matched" not in bench_sim(0.1, batch=False, stages=False, vs_matched=True)  # nothing to compare


def test_vs_matched_needs_another_plant(tmp_path, capsys):
    path = tmp_path / "sim.json"
    assert main(["bench", "sim", "--seconds", "0.1", "--vs-matched", "--json", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--vs-matched" in err[0] and not path.exists()
