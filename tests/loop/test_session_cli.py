"""`teleop session --fsr-calibration CSV`: a bad file is one line and exit 2 with nothing written; a good one is
the calibration the session's estimator uses (and records)."""

import json
from dataclasses import replace

import numpy as np

from teleop.apps.cli import main
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.geometry import default_geometry, load_geometry
from teleop.core.kinematics import pose2lengths
from teleop.io.recording import read_session
from teleop.core.sensors import default_fsr_calibration_data
from teleop.io.calibration_csv import load_fsr_calibration, write_fsr_calibration_csv


def test_calibration_with_a_missing_column_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys):
    good = tmp_path / "good.csv"
    write_fsr_calibration_csv(good, default_fsr_calibration_data())
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(",".join(line.split(",")[:2]) for line in good.read_text().splitlines()) + "\n")
    rec, js = tmp_path / "s.mcap", tmp_path / "s.json"
    rc = main(["session", "--fsr-calibration", str(bad), "--record", str(rec), "--json", str(js),
               "--seconds", "0.2", "--no-realtime", "--robot-inline"])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("teleop: error: ") and "missing column 'branch'" in err
    assert str(bad) in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "good.csv"]  # no recording, no JSON


def test_calibration_file_and_force_flags_are_what_the_session_uses(tmp_path, capsys):
    data = default_fsr_calibration_data()
    data = replace(data, reading=data.reading * 1.15, source="test: conductance +15 %")
    path = tmp_path / "cal.csv"
    write_fsr_calibration_csv(path, data)
    rec = tmp_path / "s.mcap"
    rc = main(["session", "--fsr-calibration", str(path), "--record", str(rec), "--seconds", "0.2",
               "--no-realtime", "--robot-inline", "--force-scale", "0.5", "--zero-neg-z", "--passivity-damping", "2"])
    capsys.readouterr()
    assert rc == 0
    meta = read_session(str(rec)).metadata["session"]
    render = meta["configuration"]["loop"]["render"]  # the force flags land in the loop's render settings
    assert (render["scale"], render["zero_negative_z"], render["alpha_max"]) == (0.5, True, 2.0)
    recorded = meta["calibration"]
    expected = ReadingEstimator(default_geometry(), "dynamic", cal=load_fsr_calibration(path)).describe()
    default = ReadingEstimator(default_geometry(), "dynamic").describe()
    assert recorded["fsr"] == json.loads(json.dumps(expected["fsr"], default=str))
    assert not np.allclose(np.ravel(recorded["fsr"]["loading"]), np.ravel(default["fsr"]["loading"]))


LAB_GEOMETRY = """[geometry]
base_anchors_mm = [[25, 0, 0], [12.5, 21.650635, 0], [-12.5, 21.650635, 0], [-25, 0, 0], [-12.5, -21.650635, 0],
                   [12.5, -21.650635, 0]]
platform_anchors_mm = [[0, 0, -12], [0, 0, 12], [0, 0, -12], [0, 0, 12], [0, 0, -12], [0, 0, 12]]
v_max_mm_s = 15.0
"""


def test_session_on_a_lab_geometry_records_it_and_its_cable_lengths_follow_it(tmp_path, capsys):
    """--geometry reaches the kinematics (commanded lengths), the simulated robot (its forward kinematics puts the
    end effector where the lab geometry's lengths say) and the recorded metadata."""
    path = tmp_path / "lab.toml"
    path.write_text(LAB_GEOMETRY)
    rec = tmp_path / "s.mcap"
    rc = main(["session", "--geometry", str(path), "--record", str(rec), "--seconds", "0.3", "--no-realtime",
               "--robot-inline", "--sim-clock"])
    capsys.readouterr()
    assert rc == 0
    s = read_session(str(rec))
    conf = s.metadata["session"]["configuration"]
    lab = load_geometry(path)
    np.testing.assert_allclose(conf["geometry"]["B"], lab.B)
    np.testing.assert_allclose(conf["geometry"]["r"], lab.r)
    assert conf["geometry"]["v_max"] == 0.015 and conf["geometry_file"] == str(path)
    cp = s.array("/teleop/setpoint", "setpoint_cp")
    jp = s.array("/teleop/setpoint", "servo_jp")
    moved = np.flatnonzero(s.array("/teleop/setpoint", "commanded") > 0)
    assert len(moved) > 100
    k = moved[-1]
    pose = np.r_[cp[k], 0.0, 0.0, 0.0]
    np.testing.assert_allclose(jp[k], pose2lengths(pose, lab), atol=1e-9)
    assert np.abs(jp[k] - pose2lengths(pose, default_geometry())).max() > 1e-3  # the seed robot's differ by mm
    realized = s.array("/robot/measured", "x_pose")[-1]  # the sim robot's pose from the lab lengths
    np.testing.assert_allclose(realized[:3], cp[-1], atol=1e-6)


def test_session_with_a_bad_geometry_file_is_one_line_naming_file_and_key_exit_2(tmp_path, capsys):
    path = tmp_path / "lab.toml"
    path.write_text(LAB_GEOMETRY.replace("v_max_mm_s = 15.0", "v_max_mm_s = -1"))
    rec, js = tmp_path / "s.mcap", tmp_path / "s.json"
    rc = main(["session", "--geometry", str(path), "--record", str(rec), "--json", str(js), "--seconds", "0.2",
               "--no-realtime", "--robot-inline"])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("teleop: error: ") and str(path) in err and "v_max_mm_s" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lab.toml"]  # no recording, no JSON
