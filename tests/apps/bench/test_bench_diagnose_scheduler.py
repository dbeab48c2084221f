"""`teleop bench diagnose --scheduler`: the generated cases, or the real-recording comparison, run on Dask
workers give the same report, the same bytes, as in this process (a real two-worker cluster, one for the
module, reached at its tcp:// address as a cluster started by hand would be)."""

import json

import pytest
from distributed import LocalCluster

from teleop.apps.cli import main
from teleop.diagnosis.generator import GenConfig, make_case

pytestmark = pytest.mark.xdist_group("realtime")  # a real Dask cluster: tests/conftest.py's REALTIME group


@pytest.fixture(scope="module")
def address():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        yield cluster.scheduler_address


def _bench(capsys, *argv) -> str:
    assert main(["bench", "diagnose", *argv]) == 0
    return capsys.readouterr().out


def test_generated_cases_on_workers_give_the_in_process_report(address, tmp_path, capsys):
    common = ["--suite", "rig", "--cases", "2", "--seed", "5", "--seconds", "5", "--rate", "200"]
    here = _bench(capsys, *common, "--json", str(tmp_path / "here.json"))
    there = _bench(capsys, *common, "--json", str(tmp_path / "there.json"), "--scheduler", address)
    assert (tmp_path / "here.json").read_bytes() == (tmp_path / "there.json").read_bytes()
    assert here == there
    rows = json.loads((tmp_path / "here.json").read_text())["rig_rows"]
    assert [r["index"] for r in rows] == sorted(r["index"] for r in rows) and len(rows) == 2  # plan order kept


def test_recordings_on_workers_give_the_in_process_comparison(address, tmp_path, capsys):
    short = GenConfig(fs_hz=200.0, duration_s=5.0)
    recs = [str(make_case(k, "coulomb_friction", "rig", 2, short).write(tmp_path / f"r{k}.csv")) for k in (1, 2)]
    here = _bench(capsys, "--recordings", *recs, "--json", str(tmp_path / "here.json"))
    there = _bench(capsys, "--recordings", *recs, "--json", str(tmp_path / "there.json"), "--scheduler", address)
    assert (tmp_path / "here.json").read_bytes() == (tmp_path / "there.json").read_bytes()
    assert here == there and "r1.csv" in here and "r2.csv" in here
