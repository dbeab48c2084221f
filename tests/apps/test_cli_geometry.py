"""`--geometry FILE` on every command that builds the robot (issue 29 item 6): blind-test and bench blind-jnd
(the rig's stations), palpate, the campaign's rig option; a bad file is one line naming the file and key, exit 2,
nothing written."""

import json

import numpy as np
import pytest

from scenes.pads import blind_test_pad
from teleop.apps.bench.session_diagnosis import bench_session_diagnosis
from teleop.apps.bench.sim import _make_robot
from teleop.apps.bench.tick import make_ticks
from teleop.apps.campaign.blind import point_tasks
from teleop.apps.campaign.spec import load_campaign
from teleop.apps.cli import build_parser, main
from teleop.apps.commands.blind_test import rig_options
from teleop.apps.protocols.blind.rig import BackgroundSession, RigOptions, Station, rig_dict
from teleop.core.errors import InputError
from teleop.core.geometry import default_geometry, load_geometry
from teleop.io.recording import read_session

LAB = """[geometry]
base_anchors_mm = [[25, 0, 0], [12.5, 21.650635, 0], [-12.5, 21.650635, 0], [-25, 0, 0], [-12.5, -21.650635, 0],
                   [12.5, -21.650635, 0]]
platform_anchors_mm = [[0, 0, -12], [0, 0, 12], [0, 0, -12], [0, 0, 12], [0, 0, -12], [0, 0, 12]]
mu = 0.07
"""


@pytest.fixture
def lab(tmp_path):
    path = tmp_path / "lab.toml"
    path.write_text(LAB)
    return path


def test_blind_test_rig_builds_its_stations_on_the_geometry(lab):
    args = build_parser().parse_args(["blind-test", "--geometry", str(lab)])
    options = rig_options(args)
    assert options.geometry == str(lab) and rig_dict(options)["geometry"] == str(lab)
    assert "geometry" not in rig_dict(RigOptions())  # the seed robot's rig dict is what it was
    st = Station(blind_test_pad(), options, (0, 0))
    want = load_geometry(lab)
    for g in (st.geom, st.robot.params.geometry):  # the loop's kinematics and estimator, the simulated robot
        np.testing.assert_array_equal(g.B, want.B)
        assert g.mu == 0.07
    assert not np.allclose(st.geom.B, default_geometry().B)
    # a real rig (--operator human): the background `teleop session` gets the same file
    argv = BackgroundSession("touch://", "serial:///dev/ttyACM0", options).argv
    assert argv[argv.index("--geometry") + 1] == str(lab)


def test_bench_blind_jnd_takes_the_rig_geometry(lab):
    args = build_parser().parse_args(["bench", "blind-jnd", "--geometry", str(lab)])
    assert rig_options(args).geometry == str(lab)


@pytest.mark.parametrize("argv", [["blind-test", "--participants", "1"], ["palpate", "--test", "z", "--limit", "1"],
                                  ["session", "--seconds", "0.1", "--no-realtime", "--robot-inline"],
                                  ["bench", "blind-jnd", "--participants", "1"],
                                  ["bench", "loop", "--seconds", "0.1", "--no-realtime"],
                                  ["bench", "feedforward", "--seconds", "2"],
                                  ["bench", "sim", "--seconds", "0.2"], ["bench", "tick", "--ticks", "1000"],
                                  ["bench", "session-diagnose", "--seconds", "2"]])
def test_a_bad_geometry_is_one_line_naming_file_and_key_exit_2_nothing_written(tmp_path, capsys, argv):
    bad = tmp_path / "lab.toml"
    bad.write_text(LAB.replace("mu = 0.07", "mu = -0.07"))
    out = tmp_path / "out.json"
    rc = main([*argv, "--geometry", str(bad), "--json", str(out)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("teleop: error: ") and str(bad) in err and "'mu'" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lab.toml"]


CAMPAIGN = """
[campaign]
kind = "blind-jnd"
seed = 1
[study]
participants = 2
jnd = [0.23]
[rig]
robot_substeps = 4
{rig}
[grid]
{grid}
"""


def test_campaign_rig_geometry_is_read_relative_to_the_file_and_its_content_makes_the_task(tmp_path, lab):
    path = tmp_path / "c.toml"
    path.write_text(CAMPAIGN.format(rig='geometry = "lab.toml"', grid="force_scale = [0.1]"))
    c = load_campaign(path)
    (point, block), = point_tasks(c)
    assert point.rig["geometry"] == str(lab.resolve())
    assert RigOptions(**block[0].identity["rig"]).geometry == str(lab.resolve())
    ids = {t.id for t in block}
    lab.write_text(LAB.replace("mu = 0.07", "mu = 0.08"))  # an edited robot is new work
    assert not ids & {t.id for t in point_tasks(load_campaign(path))[0][1]}
    # several robots as a grid axis
    (tmp_path / "b.toml").write_text(LAB.replace("mu = 0.07", "mu = 0.05"))
    path.write_text(CAMPAIGN.format(rig="", grid='geometry = ["lab.toml", "b.toml"]'))
    points = [p for p, _ in point_tasks(load_campaign(path))]
    assert [p.params["geometry"] for p in points] == ["lab.toml", "b.toml"]
    assert [load_geometry(p.rig["geometry"]).mu for p in points] == [0.08, 0.05]


def test_campaign_with_a_bad_geometry_names_file_and_key(tmp_path, lab, capsys):
    lab.write_text(LAB.replace("mu = 0.07", "muu = 0.07"))
    path = tmp_path / "c.toml"
    path.write_text(CAMPAIGN.format(rig='geometry = "lab.toml"', grid="force_scale = [0.1]"))
    with pytest.raises(InputError, match=r"lab.toml \[geometry\]: unknown key 'muu'"):
        load_campaign(path)
    rc = main(["campaign", "run", str(path), "--out", str(tmp_path / "out")])
    assert rc == 2 and "unknown key 'muu'" in capsys.readouterr().err and not (tmp_path / "out").exists()


def test_palpate_runs_the_simulated_robot_and_estimators_on_the_geometry(tmp_path, lab, capsys):
    out = tmp_path / "p.json"
    rc = main(["palpate", "--test", "z", "--limit", "1", "--repeats", "1", "--geometry", str(lab), "--json", str(out)])
    capsys.readouterr()
    assert rc == 0
    d = json.loads(out.read_text())
    assert d["params"]["mu"] == 0.07  # the run's own geometry (the simulated robot's, read by the estimators)
    assert d["geometry_file"] == str(lab) and d["geometry"]["B"][0] == [0.025, 0.0, 0.0]


def test_bench_loop_runs_its_session_on_the_geometry(tmp_path, lab, capsys):
    rec = tmp_path / "loop.mcap"
    rc = main(["bench", "loop", "--seconds", "0.2", "--no-realtime", "--robot-rate", "500", "--geometry", str(lab),
               "--record", str(rec)])
    capsys.readouterr()
    assert rc == 0
    conf = read_session(str(rec)).metadata["session"]["configuration"]
    assert conf["geometry"]["mu"] == 0.07 and conf["geometry_file"] == str(lab)


def test_bench_feedforward_runs_its_sessions_on_the_geometry(tmp_path, lab, capsys):
    lab.write_text(LAB + "v_max_mm_s = 15.0\n")
    out = tmp_path / "ff.json"
    rc = main(["bench", "feedforward", "--seconds", "1", "--settle-s", "0.2", "--geometry", str(lab),
               "--json", str(out)])
    capsys.readouterr()
    assert rc == 0
    d = json.loads(out.read_text())
    assert d["geometry_file"] == str(lab)
    assert d["v_max_step_mm"] == pytest.approx(15.0 * 2e-3)  # the loop's command step: the file's v_max x period


def test_bench_sim_runs_its_robot_kinematics_and_estimator_on_the_geometry(tmp_path, lab, capsys):
    with _make_robot("z60", 1, 1, geometry=load_geometry(lab)) as robot:
        assert robot.geom.mu == 0.07 and robot.geom.B[0].tolist() == [0.025, 0.0, 0.0]
    runs = {}
    for name, extra in (("seed", []), ("lab", ["--geometry", str(lab)])):
        out = tmp_path / f"{name}.json"
        assert main(["bench", "sim", "--seconds", "0.3", "--no-batch", "--json", str(out), *extra]) == 0
        runs[name] = json.loads(out.read_text())
    capsys.readouterr()
    assert runs["lab"]["geometry_file"] == str(lab) and "geometry_file" not in runs["seed"]
    assert runs["lab"]["trajectory"]["sha256"] != runs["seed"]["trajectory"]["sha256"]


def test_bench_session_diagnose_records_and_replays_on_the_geometry(tmp_path, lab):
    out = bench_session_diagnosis([("coulomb_friction", {"Fc": 0.3})], 2.0, 1, 1, tmp_path, subsets=False,
                                  geometry_file=str(lab))
    conf = read_session(str(tmp_path / "session.mcap")).metadata["session"]["configuration"]
    assert conf["geometry"]["mu"] == 0.07 and conf["geometry_file"] == str(lab)
    assert out["geometry_file"] == str(lab)


def test_bench_tick_times_the_tick_on_the_geometry(lab):
    fast, ref = make_ticks(geometry=load_geometry(lab))
    for geom in (fast.estimator.geom, ref.geom):  # the estimate's structure matrix and capstan law
        assert geom.mu == 0.07 and geom.B[0].tolist() == [0.025, 0.0, 0.0]
