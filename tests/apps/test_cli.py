"""The command line: bad input is one line on stderr and exit code 2; nothing half-written."""

import argparse
import json
import subprocess
import sys

import numpy as np
import pytest

from teleop.apps import cli
from teleop.apps.cli import main


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "teleop.apps.cli", *args], capture_output=True, text=True, cwd=cwd)


# `main` in this process: the exit code it returns is the process's (the entry-point and Ctrl-C tests below
# run the real `python -m teleop.apps.cli`)

def test_geometry_command_writes_json(tmp_path, capsys):
    out = tmp_path / "g.json"
    assert main(["geometry", "--json", str(out)]) == 0, capsys.readouterr().err
    data = json.loads(out.read_text())
    np.testing.assert_allclose(data["lengths_mm"], 25.0)


def test_bad_geometry_file_exit_2_one_line_nothing_written(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[geometry]\nmu = 1\n")
    out = tmp_path / "g.json"
    assert main(["geometry", "--geometry", str(bad), "--json", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and str(bad) in lines[0]
    assert not out.exists()


def test_nan_and_unreachable_pose_exit_2(capsys):
    assert main(["geometry", "--pose-mm-deg", "0", "0", "nan", "0", "0", "0"]) == 2
    assert "finite" in capsys.readouterr().err
    assert main(["geometry", "--pose-mm-deg", "0", "0", "80", "0", "0", "0"]) == 2
    assert "unreachable" in capsys.readouterr().err


def test_unknown_argument_exit_2(capsys):
    assert main(["geometry", "--bogus"]) == 2


# Every argparse error, in every subcommand: exactly one stderr line
# "teleop <sub>: error: <what; expected> (see teleop <sub> --help)", exit code 2, nothing on stdout.
ARGPARSE_ERRORS = [
    # (argv, prog that must report it, words the line must contain)
    (["geometry", "--bogus"], "teleop geometry", ["--bogus", "unrecognized"]),
    (["geometry", "stray"], "teleop geometry", ["stray", "unrecognized"]),
    (["blind-test", "--participants", "abc"], "teleop blind-test", ["--participants", "'abc'", "expected"]),
    (["blind-test", "--participants", "-3"], "teleop blind-test", ["--participants", "-3", ">= 1"]),
    (["palpate"], "teleop palpate", ["--test", "required", "expected --test {stiffness,z,xy,scan}"]),
    (["palpate", "--test", "nope"], "teleop palpate", ["--test", "'nope'", "choose from"]),
    (["palpate", "--test", "z", "--repeats", "x"], "teleop palpate", ["--repeats", "expected an integer", "'x'"]),
    (["palpate", "--test", "z", "--seed", "-1"], "teleop palpate", ["--seed", "-1", ">= 0"]),
    (["session", "--seconds", "soon"], "teleop session", ["--seconds", "expected a number", "'soon'"]),
    (["geometry", "--pose-mm-deg", "1", "2"], "teleop geometry", ["--pose-mm-deg", "6 arguments"]),
    (["export", __file__], "teleop export", ["--csv", "required", "expected --csv OUT"]),
    (["diagnose"], "teleop diagnose", ["REC", "required"]),
    (["bench", "--bogus"], "teleop bench", ["--bogus"]),
    (["bench", "tick", "--bogus"], "teleop bench tick", ["--bogus"]),
    (["bench", "tick", "--clock", "sundial"], "teleop bench tick", ["--clock", "'sundial'", "choose from"]),
    (["bench", "blind-jnd", "--participants", "0"], "teleop bench blind-jnd", ["--participants", "0", ">= 1"]),
    (["bench", "diagnose", "--seed", "-7"], "teleop bench diagnose", ["--seed", "-7", ">= 0"]),
    (["nosuch"], "teleop", ["'nosuch'", "choose from"]),
    (["--bogus"], "teleop", ["--bogus"]),
    # range checks (teleop.apps.argtypes)
    (["bench", "link", "--stream-seconds", "-1"], "teleop bench link", ["--stream-seconds", "> 0", "-1"]),
    (["session", "--robot-rate", "0"], "teleop session", ["--robot-rate", "50 to 10000 Hz", "got 0"]),
    (["session", "--robot-rate", "3"], "teleop session", ["--robot-rate", "50 to 10000 Hz"]),  # no Kalman gain
    (["blind-test", "--jnd", "5"], "teleop blind-test", ["--jnd", "5%"]),  # 500 %: not a person
    (["bench", "loop", "--spin-us", "-1"], "teleop bench loop", ["--spin-us", ">= 0"]),
    (["session", "--robot-rt", "200"], "teleop session", ["--robot-rt", "1-99", "200"]),
    (["session", "--seconds", "nan"], "teleop session", ["--seconds", "finite", "nan"]),
]


@pytest.mark.parametrize("argv,prog,words", ARGPARSE_ERRORS, ids=[" ".join(a) for a, _, _ in ARGPARSE_ERRORS])
def test_argparse_errors_are_one_line_exit_2(capsys, argv, prog, words):
    rc = main(argv)
    out, err = capsys.readouterr()
    assert rc == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].strip(), err
    line = lines[0]
    assert line.startswith(f"{prog}: error: ") and line.endswith(f"(see {prog} --help)"), line
    for word in words:
        assert word in line, (word, line)


def test_argparse_error_one_line_through_the_entry_point():
    r = run("blind-test", "--participants", "abc")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines() == [
        "teleop blind-test: error: argument --participants: expected a whole number, got 'abc' "
        "(see teleop blind-test --help)"]


def _help_texts(parser) -> dict:
    """--help of the top-level parser and of every (nested) subcommand parser, keyed by prog."""
    texts, todo = {}, [parser]
    while todo:
        p = todo.pop()
        texts[p.prog] = p.format_help()
        for action in p._actions:
            if isinstance(action, argparse._SubParsersAction):
                todo.extend(action.choices.values())
    return texts


def test_help_is_what_plain_argparse_prints(monkeypatch):
    ours = _help_texts(cli.build_parser())
    monkeypatch.setattr(cli, "TeleopArgumentParser", argparse.ArgumentParser)
    plain = _help_texts(cli.build_parser())
    assert "teleop bench tick" in ours and "teleop palpate" in ours
    assert ours == plain


@pytest.mark.parametrize("argv", [["--help"], ["palpate", "--help"], ["bench", "tick", "--help"], ["--version"]])
def test_help_and_version_exit_0_on_stdout(capsys, argv):
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert err == "" and out.strip()
    if argv[-1] == "--help":
        assert out.startswith(f"usage: teleop {' '.join(argv[:-1])}".rstrip())


def test_ctrl_c_during_a_recorded_session_exit_130_recording_closed_and_marked(tmp_path):
    """Ctrl-C reaches every process of the session (as a terminal sends it): the loop stops, the recording
    is closed whole, the JSON says "interrupted": "SIGINT", exit 130."""
    import os
    import signal
    import time

    from teleop.io.recording import read_session

    rec, out = tmp_path / "s.mcap", tmp_path / "s.json"
    p = subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", "session", "--seconds", "600", "--no-realtime",
                          "--record", str(rec), "--json", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 120  # a bound on a hang, not a timing check
        while not (rec.exists() and rec.stat().st_size > 50_000) and p.poll() is None and time.monotonic() < deadline:
            time.sleep(0.2)
        os.killpg(p.pid, signal.SIGINT)
        stdout, stderr = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
    assert p.returncode == 130, stderr
    assert "INTERRUPTED" in stdout and "interrupted" in stderr and "Traceback" not in stderr, (stdout, stderr)
    doc = json.loads(out.read_text())
    assert doc["interrupted"] == "SIGINT" and 0 < doc["timing"]["ticks"] < 600_000
    s = read_session(rec)
    assert not s.damage and "session" in s.metadata and s.metadata["session_end"]["interrupted"] == "SIGINT"


def test_results_follow_the_umask(tmp_path):
    """JSON (and every atomic result) gets the mode a new file gets under the umask, not mkstemp's 0600."""
    import os

    old = os.umask(0o022)
    try:
        assert main(["geometry", "--json", str(tmp_path / "a.json")]) == 0
        os.umask(0o077)
        assert main(["geometry", "--json", str(tmp_path / "b.json")]) == 0
    finally:
        os.umask(old)
    assert (tmp_path / "a.json").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "b.json").stat().st_mode & 0o777 == 0o600
