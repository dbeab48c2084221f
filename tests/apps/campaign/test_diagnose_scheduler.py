"""`teleop diagnose REC... --scheduler local:2`: each recording read and diagnosed on a Dask worker, the
report (cross-file part included) the same bytes as in this process."""

import subprocess
import sys

from teleop.diagnosis.generator import GenConfig, make_case


def test_two_recordings_on_a_local_cluster_give_the_in_process_report(tmp_path):
    short = GenConfig(fs_hz=200.0, duration_s=5.0)  # each is diagnosed twice, once in each process
    a = make_case(1008, "backlash", "rig", seed=11, cfg=short).write(tmp_path / "a.csv")
    b = make_case(1016, "coulomb_friction", "rig", seed=11, cfg=short).write(tmp_path / "b.csv")
    out = {}
    for sched in ("none", "local:2"):
        r = subprocess.run([sys.executable, "-m", "teleop.apps.cli", "diagnose", "a.csv", "b.csv", "--seed", "3",
                            "--json", f"{sched[:5]}.json", "--scheduler", sched], cwd=tmp_path,
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        out[sched] = ((tmp_path / f"{sched[:5]}.json").read_bytes(), r.stdout)
    assert out["none"] == out["local:2"]
    assert b'"cross_file"' in out["none"][0] and b'"recording": "a.csv"' in out["none"][0]
    assert a.exists() and b.exists()
