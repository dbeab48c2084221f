"""Recordings in: interchange CSV round trip, the MRDLab column map, and malformed inputs."""

import math

import numpy as np
import pytest

from teleop.apps.cli import main
from teleop.io.recording_io import (builtin_map, load_column_map, read_interchange, read_recording,
                                           write_interchange)
from teleop.core.errors import InputError

from tests._data import MRDLAB, needs_mrdlab


def _csv(tmp_path, text, name="rec.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _good_rows(n=50):
    return "\n".join(f"{k * 0.01:.3f},{math.sin(k / 5):.5f},{0.9 * math.sin(k / 5):.5f}" for k in range(n))


def test_interchange_round_trip(tmp_path):
    t = np.arange(200) * 1e-3
    chans = {"motor_pos": 1e-3 * np.sin(t * 20), "tip_pos": 0.9e-3 * np.sin(t * 20),
             "motor_force": 3 + np.cos(t), "temperature": 25 + t}
    units = {"motor_pos": "m", "tip_pos": "m", "motor_force": "N", "temperature": "C"}
    path = write_interchange(tmp_path / "r.csv", t, chans, units, {"load": "spring", "source": "test"})
    rec = read_interchange(path)
    assert rec.metadata == {"load": "spring", "source": "test"}
    assert rec.units == units
    for k, v in chans.items():
        np.testing.assert_allclose(rec.channels[k], v, rtol=1e-8, atol=1e-12)
    assert rec.n == 200 and rec.dt == pytest.approx(1e-3)


def test_units_convert_to_si(tmp_path):
    p = _csv(tmp_path, "t_s,motor_pos_deg,tip_pos_mm,extra_col\n" +
             "\n".join(f"{k * 0.01},{k},{2 * k},{k}" for k in range(30)))
    rec = read_interchange(p)
    assert rec.channels["motor_pos"][10] == pytest.approx(math.radians(10))
    assert rec.channels["tip_pos"][10] == pytest.approx(0.020)
    assert "extra_col" in rec.extra


@needs_mrdlab
def test_mrdlab_map_reads_all_runs():
    cmap = load_column_map(builtin_map("mrdlab"))
    assert {c.quantity for c in cmap.columns} == {"t", "motor_pos", "actuator_pos", "motor_force", "tip_pos",
                                                  "tip_force"}
    rec = read_recording(MRDLAB / "tool4_left_03.TXT", "mrdlab")
    assert rec.n == 20000 and rec.dt == pytest.approx(1e-3, rel=1e-6)   # seconds, not the header's ms
    # 30 deg-amplitude sine on the spindle: 0..60 deg; the jaw swings the other way through about 55 deg
    assert math.degrees(np.ptp(rec.channels["motor_pos"])) == pytest.approx(59, abs=2)
    assert math.degrees(np.ptp(rec.channels["tip_pos"])) == pytest.approx(57, abs=3)
    assert np.corrcoef(rec.channels["motor_pos"], rec.channels["tip_pos"])[0, 1] < -0.99
    # the Maxon motor behind its 35:1 gearbox turns with the spindle, scaled to the spindle's angle
    assert np.ptp(rec.channels["actuator_pos"]) == pytest.approx(np.ptp(rec.channels["motor_pos"]), rel=0.03)
    assert np.corrcoef(rec.channels["motor_pos"], rec.channels["actuator_pos"])[0, 1] > 0.99
    assert 0.05 < np.ptp(rec.channels["motor_force"]) < 0.2   # N m


@pytest.mark.parametrize("text, expect", [
    ("motor_pos_mm,tip_pos_mm\n1,2\n", "missing time column 't_s'"),
    ("t_s,motor_pos_mm,tip_pos_mm\n" + _good_rows(20) + "\n0.05,1,1\n" + "\n".join(
        f"{1 + k * 0.01},1,1" for k in range(30)), ":22: time is not increasing"),
    ("t_s,motor_pos_furlong,tip_pos_mm\n" + _good_rows(), "unknown unit 'furlong'"),
    ("t_s,motor_pos_mm\n" + "\n".join(f"{k * 0.01},{k}" for k in range(40)), "at least two recognised channels"),
    ("t_s,motor_pos_mm,tip_pos_mm\n" + _good_rows(25) + "\n" + "\n".join(
        f"{0.25 + k * 0.01},nan,1" for k in range(6)) + "\n" + "\n".join(
        f"{0.4 + k * 0.01},1,1" for k in range(20)), "column 'motor_pos' has a run of 6"),
    ("t_s,motor_pos_mm,tip_pos_mm\n" + _good_rows(25) + "\n0.3,abc,1\n", "column 'motor_pos_mm': 'abc' is not"),
])
def test_malformed_recordings_name_file_and_place(tmp_path, text, expect):
    p = _csv(tmp_path, text)
    with pytest.raises(InputError) as exc:
        read_interchange(p)
    msg = str(exc.value)
    assert str(p) in msg and expect in msg and "\n" not in msg


def test_short_nan_gap_is_interpolated(tmp_path):
    rows = [f"{k * 0.01},{k},{k}" for k in range(40)]
    rows[10] = "0.1,nan,10"
    rec = read_interchange(_csv(tmp_path, "t_s,motor_pos_mm,tip_pos_mm\n" + "\n".join(rows)))
    assert rec.channels["motor_pos"][10] == pytest.approx(0.010)


def test_cli_malformed_is_one_line_exit_2(tmp_path, capsys):
    p = _csv(tmp_path, "time,motor_pos_mm\n1,2\n")
    assert main(["diagnose", str(p)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("teleop: error:") and str(p) in err[0]


def test_bad_column_map(tmp_path):
    m = tmp_path / "m.toml"
    m.write_text('[format]\ndelimiter=","\n[[column]]\nindex=1\nquantity="t"\nunit="s"\nbogus=1\n')
    with pytest.raises(InputError, match="unknown key 'bogus'"):
        load_column_map(m)
