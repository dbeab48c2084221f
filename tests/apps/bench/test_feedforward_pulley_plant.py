"""`teleop bench feedforward --plant pulley`: seed 002's model-based compensation against the plain backlash
inverse on one cable over the pulley chain with bending rigidity (scenes.pulley_transmission), both
calibrated on one run of that cable."""

from __future__ import annotations

import json

from scenes.pulley_transmission import PulleyTransmissionParams
from teleop.apps.bench.feedforward import PULLEY_CAL_LOAD_N, PULLEY_TEST_LOADS_N, bench_single_cable, \
    calibrate_pulley_cable, single_cable_figure
from teleop.apps.cli import main
from tests.apps.test_figures import check_figure


def test_the_compensator_is_fitted_on_a_run_not_handed_the_plant():
    plant = PulleyTransmissionParams()
    cal = calibrate_pulley_cable(plant)
    assert cal["chain"].EI == 0.0                          # its model has no bending rigidity
    assert cal["w"] > 0 and cal["F_pull_N"] > PULLEY_CAL_LOAD_N > cal["F_rel_N"] > 0
    # the plant's bending losses show in the fit: a stiffer bending cable reads as more friction
    assert calibrate_pulley_cable(PulleyTransmissionParams(EI=2 * plant.EI))["mu"] > cal["mu"]


def test_on_the_pulley_plant_it_beats_the_plain_inverse_away_from_the_calibration_load():
    out, traces = bench_single_cable(plant="pulley")
    assert out["plant"] == "pulley" and out["loads_N"] == list(PULLEY_TEST_LOADS_N)
    r = out["tip_error_rms_mm"]
    for i, load in enumerate(PULLEY_TEST_LOADS_N):
        assert r["pulley"][i] < r["none"][i] and r["plain"][i] < r["none"][i]
        if load != PULLEY_CAL_LOAD_N:
            assert r["pulley"][i] < r["plain"][i]
    check_figure(single_cable_figure(out, traces), "plant pulley", "bending rigidity")


def test_command_writes_json_and_figure(tmp_path):
    js, png = tmp_path / "f.json", tmp_path / "f.png"
    assert main(["bench", "feedforward", "--plant", "pulley", "--json", str(js), "--plot", str(png)]) == 0
    out = json.loads(js.read_text())
    assert out["mode"] == "single_cable" and out["plant"] == "pulley" and png.stat().st_size > 0


def test_cable_params_take_the_pulley_table_and_bad_input_is_one_line(tmp_path, capsys):
    toml, js = tmp_path / "p.toml", tmp_path / "f.json"
    toml.write_text("[pulley_transmission]\nEI_N_m2 = 0.0\nmu = 0.05\n")
    assert main(["bench", "feedforward", "--plant", "pulley", "--cable-params", str(toml), "--json", str(js)]) == 0
    out = json.loads(js.read_text())
    assert out["calibration"]["plant_EI_N_m2"] == 0.0
    default, _ = bench_single_cable(plant="pulley")
    assert out["calibration"]["lost_motion_mm"] < default["calibration"]["lost_motion_mm"]
    capsys.readouterr()
    toml.write_text("[pulley_transmission]\nEI = 1e-6\n")
    js2 = tmp_path / "g.json"
    for argv in (["--plant", "pulley", "--cable-params", str(toml)], ["--cable-params", str(toml)]):
        assert main(["bench", "feedforward", *argv, "--json", str(js2)]) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1
        assert not js2.exists()
