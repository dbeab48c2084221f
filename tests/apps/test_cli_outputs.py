"""Outputs and inputs of the `teleop` commands: no output overwrites an input (the same path, a symbolic or a
hard link), every output is checked before the work and named in the error, several recordings' plots get
distinct names, figures are written in the format their suffix names; inputs are looked at before they are
read (size, binary, MCAP, delimiter); the smaller messages (palpate's table, the geometry error, calibrate's
summary, pybullet's banner, the session JSON's documented keys)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import teleop.apps.commands.diagnose as diagnose_cmd
from teleop.apps.cli import main
from teleop.apps.commands.diagnose import plot_paths
from teleop.apps.protocols.palpation import ESTIMATORS, PalpationResult
from teleop.core.errors import InputError
from teleop.core.geometry import default_geometry, load_geometry
from teleop.io.calibration_csv import write_examples
from teleop.io.outputs import output_problem, save_figure
from teleop.io.recording_io import MCAP_MAGIC, read_recording
from teleop.io.table import read_table

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "recording.csv"


@pytest.fixture
def rec(tmp_path):
    """A copy of the example recording (its first 600 lines: diagnosed in a few seconds)."""
    path = tmp_path / "rec.csv"
    path.write_text("".join(EXAMPLE.read_text().splitlines(keepends=True)[:600]))
    return path


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if a recording is read: the refusal must come before any work."""
    def read(*_a, **_k):
        raise AssertionError("the work started")
    monkeypatch.setattr(diagnose_cmd, "read_recording", read)


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


# item 2: no output overwrites an input -----------------------------------------------------------------

@pytest.mark.parametrize("link", ["same", "symlink", "hardlink"])
@pytest.mark.parametrize("flag", ["--json", "--save-model"])
def test_an_output_naming_an_input_is_refused_before_the_work(tmp_path, rec, capsys, no_work, link, flag):
    before = rec.read_bytes()
    out = rec
    if link == "symlink":
        out = tmp_path / "link.csv"
        out.symlink_to(rec.name)
    elif link == "hardlink":
        out = tmp_path / "hard.csv"
        os.link(rec, out)
    assert main(["diagnose", str(rec), flag, str(out)]) == 2
    err = _one_error_line(capsys)
    assert f"argument {flag}" in err and "REC" in err and str(rec) in err and "the same file" in err
    assert rec.read_bytes() == before


def test_a_calibration_plot_derived_from_out_naming_the_input_is_refused(tmp_path, capsys):
    fsr = write_examples(tmp_path)[0]
    steps = tmp_path / "steps.png"  # the recording, under the name --out's default plot would take
    steps.write_bytes(Path(fsr).read_bytes())
    before = steps.read_bytes()
    assert main(["calibrate", "fsr", str(steps), "--out", str(tmp_path / "steps.toml")]) == 2
    err = _one_error_line(capsys)
    assert "--plot" in err and "the same file" in err
    assert steps.read_bytes() == before and not (tmp_path / "steps.toml").exists()


def test_a_derived_plot_naming_another_input_is_refused(tmp_path, rec, capsys, no_work):
    other = tmp_path / "d_rec.png"  # a recording whose name `--plot d.png` would give rec.csv's figure
    other.write_bytes(rec.read_bytes())
    assert main(["diagnose", str(rec), str(other), "--plot", str(tmp_path / "d.png")]) == 2
    err = _one_error_line(capsys)
    assert "--plot" in err and str(other) in err and "the same file" in err


# item 7: outputs checked before the work, named; several recordings' plots distinct ---------------------

def test_an_output_that_cannot_be_created_is_refused_naming_the_flag_before_the_work(rec, capsys, no_work):
    assert output_problem("/proc/nope/x.json") is not None  # writable by the permission bits, for root
    assert main(["diagnose", str(rec), "--json", "/proc/nope/x.json"]) == 2
    err = _one_error_line(capsys)
    assert "argument --json" in err and "/proc/nope" in err


def test_plot_names_of_several_recordings_are_distinct():
    paths = plot_paths("out/d.png", ["day1/a.csv", "day2/a.csv", "a_2.csv", "b.TXT"])
    assert [p.name for p in paths] == ["d_a.png", "d_a_2.png", "d_a_2_2.png", "d_b.png"]
    assert all(p.parent == Path("out") for p in paths)
    assert plot_paths("d.svg", ["x/a.csv"]) == [Path("d.svg")]
    assert [p.name for p in plot_paths("d", ["a.csv", "b.csv"])] == ["d_a.png", "d_b.png"]


def test_two_recordings_with_one_file_name_get_two_plots_and_the_names_are_printed(tmp_path, rec, capsys):
    (tmp_path / "day1").mkdir()
    (tmp_path / "day2").mkdir()
    a, b = tmp_path / "day1" / "rec.csv", tmp_path / "day2" / "rec.csv"
    a.write_bytes(rec.read_bytes())
    b.write_bytes(rec.read_bytes())
    plot = tmp_path / "d.png"
    assert main(["diagnose", str(a), str(b), "--plot", str(plot)]) == 0
    out = capsys.readouterr().out
    first, second = tmp_path / "d_rec.png", tmp_path / "d_rec_2.png"
    assert first.read_bytes()[:4] == b"\x89PNG" and second.read_bytes()[:4] == b"\x89PNG"
    assert f"wrote {first} ({a})" in out and f"wrote {second} ({b})" in out


# item 5: inputs sniffed before they are read -------------------------------------------------------------

def _refused(path, **kwargs) -> str:
    with pytest.raises(InputError) as exc:
        read_recording(path, **kwargs)
    message = str(exc.value)
    assert "\n" not in message and "\0" not in message and message.isprintable(), message
    return message


def test_a_recording_above_the_size_limit_is_refused_and_the_flag_lifts_it(rec, capsys, monkeypatch):
    message = _refused(rec, max_mb=0.01)
    assert "MB" in message and "--max-input-mb" in message
    assert read_recording(rec, max_mb=None).n > 20 and read_recording(rec).n > 20
    monkeypatch.setattr(Path, "read_text", lambda *_a, **_k: pytest.fail("read before the size was checked"))
    assert main(["diagnose", str(rec), "--max-input-mb", "0.01"]) == 2
    assert "--max-input-mb" in _one_error_line(capsys)


def test_binary_content_is_one_line_without_its_bytes(tmp_path):
    nul = tmp_path / "nul.csv"
    nul.write_bytes(b"t_s,motor_pos_mm\n" + b"\0" * 80 + b"\n")
    assert "binary content (NUL bytes" in _refused(nul)
    latin = tmp_path / "latin.csv"
    latin.write_bytes("t_s,motor_pos_mm,temp\xe9rature_C\n".encode("latin-1"))
    assert "not UTF-8" in _refused(latin)
    with pytest.raises(InputError, match=r"binary content \(NUL bytes"):
        read_table(nul, ("t_s",))


def test_an_mcap_session_points_to_teleop_export(tmp_path, capsys):
    run = tmp_path / "run.mcap"
    run.write_bytes(MCAP_MAGIC + b"0\r\n" + bytes(range(256)))
    assert "teleop export" in _refused(run)
    assert main(["diagnose", str(run)]) == 2
    err = _one_error_line(capsys)
    assert f"teleop export {run} --csv" in err


def test_a_semicolon_csv_is_told_its_delimiter(tmp_path):
    semi = tmp_path / "semi.csv"
    semi.write_text(EXAMPLE.read_text().replace(",", ";"))
    assert "semicolon-separated, expected commas" in _refused(semi)


# item 9: the smaller items ------------------------------------------------------------------------------

@pytest.mark.parametrize("suffix, magic", [(".pdf", b"%PDF"), (".svg", b"<?xml"), (".png", b"\x89PNG")])
def test_a_figure_is_written_in_the_format_its_suffix_names(tmp_path, suffix, magic):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    path = save_figure(fig, tmp_path / f"f{suffix}")
    assert path.read_bytes()[:len(magic)] == magic


def test_a_plot_suffix_of_no_figure_format_is_refused_naming_the_flag(rec, capsys, no_work):
    assert main(["diagnose", str(rec), "--plot", "d.jpg"]) == 2
    err = _one_error_line(capsys)
    assert "argument --plot" in err and ".png, .pdf, .svg" in err


def test_palpate_prints_a_table_not_python_dicts():
    summary = {n: {"mean_abs_error_N": 0.1, "rmse_N": 0.2, "max_abs_error_N": 0.3} for n in ESTIMATORS}
    contrast = {n: {"rigid_mean_N": 2.0, "silicone_mean_N": 1.0, "ratio": 2.0} for n in ("ground_truth",) + ESTIMATORS}
    res = PalpationResult("stiffness", "uniform", 1, {}, [], summary,
                          {"ranks_correctly": {n: True for n in ESTIMATORS}, "contrast": contrast}, 1.0, 1.0)
    table = res.table()
    assert "{" not in table and "': " not in table and "True" not in table
    assert "non_compensated yes" in table and "rigid [N]" in table


def test_the_geometry_error_names_the_file_once(tmp_path):
    g = default_geometry()
    vectors = lambda a: "[" + ", ".join("[" + ", ".join(f"{v * 1e3:g}" for v in row) + "]" for row in a) + "]"
    path = tmp_path / "lab.toml"
    path.write_text(f"[geometry]\nbase_anchors_mm = {vectors(g.B)}\nplatform_anchors_mm = {vectors(g.r)}\nmu = -1\n")
    with pytest.raises(InputError) as exc:
        load_geometry(path)
    assert str(exc.value).count(str(path)) == 1 and "'mu'" in str(exc.value)


def test_calibrate_says_it_wrote_the_json(tmp_path, capsys):
    one = write_examples(tmp_path)[2]
    out, js = tmp_path / "cal.toml", tmp_path / "cal.json"
    assert main(["calibrate", "one-sensor", str(one), "--out", str(out), "--json", str(js)]) == 0
    printed = capsys.readouterr().out
    assert js.exists() and str(js) in printed and str(out) in printed


def test_opening_a_world_prints_no_pybullet_banner():
    code = ("from scenes.pads import z_test_pad\nfrom scenes.world import PadWorld, WorldParams\n"
            "with PadWorld(z_test_pad(), WorldParams()) as w:\n    pass\nprint('opened')\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0 and done.stdout == "opened\n", done.stderr
    assert "pybullet" not in done.stderr, done.stderr


def test_every_key_of_the_session_json_is_documented(tmp_path, capsys):
    model = tmp_path / "m.json"
    model.write_text(json.dumps({"format": "teleop-link-model/1", "source": "hand-written", "links": [
        {"kind": "position", "input": "motor_pos", "output": "tip_pos", "gain": 1.0, "offset": 0.0,
         "effects": [{"effect": "backlash", "params": {"width": 0.0005}}]}]}))
    js = tmp_path / "s.json"
    assert main(["session", "--compensation", str(model), "--json", str(js), "--seconds", "0.05",
                 "--no-realtime", "--robot-inline"]) == 0
    doc = json.loads(js.read_text())
    docs = (ROOT / "docs" / "formats.md").read_text()
    entry = docs[docs.index("- `teleop session`:"):]
    entry = entry[:entry.index("\n- ")]
    for key in list(doc) + list(doc["compensation"]):
        assert f'"{key}"' in entry, key


@pytest.mark.parametrize("argv, named", [
    (["bench", "feedforward", "--compensation", "bogus://"], "--compensation"),
    (["bench", "blind-jnd", "--speed-mm-s", "-1"], "--speed-mm-s"),
    (["blind-test", "--depth-mm", "0"], "--depth-mm"),
])
def test_a_bad_option_value_is_one_line_naming_the_option(capsys, argv, named):
    assert main(argv) == 2
    err = _one_error_line(capsys)
    assert f"argument {named}" in err and argv[-1] in err


def test_a_binary_link_model_is_one_line(tmp_path, capsys):
    model = tmp_path / "binary.json"
    model.write_bytes(b"{" + bytes(range(128, 256)))
    assert main(["bench", "feedforward", "--compensation", str(model)]) == 2
    err = _one_error_line(capsys)
    assert str(model) in err and "not UTF-8" in err
