"""A session recording (MCAP, teleop.io.recording) exported to the interchange CSV and read back."""

import numpy as np
import pytest

from teleop.io.recording_io import read_interchange
from teleop.io.session_export import cable_columns, export_session
from teleop.io.recording import INT, Layout, SessionWriter, Signal


def test_session_export_round_trip(tmp_path):
    layout = Layout((Signal("/loop", "tick", 1, INT), Signal("/loop", "t"),
                     Signal("/robot/measured", "commanded_lengths", 6), Signal("/estimation", "tensions", 6)))
    t = np.arange(300) * 1e-3
    lengths = 0.05 + 2e-3 * np.sin(2 * np.pi * 2 * t)[:, None] * np.arange(1, 7)
    tensions = 3 + np.cos(2 * np.pi * t)[:, None] * np.arange(1, 7)
    path = tmp_path / "s.mcap"
    with open(path, "wb") as fh:
        w = SessionWriter(fh, layout, {"config": "test"}, 0)
        for k in range(t.size):
            w.write_row(np.concatenate([[k, t[k]], lengths[k], tensions[k]]))
        w.finish({"drops": 0})
    out = export_session(path, tmp_path / "s.csv", cable_columns(2), {"load": "external"})
    rec = read_interchange(out)
    assert rec.metadata["load"] == "external"
    np.testing.assert_allclose(rec.t, t, atol=1e-9)
    np.testing.assert_allclose(rec.channels["motor_pos"], lengths[:, 2], atol=1e-9)
    np.testing.assert_allclose(rec.channels["motor_force"], tensions[:, 2], rtol=1e-8)
