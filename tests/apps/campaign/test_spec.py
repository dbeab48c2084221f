"""Campaign files: the grid and its tasks, and bad input named with the file and key (exit 2, one line,
nothing written)."""

import pytest

from teleop.apps.campaign.blind import point_tasks, tasks
from teleop.apps.campaign.spec import load_campaign
from teleop.apps.cli import main
from teleop.core.errors import InputError

GOOD = """
[campaign]
kind = "blind-jnd"
seed = 5
[study]
participants = 5
participants_per_task = 2
jnd = ["23%", 0.1, 0.1]
[rig]
robot_substeps = 4
[participant]
force = 0.25
[grid]
force_scale = [0.05, 0.1]
compensation = [true, false]
"""


def write(tmp_path, text, name="c.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_grid_points_tasks_and_identities(tmp_path):
    c = load_campaign(write(tmp_path, GOOD))
    assert c.kind == "blind-jnd" and c.seed == 5 and c.study.jnds == (0.1, 0.23)
    assert [p.params for p in c.study.points] == [
        {"force_scale": 0.05, "compensation": True}, {"force_scale": 0.05, "compensation": False},
        {"force_scale": 0.1, "compensation": True}, {"force_scale": 0.1, "compensation": False}]
    p0 = c.study.points[0]
    assert p0.rig["robot_substeps"] == 4 and p0.rig["kalman_bandwidth"] == 80.0 and "seed" not in p0.rig
    assert p0.participant["force"] == 0.25 and "jnd" not in p0.participant
    blocks = point_tasks(c)
    assert [t.identity["participants"] for t in blocks[0][1]] == [[1, 2], [3, 4], [5, 5]]
    ids = [t.id for t in tasks(c)]
    assert len(ids) == len(set(ids)) == 12
    assert blocks[0][1][0].label == "force_scale=0.05, compensation=True; participants 1-2"
    # the seed on the command line replaces the file's, and with it every identity
    assert not set(ids) & {t.id for t in tasks(load_campaign(write(tmp_path, GOOD), seed=6))}


@pytest.mark.parametrize("change, message", [
    (("seed = 5", "seed = -1"), "[campaign]: key 'seed' must be >= 0"),
    (('kind = "blind-jnd"', 'kind = "blind"'), "kind 'blind': expected one of: blind-jnd, diagnose, noop"),
    (("[rig]", "[rigg]"), "unknown key 'rigg'"),
    (("robot_substeps = 4", "robot_substeps = 4.5"), "[rig] robot_substeps: expected a whole number"),
    (("force = 0.25", "forse = 0.25"), "[participant]: unknown key 'forse'"),
    (("compensation = [true, false]", 'compensation = ["yes"]'), "[grid] compensation: expected true or false"),
    (("compensation = [true, false]", "jnd = [0.1]"), "[grid]: unknown key 'jnd'"),
    (("compensation = [true, false]", "force = [0.1]"), "[grid] force: also given as a fixed value"),
    (("compensation = [true, false]", "kalman_bandwidth = [80, -1]"), "kalman_bandwidth must be > 0 Hz"),
    (("force_scale = [0.05, 0.1]", "force_scale = [0.1, 0.1]"), "a value is listed twice"),
    (('jnd = ["23%", 0.1, 0.1]', 'jnd = ["23 percent"]'), "[study] jnd: expected a fraction"),
    (('jnd = ["23%", 0.1, 0.1]', "jnd = []"), "[study] jnd: expected at least one JND"),
    (("participants = 5", "participants = 0"), "key 'participants' must be >= 1"),
    (("[grid]", "[grid\n"), "invalid TOML"),
])
def test_bad_campaign_files_name_the_file_and_key(tmp_path, change, message):
    path = write(tmp_path, GOOD.replace(*change))
    with pytest.raises(InputError) as err:
        load_campaign(path)
    assert str(path) in str(err.value) and message in str(err.value)


def test_recordings_campaign_paths_maps_and_errors(tmp_path):
    (tmp_path / "recs").mkdir()
    for name in ("b.csv", "a.csv"):
        (tmp_path / "recs" / name).write_text("t_s,motor_pos_mm\n0,1\n")
    c = load_campaign(write(tmp_path, '[campaign]\nkind = "diagnose"\n[[recordings]]\npaths = ["recs/*.csv", '
                                      '"recs/a.csv"]\nholdout = 0.3\n'))
    assert [r.path for r in c.study] == [str(tmp_path / "recs" / n) for n in ("a.csv", "b.csv")]
    assert c.study[0].holdout == 0.3 and c.study[0].map is None and len(c.study[0].sha256) == 64
    for body, message in (('paths = ["none/*.csv"]', "'none/*.csv' matches no file"),
                          ('paths = ["recs/a.csv"]\nmap = "nosuchmap"', "column map 'nosuchmap' not found"),
                          ('paths = ["recs/a.csv"]\nholdout = 1.5', "'holdout' must be a fraction"),
                          ('paths = ["recs/a.csv"]\ncolumns = 3', "unknown key 'columns'"),
                          ('paths = ["recs/a.csv"]\nbaseline = "nosuch"', "--baseline"),
                          ('paths = ["recs/a.csv"]\nsindy = 1', "'sindy' must be true or false")):
        with pytest.raises(InputError, match="#1: " if "columns" not in body else "#1") as err:
            load_campaign(write(tmp_path, f'[campaign]\nkind = "diagnose"\n[[recordings]]\n{body}\n'))
        assert message in str(err.value)


def test_cli_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path, monkeypatch, capsys):
    """Through `teleop.apps.cli.main` in this process, run in tmp_path (`--out out` is relative to it)."""
    monkeypatch.chdir(tmp_path)
    bad = write(tmp_path, GOOD.replace("robot_substeps = 4", "robot_substeps = 'four'"))
    for args, needle in (
            (["campaign", "run", str(bad), "--out", "out"], "[rig] robot_substeps: expected a whole number"),
            (["campaign", "run", str(tmp_path / "c.toml"), "--out", "out", "--scheduler", "local:0"],
             "expected none, local:N"),
            (["campaign", "run", str(tmp_path / "missing.toml"), "--out", "out"], "file not found"),
            (["bench", "blind-jnd", "--scheduler", "udp://x:1"], "expected none, local:N"),
            (["campaign", "summary", str(write(tmp_path, GOOD, "g.toml")), "--out", "out"],
             "holds no campaign results")):
        rc, err = main(args), capsys.readouterr().err
        assert rc == 2, err
        assert len(err.strip().splitlines()) == 1 and needle in err, err
        assert not (tmp_path / "out").exists()
