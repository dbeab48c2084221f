"""Palpation protocols: trajectories, summaries, a short simulated run, determinism by seed, the CLI."""

import dataclasses
import json

import numpy as np
import pytest

from teleop.apps.cli import main
from teleop.apps.protocols.palpation import (ESTIMATORS, PalpationParams, PlannedPoke, line, load_depth, plan_pokes,
                                             reach_scale, run_test, sessions_for, stiffness_extras, stroke, summarise,
                                             load_response, SEED_TABLE1)

# short runs: 2 mm/s pokes and a 3 mm turn-compensation run (the CLI defaults are the seed's 0.5 mm/s)
QUICK = dataclasses.replace(PalpationParams(), fit_dynamic=False, speed=2e-3, fit_cycles=2, fit_travel=0.003)


def test_line_and_uniform_stroke_speed():
    pts = line([0, 0, 0], [0, 0, 0.001], 0.5e-3, 0.01)
    assert len(pts) == 200 and np.allclose(pts[-1], [0, 0, 0.001])
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert np.allclose(steps, 0.5e-3 * 0.01)


def test_variable_stroke_reverses_and_arrives():
    rng = np.random.default_rng(0)
    pts = stroke([0, 0, 0], [0, 0, 0.006], "variable", PalpationParams(), 0.01, rng)
    dz = np.diff(pts[:, 2])
    assert np.isclose(pts[-1, 2], 0.006) and (dz < 0).any() and (dz > 0).any()
    speeds = np.abs(dz[dz != 0]) / 0.01
    assert speeds.max() > 2 * speeds.min()  # not uniform
    assert pts[:, 2].max() <= 0.006 + 1e-12  # never deeper than commanded


def test_plan_deepest_points_are_at_depth():
    pokes = [PlannedPoke("a", (0.001, 0.0)), PlannedPoke("b", (-0.002, 0.001))]
    p = PalpationParams()
    plan = plan_pokes(pokes, 0.0235, [0, 0, 0.02], p, 0.004, "uniform", 0.01, np.random.default_rng(0))
    for k, pk in zip(plan.deepest, pokes):
        assert np.allclose(plan.tips[k], [pk.xy[0], pk.xy[1], 0.0275])
    assert reach_scale(pokes, 0.006) == 1.0 and reach_scale([PlannedPoke("c", (0.012, 0.0))], 0.006) == 0.5


def test_stiffness_pokes_go_to_table1_loads():
    from scenes.pads import three_region_pad

    pad = three_region_pad()
    k_black = pad.stiffness_at(np.array(pad.points["black"]), 0.0015)
    assert load_depth(pad, pad.points["black"], 1.0, None, 0.0015) == pytest.approx(1.0 / k_black)
    # the robot's stiffness in series makes the same load need a deeper command
    assert load_depth(pad, pad.points["black"], 1.0, 1e4, 0.0015) == pytest.approx(1.0 / k_black + 1.0 / 1e4)
    (s,) = sessions_for("stiffness", PalpationParams(), tip_stiffness=1e4)
    depth = {pk.label: pk.depth for pk in s.pokes}
    assert depth["red"] < depth["yellow"] < depth["black"]  # stiffer region: shallower poke for its load
    plan = plan_pokes(s.pokes[:1], 0.0235, [0, 0, 0.02], PalpationParams(), s.depth, "uniform", 0.01,
                      np.random.default_rng(0))
    assert plan.tips[plan.deepest[0], 2] == pytest.approx(0.0235 + depth["black"])


def test_summary_and_ranking_logic():
    rows = []
    for lab, gt, nc in (("black", 1.0, 4.8), ("red", 2.2, 4.7), ("yellow", 1.4, 4.5)):
        for r in range(2):
            rows.append({"label": lab, "ground_truth_N": gt, "non_compensated_N": nc + 0.1 * r,
                         "single_N": gt + 0.05, "double_N": gt - 0.02, "dynamic_N": gt + 0.01})
    s = summarise(rows)
    assert s["double"]["mean_abs_error_N"] == pytest.approx(0.02)
    assert s["non_compensated"]["rmse_N"] > 3
    ex = stiffness_extras(rows)
    assert ex["truth_ranking"] == ["red", "yellow", "black"]
    assert not ex["ranks_correctly"]["non_compensated"] and ex["ranks_correctly"]["double"]
    assert ex["within_0_3_N"]["double"] and not ex["within_0_3_N"]["non_compensated"]
    assert ex["load_response"]["double"] == {"offset_N": pytest.approx(-0.02), "gain": pytest.approx(1.0)}


def test_load_response_line_and_the_seeds_flat_non_compensated_values():
    r = load_response([1.0, 2.0, 3.0], [2.5, 4.0, 5.5])
    assert r["offset_N"] == pytest.approx(1.0) and r["gain"] == pytest.approx(1.5)
    seed = {n: load_response(SEED_TABLE1["ground_truth"], SEED_TABLE1[n]) for n in ("non_compensated", "double")}
    assert abs(seed["non_compensated"]["gain"]) < 0.2  # flat: cannot rank (Table 1)
    assert seed["double"]["gain"] == pytest.approx(1.2, abs=0.1)


def test_short_stiffness_run_is_physical_and_deterministic():
    a = run_test("stiffness", "uniform", seed=7, params=QUICK, limit=1)
    b = run_test("stiffness", "uniform", seed=7, params=QUICK, limit=1)
    assert json.dumps(a.to_json()) == json.dumps(b.to_json())
    (poke,) = a.pokes
    assert poke["ground_truth_N"] == pytest.approx(1.01, abs=0.1)  # Ecoflex 00-10 region at Table 1's load
    assert poke["non_compensated_N"] > poke["ground_truth_N"] + 0.5  # sheath friction reads high
    assert abs(poke["single_N"] - poke["ground_truth_N"]) < 0.3
    assert set(a.summary) == set(ESTIMATORS)
    assert a.simulated_s > 10 and "attribution" in a.to_json()


def test_cli_writes_json_and_plot(tmp_path, capsys, monkeypatch):
    import teleop.apps.protocols.palpation as palpation

    monkeypatch.setattr(palpation, "PalpationParams", lambda: dataclasses.replace(QUICK, fit_dynamic=True))
    out, png = tmp_path / "r.json", tmp_path / "r.png"
    rc = main(["palpate", "--test", "stiffness", "--limit", "1", "--seed", "3", "--json", str(out), "--plot", str(png)])
    assert rc == 0 and png.stat().st_size > 1000
    again = tmp_path / "again.json"
    assert main(["palpate", "--test", "stiffness", "--limit", "1", "--seed", "3", "--json", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()  # same seed, same bytes
    doc = json.loads(out.read_text())
    assert doc["test"] == "stiffness" and doc["speed_profile"] == "uniform" and len(doc["pokes"]) == 1
    for n in ESTIMATORS:
        assert {"mean_abs_error_N", "rmse_N"} <= set(doc["summary"][n])
    cal = doc["calibration"]["stiffness3"]
    assert cal["dynamic"]["dahl_Fc"] > 0 and cal["turn_duration_s"]["z"] > 0
    assert "MAE" in capsys.readouterr().out


def test_cli_rejects_bad_arguments(capsys):
    assert main(["palpate", "--test", "z", "--limit", "0"]) == 2
    assert "teleop: error:" in capsys.readouterr().err
