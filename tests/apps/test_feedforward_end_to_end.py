"""How a user gets the compensation MODEL: a session on the robot with play, recorded; exported per cable;
`teleop diagnose --save-model` names the play and measures its width; that file is what --compensation takes."""

import csv
import json

import pytest

from teleop.apps.cli import main
from teleop.core.control.feedforward import model_backlash_width
from teleop.io.model_io import load_model


def test_session_recording_to_diagnosed_backlash_model(tmp_path, capsys):
    rec, csv, model = tmp_path / "s.mcap", tmp_path / "c1.csv", tmp_path / "m.json"
    # on the simulated clock (tick k at k periods, as fast as the machine runs): the same recording on any
    # machine and load, and no wall-clock pacing to share a worker with (tests/conftest.py REALTIME)
    assert main(["session", "--haptic", "sim://?script=sine&amp_mm=12&axis=x&period_s=2",
                 "--robot", "sim://robot?substeps=2&backlash_mm=0.5", "--robot-inline", "--sim-clock",
                 "--seconds", "8", "--record", str(rec)]) == 0
    assert "final state ENABLED" in capsys.readouterr().out
    assert main(["export", str(rec), "--csv", str(csv), "--cable", "1"]) == 0
    # the play is the position link's (tip_pos against motor_pos, tip_force its load): diagnosed without the
    # motor_force column, whose force link (no finding, nothing the compensation takes) is most of the
    # diagnosis's fitting (tests/diagnosis/test_sim_session_no_finding.py diagnoses that link on the
    # simulated robot's sessions)
    _drop_column(csv, "motor_force_N")
    assert main(["diagnose", str(csv), "--save-model", str(model), "--seed", "0"]) == 0
    out = capsys.readouterr().out
    assert "backlash on tip_pos" in out
    width = model_backlash_width(load_model(model), str(model))
    assert width == pytest.approx(0.5e-3, rel=0.1)
    # and the file drives the feed-forward
    js = tmp_path / "ff.json"
    assert main(["bench", "feedforward", "--compensation", str(model), "--seconds", "2", "--settle-s", "0.5",
                 "--json", str(js)]) == 0
    assert json.loads(js.read_text())["compensation"]["width_mm"] == pytest.approx(width * 1e3)


def _drop_column(path, name: str) -> None:
    """Interchange CSV `path` rewritten without column `name` and its metadata line."""
    lines = path.read_text().splitlines()
    meta = [ln for ln in lines if ln.startswith("#") and not ln.startswith(f"# {name} ")]
    rows = list(csv.reader(ln for ln in lines if not ln.startswith("#")))
    k = rows[0].index(name)
    path.write_text("\n".join(meta + [",".join(r[:k] + r[k + 1:]) for r in rows]) + "\n")
