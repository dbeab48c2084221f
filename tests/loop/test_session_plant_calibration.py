"""A session on the distributed plant converts its FSRs with that plant's platform calibration
(scenes.fsr_lab.robot_url_calibration), as palpation and `teleop bench seed` do; a file given with
--fsr-calibration still wins, and the matched plant keeps the built-in calibration."""

import json

import numpy as np

from scenes.fsr_lab import robot_url_calibration
from teleop.apps.cli import main
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.geometry import default_geometry
from teleop.core.sensors import default_fsr_calibration_data
from teleop.io.calibration_csv import load_fsr_calibration, write_fsr_calibration_csv
from teleop.io.recording import read_session
from teleop.loop.session import run_session

URL = "sim://robot?substeps=2&plant=distributed"


def _recorded_fsr(rec) -> dict:
    return read_session(str(rec)).metadata["session"]["calibration"]["fsr"]


def _described(cal) -> dict:
    return json.loads(json.dumps(ReadingEstimator(default_geometry(), "dynamic", cal=cal).describe()["fsr"],
                                 default=str))


def test_the_session_on_the_distributed_plant_converts_with_its_platform_calibration(tmp_path, capsys):
    rec = tmp_path / "d.mcap"
    assert main(["session", "--robot", URL, "--record", str(rec), "--seconds", "0.1", "--no-realtime",
                 "--robot-inline"]) == 0
    own = _described(robot_url_calibration(URL))
    assert _recorded_fsr(rec) == own
    assert not np.allclose(np.ravel(own["loading"]), np.ravel(_described(None)["loading"]))
    # a file still wins
    path = tmp_path / "cal.csv"
    write_fsr_calibration_csv(path, default_fsr_calibration_data())
    rec2 = tmp_path / "f.mcap"
    assert main(["session", "--robot", URL, "--fsr-calibration", str(path), "--record", str(rec2), "--seconds", "0.1",
                 "--no-realtime", "--robot-inline"]) == 0
    assert _recorded_fsr(rec2) == _described(load_fsr_calibration(path))
    capsys.readouterr()


def test_run_sessions_own_estimator_takes_the_plants_calibration(tmp_path):
    rec = tmp_path / "r.mcap"
    run_session("sim://?script=pokes", URL, 0.1, record=str(rec), robot_process_hz=None, realtime=False)
    assert _recorded_fsr(rec) == _described(robot_url_calibration(URL))
    rec_m = tmp_path / "m.mcap"
    run_session("sim://?script=pokes", "sim://robot?substeps=2", 0.1, record=str(rec_m), robot_process_hz=None,
                realtime=False)
    assert _recorded_fsr(rec_m) == _described(None)
