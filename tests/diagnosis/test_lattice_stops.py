"""A drive read on an encoder's lattice that pauses holds one reading for many times the time it took per count
on either side (links.lattice_stops): its rate is zero there, where the smoothed drive's rate moved through the
pause (half a smoothing width into each end, round-off with a sign between) and the catalogue's rate laws read
motion: a Stribeck friction's breakaway peak shows only on those slow samples, so the generator's Stribeck on a
strokes drive was named a Coulomb (issue 26 d2: the naming bench's generator case 4, seed 1)."""

import numpy as np

from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import GenConfig, case_plan, make_case
from teleop.diagnosis.links import lattice_stops
from teleop.io.recording_io import read_interchange

Q = 1e-6     # encoder count [m]


def test_a_sine_on_a_lattice_has_no_stop():
    t = np.arange(20000) / 1000.0
    for f in (0.1, 0.5, 2.0):
        x = np.round(5e-3 * np.sin(2 * np.pi * f * t) / Q) * Q
        assert not lattice_stops(x).any(), f


def test_the_pauses_of_strokes_on_a_lattice_are_stops():
    # ramps of 4 mm at 10 mm/s, each followed by a 150 ms pause, alternating direction
    dt, seg = 1e-3, []
    pos = 0.0
    for k in range(8):
        ramp = pos + (1 if k % 2 == 0 else -1) * 1e-2 * np.arange(1, 401) * dt
        seg += [ramp, np.full(150, ramp[-1])]
        pos = ramp[-1]
    seg.append(pos + 1e-2 * np.arange(1, 401) * dt)      # and a last ramp
    x = np.round(np.concatenate(seg) / Q) * Q
    stop = lattice_stops(x)
    paused = np.r_[np.concatenate([np.r_[np.zeros(400, bool), np.ones(150, bool)] for _ in range(8)]),
                   np.zeros(400, bool)]
    arrived = np.r_[paused[1:], False]     # the ramp's last sample already holds the pause's reading
    assert stop[paused].mean() > 0.9 and not stop[~(paused | arrived)].any()


def test_a_stribeck_on_strokes_is_named_stribeck(tmp_path):
    effect, setup = case_plan(5)[4]
    assert effect == "stribeck_friction"
    case = make_case(4, effect, setup, 1, GenConfig(None, 10.0, 1.0, "literature"))
    assert case.trajectory == "strokes"
    doc = diagnose(read_interchange(case.write(tmp_path / "c.csv"))).as_dict()
    assert doc["findings"] and doc["findings"][0]["effect"] == "stribeck_friction", doc["findings"]
