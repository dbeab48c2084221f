"""The single-cable bench over the literature's ranges (scenes.cable_rig.LITERATURE): the draws stay within
the ranges and reach both ends of the categorical ones, the columns drawn always show the effect, the drive
keeps within its frequency and speed limits, a recording is reproducible from its seed, and the sheath's
stick transition spans Kaneko's dead zone of the drawn cable."""

import math

import numpy as np
import pytest

from scenes.cable_rig import (COLUMNS, LITERATURE, OPTIONAL_COLUMNS, draw_columns, draw_setup, observable, rig_effects,
                              simulate, trajectory)
from scenes.tendon_sheath import dead_zone_uniform


def test_setup_draws_stay_within_the_literature_ranges():
    draws = [draw_setup(np.random.default_rng([3, i]), LITERATURE) for i in range(200)]
    for d in draws:
        assert LITERATURE.mu[0] <= d["mu"] <= LITERATURE.mu[1]
        assert math.radians(LITERATURE.bend_deg[0]) <= d["bend_rad"] <= math.radians(LITERATURE.bend_deg[1])
        assert 1.0 < d["capstan_ratio"] <= LITERATURE.max_capstan_ratio
        assert LITERATURE.fs_hz[0] <= d["fs_hz"] <= LITERATURE.fs_hz[1]
        assert LITERATURE.noise_fs[0] <= d["noise_fs"] <= LITERATURE.noise_fs[1]
        ea = dict((c, r) for c, r, _ in LITERATURE.cables)[d["cable"]]
        assert ea[0] <= d["EA_N"] <= ea[1]
    assert {d["cable"] for d in draws} == {c for c, _, _ in LITERATURE.cables}
    assert {d["motor_encoder"] for d in draws} == {"exact", "noisy"}
    assert max(d["capstan_ratio"] for d in draws) > 4.0          # the high band is reached
    assert max(math.degrees(d["bend_rad"]) for d in draws) > 450.0


@pytest.mark.parametrize("load", ["spring", "external"])
def test_drawn_columns_show_the_effect_and_sensors_come_and_go(load):
    seen = set()
    for effect in rig_effects() + ("none",):
        if effect != "none" and not observable(effect, COLUMNS, load):
            with pytest.raises(ValueError, match=effect):
                draw_columns(np.random.default_rng(0), LITERATURE, (effect,), load)
            continue
        for i in range(6):
            cols = draw_columns(np.random.default_rng([i, 5]), LITERATURE, (effect,), load)
            assert cols[0] == "motor_pos_mm"
            if effect == "none":
                assert any(observable(e, cols, load) for e in rig_effects())
            else:
                assert observable(effect, cols, load), (effect, cols)
            seen.add(len(cols))
    assert min(seen) < 1 + len(OPTIONAL_COLUMNS)       # some recordings lack a sensor


def test_drive_keeps_to_its_frequency_and_speed():
    fs = 1000.0
    t = np.arange(int(40 * fs)) / fs
    for i in range(12):
        kind, x = trajectory(np.random.default_rng([i, 9]), t, fs, LITERATURE)
        v = np.abs(np.gradient(x, t))
        assert float(v.max()) <= 1.05 * LITERATURE.max_speed, kind
        assert 2.9e-3 <= float(np.ptp(x)) / 2 <= 10.1e-3


def test_literature_recording_is_reproducible_and_records_its_setup():
    a = simulate([4, 2], ("backlash",), load="spring", fs_hz=None, duration_s=3.0, ranges=LITERATURE)
    b = simulate([4, 2], ("backlash",), load="spring", fs_hz=None, duration_s=3.0, ranges=LITERATURE)
    assert a.csv == b.csv
    s = a.setup
    assert LITERATURE.fs_hz[0] <= s["fs_hz"] <= LITERATURE.fs_hz[1]
    n = len(a.csv.strip().splitlines()) - 3                  # two metadata lines and the header
    assert n == int(3.0 * s["fs_hz"])
    assert s["capstan_ratio"] == pytest.approx(math.exp(s["mu"] * s["theta_mean"]))


def test_stick_transition_spans_the_cables_dead_zone():
    """A constant tip load, no sensor gains or noise: after a reversal the motor force crosses from the
    pulling to the releasing capstan branch over the motor travel of Kaneko's dead zone."""
    fs, dur = 1000.0, 6.0
    t = np.arange(int(dur * fs)) / fs
    probe = simulate([7, 1], ("none",), load="external", fs_hz=fs, duration_s=dur, ranges=LITERATURE)
    s = probe.setup
    L0 = 10.0
    dz = dead_zone_uniform(L0, s["EA_N"], s["length_m"], s["mu"] * s["theta_mean"])
    A = 3 * dz
    x = A * np.sin(2 * np.pi * 0.25 * t)
    rig = simulate([7, 1], ("none",), load="external", fs_hz=fs, duration_s=dur, noise=0.0, ranges=LITERATURE,
                   given={"x": x, "tip_force": np.full(t.shape, L0), "ideal_sensors": True,
                          "theta": s["theta_mean"], "mu": s["mu"]})
    rows = np.array([[float(v) for v in line.split(",")] for line in rig.csv.strip().splitlines()[3:]])
    head = rig.csv.strip().splitlines()[2].split(",")
    xm, fm = rows[:, head.index("motor_pos_mm")] * 1e-3, rows[:, head.index("motor_force_N")]
    top, bottom = L0 * s["capstan_ratio"], L0 / s["capstan_ratio"]
    k = int(np.argmax(xm))                                    # the first reversal (pulling -> releasing)
    after = np.arange(k, int(k + 0.5 * fs * 2))
    on_branch = after[np.abs(fm[after] - bottom) < 1e-6 * top]
    travel = xm[k] - xm[on_branch[0]]
    assert travel == pytest.approx(dz, rel=0.02)
