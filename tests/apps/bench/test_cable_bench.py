"""teleop bench cable: the seed 000 single-cable experiments on the simulated bench (physics checks, not
the seed's numbers: those are printed beside ours, not asserted)."""

import json
import math

import numpy as np
import pytest

from scenes.tendon_sheath import TendonSheathParams
from teleop.apps.bench import cable
from teleop.apps.cli import main


@pytest.fixture(scope="module")
def fig9():
    return cable.fig9(seed=0)


def test_fig9_capstan_levels_and_proximal_above_distal(fig9):
    c0 = fig9["cases"]["0"]
    mt = cable.mu_bd() * cable.THETA0
    # the cable's tension at B is the hanging weight times exp(+-mu theta) (seed 000 eq 3)
    assert c0["tension_B_N"][0] == pytest.approx(1.96 * math.exp(mt), rel=0.01)
    assert c0["tension_B_N"][1] == pytest.approx(1.96 * math.exp(-mt), rel=0.01)
    changes = [fig9["cases"][d]["tension_B_change_N"] for d in ("30", "60", "90")]
    assert changes == sorted(changes)                   # more bend, more swing at the same pretension
    for c in fig9["cases"].values():                    # the motor side always swings more (seed Fig 9)
        assert c["proximal_change_N"] > c["tension_B_change_N"]
    # where the swing exceeds the FSR's own branch gap, the FSR reports the tension at B
    c30 = fig9["cases"]["30"]
    assert np.allclose(c30["distal_N"], c30["tension_B_N"], rtol=0.03)


def test_fig11_flat_transitions_beat_the_direction_switch_and_ab_bend_is_invisible_at_b():
    res = cable.fig11(seed=1)
    for m in ("b", "c"):
        a, b = res["cases"][f"{m}_360"], res["cases"][f"{m}_180"]
        assert a["single"] == b["single"] and a["fsr_raw"] == b["fsr_raw"]
        assert a["proximal_range_N"] != b["proximal_range_N"]
        assert a["flat_transitions"]["rmse_N"] < 0.5 * a["single"]["rmse_N"]
        assert a["single"]["rmse_away_from_turns_N"] < 0.5 * a["fsr_raw"]["rmse_away_from_turns_N"]


def test_fig13_double_compensation_lowers_the_turn_error():
    res = cable.fig13(seed=2, pretensions_N=(4.9,), speed_mm_s=2.0)
    r = res["pretensions"]["4.9"]["cases"]
    assert r["single"]["rmse_away_from_turns_N"] < 0.5 * r["non_compensated"]["rmse_away_from_turns_N"]
    assert r["double"]["rmse_N"] < r["single"]["rmse_N"]
    assert r["double"]["peak_to_peak_moving_N"] < r["single"]["peak_to_peak_moving_N"]


def test_cli_json_and_plot(tmp_path, capsys):
    out, png = tmp_path / "f.json", tmp_path / "f.png"
    assert main(["bench", "cable", "--experiment", "fig11", "--json", str(out), "--plot", str(png)]) == 0
    text = capsys.readouterr().out
    assert "seed (in words)" in text and "flat_transitions" in text
    doc = json.loads(out.read_text())
    assert doc["experiment"] == "fig11" and "series" not in doc and set(doc["cases"]) == {"b_360", "b_180", "c_360", "c_180"}
    assert png.stat().st_size > 20_000
    assert main(["bench", "cable", "--experiment", "fig12"]) == 2
    assert "--experiment" in capsys.readouterr().err


def test_distributed_fsr_alone_passes_a_swing_smaller_than_the_calibration_gap():
    # the distributed cable's FSR is the sensor alone (scenes.fsr_sensor): at 0 deg the tension at B swings
    # less than the calibration's branch gap (0.72 N at 2 N), which the matched bench's FsrBranchLag holds
    res = cable.fig9(seed=0, cable=TendonSheathParams())
    c0 = res["cases"]["0"]
    assert c0["tension_B_change_N"] < cable.FsrBranchLag(cable.default_fsr_calibration(), 1).gap(2.0)
    assert c0["distal_change_N"] > 0.5 * c0["tension_B_change_N"]
    # rising, the reading is on the loading branch, which the converter inverts: the FSR reads the tension at B
    assert c0["distal_N"][0] == pytest.approx(c0["tension_B_N"][0], rel=0.03)
    # falling, the converter's unloading branch takes off the calibration's gap, more than the sensor's own
    assert c0["distal_N"][1] < c0["tension_B_N"][1]


def test_the_platform_calibration_reads_the_scaffolds_friction_into_the_fsr(tmp_path, capsys):
    # converted with the calibration fitted on the cable's own platform (scenes.fsr_lab), the FSR rising reads
    # the weight the platform would hang for that reading: the tension at B times e^(mu_c theta0)
    p = TendonSheathParams()
    out = tmp_path / "p.json"
    assert main(["bench", "cable", "--experiment", "fig9", "--plant", "distributed", "--fsr-calibration", "platform",
                 "--json", str(out)]) == 0
    assert "platform calibration" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    c0 = doc["cases"]["0"]
    assert doc["fsr_calibration"] == "platform"
    assert c0["distal_N"][0] == pytest.approx(c0["tension_B_N"][0] * math.exp(p.mu_c * p.theta0), rel=0.03)
    builtin = cable.fig9(seed=0, cable=p)["cases"]["0"]
    assert c0["distal_change_N"] > builtin["distal_change_N"] + 0.1        # the friction read in, by branch
    assert main(["bench", "cable", "--experiment", "fig9", "--fsr-calibration", "platform"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--fsr-calibration platform" in err
