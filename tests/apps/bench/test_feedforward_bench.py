"""`teleop bench feedforward`: the three closed-loop sessions, their JSON, determinism and bad input."""

import json

import pytest

from teleop.apps.cli import main


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    d = tmp_path_factory.mktemp("ff")
    js, png = d / "ff.json", d / "ff.png"
    rc = main(["bench", "feedforward", "--seconds", "3", "--settle-s", "0.5", "--seed", "4", "--json", str(js),
               "--plot", str(png)])
    assert rc == 0
    return json.loads(js.read_text()), png, d


def test_the_feedforward_cuts_the_tip_error_at_least_twice_within_the_speed_limit(result):
    out, png, _ = result
    s = out["sessions"]
    assert set(s) == {"plain", "compensated", "no_play"}
    assert all(v["final_state"] == "ENABLED" and v["readings"] > 1000 for v in s.values())
    rms = {k: v["tip_error_mm"]["rms"] for k, v in s.items()}
    assert rms["no_play"] < rms["compensated"] < rms["plain"]
    assert out["ratio_rms"] == pytest.approx(rms["plain"] / rms["compensated"], rel=1e-3)
    assert out["ratio_rms"] >= 2.0 and out["pass"]
    # every command that reached the robot kept the per-command speed limit
    assert max(v["max_command_step_mm"] for v in s.values()) <= out["v_max_step_mm"] * (1 + 1e-9)
    assert png.stat().st_size > 10_000


def test_the_same_seed_gives_the_same_numbers(result, capsys):
    out, _, d = result
    js = d / "again.json"
    assert main(["bench", "feedforward", "--seconds", "3", "--settle-s", "0.5", "--seed", "4", "--json", str(js)]) == 0
    assert json.loads(js.read_text()) == out
    assert "ratio plain / compensated (rms)" in capsys.readouterr().out


@pytest.mark.parametrize("argv, flag", [(["--backlash-mm", "0"], "--backlash-mm"), (["--seconds", "-1"], "--seconds"),
                                        (["--settle-s", "20"], "--settle-s"), (["--amp-mm", "50"], "--amp-mm")])
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, argv, flag):
    js = tmp_path / "x.json"
    assert main(["bench", "feedforward", *argv, "--json", str(js)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and flag in err
    assert not js.exists()


def test_a_model_without_backlash_is_refused(tmp_path, capsys):
    m = tmp_path / "m.json"
    m.write_text(json.dumps({"format": "teleop-link-model/1", "links": [
        {"kind": "position", "input": "motor_pos", "output": "tip_pos", "gain": 1.0, "offset": 0.0, "effects": []}]}))
    assert main(["bench", "feedforward", "--compensation", str(m)]) == 2
    assert "no backlash" in capsys.readouterr().err
