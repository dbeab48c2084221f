"""The command line: bad input is one line on stderr and exit code 2; nothing half-written."""

import json
import subprocess
import sys

import numpy as np


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "teleop.cli", *args], capture_output=True, text=True, cwd=cwd)


def test_geometry_command_writes_json(tmp_path):
    out = tmp_path / "g.json"
    r = run("geometry", "--json", str(out))
    assert r.returncode == 0, r.stderr
    data = json.loads(out.read_text())
    np.testing.assert_allclose(data["lengths_mm"], 25.0)


def test_bad_geometry_file_exit_2_one_line_nothing_written(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[geometry]\nmu = 1\n")
    out = tmp_path / "g.json"
    r = run("geometry", "--geometry", str(bad), "--json", str(out))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and str(bad) in lines[0]
    assert not out.exists()


def test_nan_and_unreachable_pose_exit_2():
    r = run("geometry", "--pose-mm-deg", "0", "0", "nan", "0", "0", "0")
    assert r.returncode == 2 and "finite" in r.stderr
    r = run("geometry", "--pose-mm-deg", "0", "0", "80", "0", "0", "0")
    assert r.returncode == 2 and "unreachable" in r.stderr


def test_unknown_argument_exit_2():
    assert run("geometry", "--bogus").returncode == 2
