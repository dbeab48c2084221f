"""Palpation on the rich plant (`--plant rich`) and the seed's turn compensation off the z axis: the turn
detectors ignore the forward kinematics' round-off, so `double` stays on `single` along x and y."""

import dataclasses
import json

import numpy as np
import pytest

from teleop.apps.cli import main
from teleop.core.estimation.turn import AxisTurnFit, TurnCompensation, TurnCompensator
from teleop.apps.protocols.palpation import ESTIMATORS, PalpationParams, run_test

QUICK = dataclasses.replace(PalpationParams(), fit_dynamic=False, speed=2e-3, fit_cycles=2, fit_travel=0.003)


def _corrections(deadband):
    poly = tuple((1.0, 0.0, 0.0) for _ in range(6))       # a unit error right after any turn along x
    comp = TurnCompensator(TurnCompensation((AxisTurnFit(0, 0.5, poly, poly, deadband=deadband),)))
    out = []
    for k in range(200):                                  # a z move; x holds 0 up to round-off
        out.append(comp.update((1e-17 * (-1) ** k, 0.0, 0.02 + 5e-6 * k), 0.01))
    return np.array(out)


def test_turn_detector_ignores_round_off_on_an_axis_that_does_not_move():
    assert np.abs(_corrections(0.0)).max() == pytest.approx(1.0)    # every wiggle a turn: the seed's misfire
    assert np.abs(_corrections(PalpationParams().turn_deadband)).max() == 0.0


def test_double_stays_on_single_in_x_and_y():
    res = run_test("xy", "uniform", seed=2, params=QUICK, limit=4)
    assert {p["direction"] for p in res.pokes} == {"+x", "-x"}
    for p in res.pokes:   # before the dead band, double read 0.75 N off single on every x poke
        assert abs(p["double_N"] - p["single_N"]) < 0.05


def test_rich_plant_run_is_deterministic_and_reported(tmp_path, capsys):
    a = run_test("stiffness", "uniform", seed=5, params=QUICK, limit=1, plant="rich")
    b = run_test("stiffness", "uniform", seed=5, params=QUICK, limit=1, plant="rich")
    m = run_test("stiffness", "uniform", seed=5, params=QUICK, limit=1)
    assert json.dumps(a.to_json()) == json.dumps(b.to_json())
    doc = a.to_json()
    assert doc["plant"]["name"] == "rich" and len(doc["plant"]["cables"]) == 6
    assert m.to_json()["plant"] == {"name": "matched"}
    (pa,), (pm,) = a.pokes, m.pokes
    assert pa["ground_truth_N"] == pytest.approx(pm["ground_truth_N"], abs=0.05)   # same pad, same load
    assert abs(pa["non_compensated_N"] - pm["non_compensated_N"]) > 1e-3           # a different robot
    assert set(a.summary) == set(ESTIMATORS) and "plant: rich" in a.table()


def test_cli_plant_option(capsys):
    assert main(["palpate", "--test", "z", "--plant", "fancy"]) == 2
    assert "--plant" in capsys.readouterr().err


def test_turn_fit_level_before_the_next_turn_ignores_a_mid_stroke_transition():
    from teleop.core.estimation.turn import fit_turn_compensation

    dt, half = 0.01, 20.0                                   # 20 s half cycles along y, four of them
    t = np.arange(0.0, 4 * half, dt)
    s = (t % half) / half
    y = np.where((t // half) % 2 == 0, s, 1.0 - s) * 0.01
    poses = np.zeros((t.size, 6))
    poses[:, 1] = y
    tau = t % half
    w = np.zeros((t.size, 6))
    w[:, 1] = np.exp(-tau / 0.3) * np.where((t // half) % 2 == 0, 1.0, -1.0)   # the jump after each turn
    w[:, 0] = np.where((s > 0.5) & (s < 0.8), -0.4, 0.0)                       # a cable reversing mid-stroke
    old = fit_turn_compensation(t, poses, w, axis=1, deadband=1e-9)
    new = fit_turn_compensation(t, poses, w, axis=1, deadband=1e-9, level_tail=0.1)
    assert old.duration > 0.9 * half                        # never settles: the plateau went into the level
    assert new.duration < 2.0                               # the jump's own settling (0.3 s time constant)
    assert new.correction(1, 0.0)[1] == pytest.approx(1.0, abs=0.05)
    with pytest.raises(Exception, match="level_tail"):
        fit_turn_compensation(t, poses, w, axis=1, level_tail=0.0)


def test_no_load_run_reports_every_estimator_only_when_asked():
    """Robot-level seed 000 Fig 13: the no-load z run's wrench per estimator (truth 0), in extra["no_load"]."""
    a = run_test("stiffness", "uniform", seed=5, params=QUICK, limit=1, no_load=True)
    b = run_test("stiffness", "uniform", seed=5, params=QUICK, limit=1)
    assert "no_load" not in b.extra and a.pokes == b.pokes          # asking for it changes nothing else
    (session,) = a.extra["no_load"].values()
    z = session["z"]
    assert z["turns"] == 2 * QUICK.fit_cycles - 1
    for n in ESTIMATORS:
        e = z[n]
        assert e["peak_to_peak_N"] > 0 and e["rmse_N"] <= e["max_abs_N"]
    # the matched plant's single compensation is steadier off the turns than none (the capstan is its model)
    assert z["single"]["rmse_off_turns_N"] < z["non_compensated"]["rmse_off_turns_N"]
