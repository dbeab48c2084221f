"""`teleop session --compensation MODEL`: a bad model is one line and exit 2 with nothing written; a good one
is applied in the command path and stored in the recording's metadata."""

import json

import pytest

from teleop.apps.cli import main
from teleop.io.recording import read_session

HAND_WRITTEN = {"format": "teleop-link-model/1", "source": "hand-written", "links": [
    {"kind": "position", "input": "motor_pos", "output": "tip_pos", "gain": 1.0, "offset": 0.0,
     "effects": [{"effect": "backlash", "params": {"width": 0.0005}}]}]}


@pytest.mark.parametrize("content, expect", [
    ("{not json", "invalid JSON"),
    (json.dumps({"format": "other"}), "not a link model"),
    (json.dumps({**HAND_WRITTEN, "links": [{**HAND_WRITTEN["links"][0], "effects": []}]}), "no backlash"),
    (json.dumps({**HAND_WRITTEN, "links": [{**HAND_WRITTEN["links"][0],
                                            "effects": [{"effect": "backlash", "params": {"width": -1}}]}]}),
     "width"),
])
def test_a_bad_model_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, content, expect):
    model = tmp_path / "m.json"
    model.write_text(content)
    rc = main(["session", "--compensation", str(model), "--record", str(tmp_path / "s.mcap"),
               "--json", str(tmp_path / "s.json"), "--seconds", "0.2", "--no-realtime", "--robot-inline"])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("teleop: error: ") and expect in err and str(model) in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]


def test_the_model_is_applied_and_recorded(tmp_path, capsys):
    model = tmp_path / "m.json"
    model.write_text(json.dumps(HAND_WRITTEN))
    rec, js = tmp_path / "s.mcap", tmp_path / "s.json"
    rc = main(["session", "--robot", "sim://robot?substeps=2&backlash_mm=0.5", "--compensation", str(model),
               "--record", str(rec), "--json", str(js), "--seconds", "0.3", "--no-realtime", "--robot-inline"])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert "backlash feed-forward of 0.5 mm per cable" in out
    assert json.loads(js.read_text())["compensation"]["backlash_width_mm"] == pytest.approx(0.5)
    conf = read_session(str(rec)).metadata["session"]["configuration"]
    assert conf["compensation"]["width_mm"] == pytest.approx([0.5] * 6)
    # the bench measures the recorded session's tip error and names its compensation
    out_js = tmp_path / "rec.json"
    assert main(["bench", "feedforward", "--recordings", str(rec), "--settle-s", "0.1", "--json", str(out_js)]) == 0
    r = json.loads(out_js.read_text())["recordings"][str(rec)]
    assert r["readings"] > 10 and r["tip_error_mm"]["rms"] > 0
    assert r["compensation"]["width_mm"] == pytest.approx([0.5] * 6)
