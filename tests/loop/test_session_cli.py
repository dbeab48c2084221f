"""`teleop session --fsr-calibration CSV`: a bad file is one line and exit 2 with nothing written; a good one is
the calibration the session's estimator uses (and records)."""

import json
from dataclasses import replace

import numpy as np

from teleop.apps.cli import main
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.geometry import default_geometry
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
