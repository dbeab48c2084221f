"""`teleop bench diagnose`: the per-channel comparison with the PySINDy peer (every fitted channel, the ratio
and the channels where physics is worse), the capstan-ratio bands, the literature generator's reproducible
cases, and the distributed suite's report."""

import json

import pytest

from teleop.apps.bench.diagnose import _band, grouped, peer_summary
from teleop.apps.bench.diagnose_distributed import distributed_plan, sensor_effects, simulate_case
from teleop.apps.cli import main
from teleop.diagnosis.generator import Case, GenConfig, make_case
from teleop.diagnosis.scoring import peer_rows, score, true_noise

DOC = {"peer": {
    "tip_pos": {"arx_rmse": 2e-5, "baseline_rmse": 3e-5, "model_rmse": 1e-5, "sindy_static_rmse": 2e-5,
                "sindy_free_run_rmse": None, "sindy_rmse": 2e-5},
    "motor_force": {"arx_rmse": 0.2, "baseline_rmse": 0.3, "model_rmse": 0.12, "sindy_static_rmse": 0.15,
                    "sindy_free_run_rmse": 0.1, "sindy_rmse": 0.1}}}


def test_peer_rows_cover_every_channel_with_ratio_and_noise():
    rows = {r["channel"]: r for r in peer_rows(DOC, {"motor_force": 0.05})}
    assert set(rows) == {"tip_pos", "motor_force"}
    assert rows["tip_pos"]["ratio"] == pytest.approx(0.5) and not rows["tip_pos"]["worse"]
    assert rows["motor_force"]["ratio"] == pytest.approx(1.2) and rows["motor_force"]["worse"]
    assert rows["motor_force"]["model_over_noise"] == pytest.approx(2.4)
    assert "model_over_noise" not in rows["tip_pos"]
    # both exact to round-off: a tie, whatever the ratio
    exact = {"peer": {"tip_pos": {"arx_rmse": 1e-6, "model_rmse": 9e-18, "sindy_static_rmse": 7e-18,
                                  "sindy_free_run_rmse": None, "sindy_rmse": 7e-18}}}
    assert peer_rows(exact)[0]["ratio"] > 1.0 and not peer_rows(exact)[0]["worse"]
    # without the peer: no ratio, never "worse"
    plain = peer_rows({"peer": {"tip_pos": {"arx_rmse": 1.0, "model_rmse": 2.0}}})
    assert plain[0]["ratio"] is None and plain[0]["worse"] is False


def test_peer_summary_lists_the_channels_where_physics_is_worse():
    items = [("case 0", p) for p in peer_rows(DOC)] + [("case 1", p) for p in peer_rows(DOC)]
    s = peer_summary(items)
    assert s["model_le_sindy"] == "2/4"
    assert [(w["case"], w["channel"]) for w in s["worse"]] == [("case 0", "motor_force"), ("case 1", "motor_force")]
    assert s["by_channel"]["motor_force"]["worse"] == 2 and s["by_channel"]["tip_pos"]["worse"] == 0
    assert s["by_channel"]["motor_force"]["ratio_max"] == pytest.approx(1.2)


def test_capstan_bands_and_groups():
    assert [_band(r) for r in (1.0, 1.49, 1.5, 3.0, 4.9, None)] == ["1.0-1.5", "1.0-1.5", "1.5-2.5", "2.5-4.0",
                                                                   "4.0+", "n/a"]
    rows = [{"truth": "none", "correct": True, "capstan_ratio": 1.2},
            {"truth": "backlash", "correct": False, "params_ok": False, "improved_2x": True, "improvement": 3.0,
             "capstan_ratio": 3.0}]
    g = grouped(rows, lambda r: _band(r["capstan_ratio"]))
    assert g["1.0-1.5"]["none_rate"] == 1.0 and g["2.5-4.0"]["named_first_rate"] == 0.0


def test_literature_cases_are_reproducible_and_vary_their_setup():
    cfg = GenConfig(None, 3.0, 1.0, "literature")
    a, b = make_case(3, "backlash", "rig", 5, cfg), make_case(3, "backlash", "rig", 5, cfg)
    assert a.csv == b.csv and a.columns == b.columns
    cases = [make_case(i, "coulomb_friction", "rig", 5, cfg) for i in range(6)]
    assert len({c.rig["fs_hz"] for c in cases}) == 6
    assert len({c.load for c in cases}) == 2 or len({c.columns for c in cases}) > 1
    noise = true_noise(a.rig)
    assert set(noise) == {"motor_force", "tip_force", "motor_pos", "tip_pos"} and min(noise.values()) > 0


def test_distributed_case_is_reproducible_and_records_its_noise():
    plan = distributed_plan(3)
    assert [c["load"] for c in plan] == ["spring", "force", "spring"]
    assert plan[2]["effect"] == sensor_effects()[0]
    a, b = simulate_case(plan[2], 4, duration_s=2.0), simulate_case(plan[2], 4, duration_s=2.0)
    assert a["csv"] == b["csv"]
    assert set(a["truth"]) == {plan[2]["effect"]}
    header = [line for line in a["csv"].splitlines() if line.startswith("t_s")][0].split(",")
    assert {"motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "temperature_C"} <= set(header)
    assert a["setup"]["dead_zone_range_m"][0] <= a["setup"]["dead_zone_range_m"][1]   # grows with the tension
    assert {"motor_force", "tip_force", "motor_pos", "tip_pos"} <= set(a["noise"])


def test_distributed_suite_reports_per_channel(tmp_path):
    out = tmp_path / "d.json"
    assert main(["bench", "diagnose", "--suite", "distributed", "--cases", "1", "--seconds", "5", "--seed", "3",
                 "--rate", "250", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    row = doc["distributed_rows"][0]
    assert row["source"] == "distributed" and row["fs_hz"] == 250.0
    assert {p["channel"] for p in row["peer"]} >= {"motor_force"}
    assert all(p["model_over_noise"] > 0 for p in row["peer"])
    assert doc["distributed"]["cases"] == 1 and "motor_force" in doc["distributed"]["expected"]


def test_map_without_recordings_is_refused(capsys):
    assert main(["bench", "diagnose", "--map", "mrdlab"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--map" in err[0]


def test_a_missing_recording_is_refused_before_any_work(tmp_path, capsys):
    assert main(["bench", "diagnose", "--recordings", str(tmp_path / "absent.csv"), "--json",
                 str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "absent.csv" in err[0]
    assert not (tmp_path / "r.json").exists()


def test_score_takes_the_channel_the_effect_was_found_on():
    """A play under a spring acts on the tip force, but shows on the tip position where that is recorded;
    a channel the diagnosis does not fit scores no improvement (never a KeyError)."""
    case = Case(0, "backlash", "tip_force", {"width": 1e-3}, "rig", "sine", "")
    found = {"findings": [{"effect": "backlash", "channel": "tip_pos", "params": {"width": {"value": 1.1e-3}},
                           "rmse_after": 1e-5, "alternatives": []}], "unexplained": [],
             "baseline": {"rmse": {"tip_pos": 4e-5}}, "channels": {"tip_pos": {"rmse_model": 1e-5}}}
    row = score(case, found)
    assert row["correct"] and row["improvement"] == pytest.approx(4.0) and row["params_ok"]
    none = {"findings": [], "unexplained": [], "baseline": {"rmse": {"tip_pos": 4e-5}},
            "channels": {"tip_pos": {"rmse_model": 4e-5}}}
    row = score(case, none)
    assert not row["correct"] and row["improvement"] == 1.0 and not row["improved_2x"]
