"""`teleop bench pulley`: seed 002's tension and displacement transmission on closed-form limits, and the
pulley layout's wrap angles."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from teleop.apps.bench.pulley import compute, displacement_transmission, figure, instrument, tension_transmission
from teleop.apps.cli import main
from teleop.core.physics.pulley import Pulley, PulleyChain, chain_from_layout
from tests.apps.test_figures import check_figure


def chain(mus, thetas, EI=0.0, EA=2e3, R=0.002, d=0.1):
    return PulleyChain(tuple(Pulley(theta=t, R=R, mu=m, d=d) for m, t in zip(mus, thetas)), EI=EI, EA=EA, d_tip=d)


def test_lossless_chain_transmits_tension_and_displacement_one_to_one():
    ch = chain([0.0, 0.0, 0.0], [1.0, 2.0, 0.5])
    tt = tension_transmission(ch, [1.0, 5.0, 20.0])
    np.testing.assert_allclose(tt["pulling"], 1.0)
    np.testing.assert_allclose(tt["releasing"], 1.0)
    np.testing.assert_allclose(tt["cumulative"], 1.0)
    dt = displacement_transmission(ch, 10.0, stroke=0.004)
    assert dt["lost_motion_m"] == pytest.approx(0.0, abs=1e-15)
    assert dt["ratio"] == pytest.approx(1.0, abs=1e-12)


def test_per_pulley_friction_gives_the_product_of_capstan_factors():
    mus, thetas = [0.1, 0.2, 0.05], [1.2, 0.7, 3.0]
    ch = chain(mus, thetas)
    K = [math.exp(m * t) for m, t in zip(mus, thetas)]
    tt = tension_transmission(ch, [3.0, 12.0])
    np.testing.assert_allclose(tt["pulling"], 1.0 / np.prod(K), rtol=1e-12)
    np.testing.assert_allclose(tt["releasing"], 1.0 / np.prod(K), rtol=1e-12)
    np.testing.assert_allclose(tt["cumulative"], 1.0 / np.cumprod(K), rtol=1e-12)


def test_bending_rigidity_loses_a_load_independent_tension_per_pulley():
    R, EI = 0.002, 2e-6
    ch = chain([0.0, 0.0], [1.0, 1.0], EI=EI, R=R)
    T = np.array([2.0, 10.0])
    np.testing.assert_allclose(tension_transmission(ch, T)["pulling"], T / (T + 2 * EI / R ** 2))


def test_more_wrap_loses_more_tension_and_more_motion():
    small, large = chain([0.1, 0.1], [0.5, 0.5], EI=1e-6), chain([0.1, 0.1], [1.5, 1.5], EI=1e-6)
    ts, tl = tension_transmission(small, [10.0]), tension_transmission(large, [10.0])
    assert tl["pulling"][0] < ts["pulling"][0] < 1.0
    assert tl["releasing"][0] < ts["releasing"][0] < 1.0
    ds, dl = displacement_transmission(small, 10.0, 0.004), displacement_transmission(large, 10.0, 0.004)
    assert 0.0 < ds["lost_motion_m"] < dl["lost_motion_m"]
    assert dl["ratio"] < ds["ratio"] < 1.0
    # past the transition the tip follows the motor one to one: the stroke lost is the lost motion
    assert dl["ratio"] == pytest.approx(1.0 - dl["lost_motion_m"] / 0.004, rel=1e-6)


def test_layout_sets_wrap_angles_and_spans():
    # a U-turn round a 1 mm pulley: the cable turns by pi; a straight pass: no wrap
    u = chain_from_layout([(0.0, 0.0, 0.0), (0.01, 0.001, 0.001), (0.0, 0.002, 0.0)], 0.1)
    assert u.pulleys[0].theta == pytest.approx(math.pi, abs=1e-3)
    assert u.pulleys[0].d == pytest.approx(0.01, rel=1e-3) and u.d_tip == pytest.approx(0.01, rel=1e-3)
    s = chain_from_layout([(0.0, 0.0, 0.0), (0.01, 0.001, 0.001), (0.02, 0.0, 0.0)], 0.1)
    assert s.pulleys[0].theta == pytest.approx(0.0, abs=1e-9)
    # over the top of the same pulley: the cable rises to its tangent and falls again, turning by
    # 2 (atan(1/10) + asin(1 / |c|)) with |c| the centre's distance in mm
    o = chain_from_layout([(0.0, 0.0, 0.0), (0.01, 0.001, -0.001), (0.02, 0.0, 0.0)], 0.1)
    turn = 2 * (math.atan(0.1) + math.asin(0.001 / math.hypot(0.01, 0.001)))
    assert o.pulleys[0].theta == pytest.approx(turn, rel=1e-9)
    with pytest.raises(ValueError):
        chain_from_layout([(0.0, 0.0, 0.0), (0.0005, 0.0, 0.001), (0.02, 0.0, 0.0)], 0.1)


def test_instrument_bending_costs_tension_beyond_the_capstan_law():
    with_ei, capstan = instrument(), instrument(EI=0.0)
    assert tension_transmission(with_ei, [10.0])["pulling"][0] < tension_transmission(capstan, [10.0])["pulling"][0]


def test_command_writes_json_and_png(tmp_path, capsys):
    js, png = tmp_path / "p.json", tmp_path / "p.png"
    assert main(["bench", "pulley", "--seed", "3", "--json", str(js), "--plot", str(png)]) == 0
    res = json.loads(js.read_text())
    assert res["spread"]["seed"] == 3 and set(res["models"]) == {"bending", "capstan"}
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert "tension ratio" in capsys.readouterr().out


def test_bad_output_is_one_line_exit_2(tmp_path, capsys):
    assert main(["bench", "pulley", "--plot", str(tmp_path / "p.txt")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not (tmp_path / "p.txt").exists()


def test_figure_keeps_the_house_rules():
    check_figure(figure(compute(0)), "seed 002", "tension transmission", "displacement transmission")
