"""Seed 002's model-based position compensation (teleop.core.control.feedforward.pulley_precompensate) and
`teleop bench feedforward --plant distributed --single-cable`."""

from __future__ import annotations

import json

import numpy as np

from teleop.apps.bench.feedforward import TEST_LOADS_N, bench_single_cable, single_cable_figure
from teleop.apps.cli import main
from teleop.core.control.feedforward import pulley_precompensate
from teleop.core.physics.pulley import Pulley, PulleyChain, pulley_elongation, pulley_motor_force
from tests.apps.test_figures import check_figure


def _chain(mu):
    return PulleyChain((Pulley(1.2, 0.002, mu, 0.3), Pulley(0.8, 0.002, mu, 0.3)), EI=1e-7, EA=3e3, d_tip=0.3)


def _tip(x, T, chain):
    F = pulley_motor_force(x, np.full(x.shape, T), chain, k=1e9)
    return x - pulley_elongation(F, np.full(x.shape, T), chain)


def test_on_its_own_chain_the_tip_follows_the_target():
    chain, T = _chain(0.1), 6.0
    y = 2e-3 * np.sin(np.linspace(0.0, 4 * np.pi, 4001))
    plain_err = _tip(y, T, chain) - y
    err = _tip(pulley_precompensate(y, T, chain), T, chain) - y
    assert np.abs(err[200:]).max() < 1e-3 * np.abs(plain_err[200:]).max()


def test_without_friction_it_only_adds_the_static_stretch():
    chain = PulleyChain((Pulley(1.0, 1.0, 0.0, 0.5),), EA=5e3, d_tip=0.5)
    y = np.linspace(0.0, 1e-3, 50)
    np.testing.assert_allclose(pulley_precompensate(y, 5.0, chain), y + 5.0 * 1.0 / 5e3, rtol=0, atol=1e-15)


def test_on_the_distributed_cable_it_beats_the_plain_inverse_away_from_the_calibration_load():
    out, _ = bench_single_cable()
    r = out["tip_error_rms_mm"]
    for i, load in enumerate(TEST_LOADS_N):
        assert r["pulley"][i] < r["none"][i]
        if load != out["calibration"]["load_N"]:
            assert r["pulley"][i] < r["plain"][i]


def test_command_writes_json_and_a_figure_that_keeps_the_rules(tmp_path):
    js, png = tmp_path / "f.json", tmp_path / "f.png"
    assert main(["bench", "feedforward", "--plant", "distributed", "--single-cable", "--json", str(js),
                 "--plot", str(png)]) == 0
    assert json.loads(js.read_text())["mode"] == "single_cable"
    check_figure(single_cable_figure(*bench_single_cable()), "single-cable", "plant distributed")


def test_single_cable_needs_the_distributed_plant(tmp_path, capsys):
    assert main(["bench", "feedforward", "--single-cable", "--json", str(tmp_path / "f.json")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not (tmp_path / "f.json").exists()
