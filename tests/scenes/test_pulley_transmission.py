"""Seed 002's pulley chain as the simulated robot's cable transmission (scenes.pulley_transmission,
`sim://robot?plant=pulley`): its limits (frictionless, no bending rigidity, the lumped sheath), lost motion
that grows with the tension, per-reading and batch paths, parameters from TOML, and a session that enables."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from scenes.pulley_transmission import PulleyTransmission, PulleyTransmissionParams
from scenes.sim_robot import SimRobotParams, with_named_plant
from scenes.tendon_sheath import TendonSheathParams
from teleop.apps.cli import build_parser, main
from teleop.core.errors import InputError
from teleop.core.kernels import sheath as SH
from teleop.core.kinematics import poses2lengths
from teleop.loop.devices_by_url import open_device
from tests.scenes._readings import read_then_run

WRAP = 2.6  # rad, a capstan wrap of the robot's order (theta0 + a pose bend)


def _triangle(stroke=3e-3, n=600, legs=3):
    leg = np.linspace(0.0, stroke, n)
    parts = [leg if k % 2 == 0 else leg[::-1] for k in range(legs)]
    return np.concatenate([parts[0]] + [p[1:] for p in parts[1:]])


def _travel(params, x, T, wrap=WRAP, sheath_mu=0.056):
    tr = PulleyTransmission(params, 1, 0.0, sheath_mu)
    ones = np.ones((len(x), 1))
    return tr.travel(-x[:, None], T * ones, wrap * ones)


def _lost_motion(r, x):
    """Motor stroke minus tip stroke over the last leg [m]."""
    n = (len(x) + 2) // 3
    return float(np.ptp(x[-n:]) - np.ptp(r.x_tip[-n:, 0]))


def test_frictionless_without_bending_rigidity_transmits_one_to_one():
    p = PulleyTransmissionParams(mu=0.0, guide_mu=0.0, EI=0.0)
    x = _triangle()
    r = _travel(p, x, 4.0)
    for t in (r.t_fsr, r.t_fbg, r.t_motor):
        np.testing.assert_allclose(t, 4.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.x_tip[:, 0], x, rtol=0, atol=1e-15)   # no lost motion


def test_without_bending_rigidity_the_sliding_ratio_is_the_pure_capstan_ratio():
    p = PulleyTransmissionParams(EI=0.0, sensor_after=None)   # the FSR at the motor end
    chain = p.chain()
    mu_theta = 0.056 * WRAP + sum(q.mu * q.theta for q in chain.pulleys)
    x = _triangle()
    r = _travel(p, x, 3.0)
    v = np.gradient(x)
    n = (len(x) + 2) // 3
    pull = (v > 0) & (np.arange(len(x)) > 2 * n + 100)       # last leg, past the stick transition
    rel = (v < 0) & (np.arange(len(x)) > n + 100) & (np.arange(len(x)) < 2 * n)
    np.testing.assert_allclose(r.t_motor[pull, 0] / 3.0, math.exp(mu_theta), rtol=1e-12)
    np.testing.assert_allclose(r.t_motor[rel, 0] / 3.0, math.exp(-mu_theta), rtol=1e-12)
    np.testing.assert_allclose(r.t_fsr, r.t_motor, rtol=1e-14)


def test_the_guide_alone_without_bending_rigidity_is_the_lumped_sheath_sample_for_sample():
    sheath = SH.Sheath()
    p = PulleyTransmissionParams(layout=(), EI=0.0, stick_k=sheath.stick_k)
    x = _triangle(n=300) + 1e-3 * np.sin(np.linspace(0, 20, 898))
    T = 2.85 + 0.5 * np.sin(np.linspace(0, 7, len(x)))
    tr = PulleyTransmission(p, 1, 0.0, sheath.mu)
    r = tr.travel(-x[:, None], T[:, None], np.full((len(x), 1), WRAP))
    ref = SH.motor_force_run(x, T, np.full(len(x), WRAP), sheath.constants(), SH.new_state(1), 0, np.empty(len(x)))
    np.testing.assert_allclose(r.t_fsr[:, 0], ref, rtol=0, atol=1e-12)


def test_lost_motion_grows_with_the_tension_and_with_bending_rigidity():
    x = _triangle()
    lost = [_lost_motion(_travel(PulleyTransmissionParams(), x, T), x) for T in (2.0, 5.0, 10.0)]
    assert 0 < lost[0] < lost[1] < lost[2]
    assert _lost_motion(_travel(PulleyTransmissionParams(EI=0.0), x, 5.0), x) < lost[1]
    # a stiffer cable loses less motion
    assert _lost_motion(_travel(PulleyTransmissionParams(EA=4 * 9.5e3), x, 5.0), x) < lost[1]


def test_the_fsr_sits_after_the_guide_the_fbg_on_the_tip_segment():
    x = _triangle()
    r = _travel(PulleyTransmissionParams(), x, 3.0)
    np.testing.assert_array_equal(r.t_fbg, 3.0)
    v = np.gradient(x)
    n = (len(x) + 2) // 3
    pull = (v > 0) & (np.arange(len(x)) > 2 * n + 100)
    assert np.all(r.t_motor[pull] > r.t_fsr[pull]) and np.all(r.t_fsr[pull] > 3.0)


def test_reading_by_reading_is_the_batch():
    p = PulleyTransmissionParams()
    rng = np.random.default_rng(3)
    m, n = 400, 6
    X = 0.03 + np.cumsum(rng.normal(0, 2e-5, (m, n)), axis=0)
    T = 2.85 + rng.normal(0, 0.3, (m, n))
    TH = WRAP + rng.normal(0, 0.05, (m, n))
    a = PulleyTransmission(p, n, 0.03, 0.056)
    rows = [a.step(X[k], T[k], TH[k]) + (a.x_tip.copy(),) for k in range(m)]
    b = PulleyTransmission(p, n, 0.03, 0.056).travel(X, T, TH)
    for got, want in zip(zip(*rows), (b.t_fsr, b.t_fbg, b.t_motor, b.x_tip)):
        np.testing.assert_allclose(np.array(got), want, rtol=0, atol=1e-12)


def test_the_robot_batch_path_reads_what_the_readings_read():
    q = np.zeros((300, 6))
    q[:, 2] = np.concatenate([np.linspace(0.0, 8e-3, 150), np.linspace(8e-3, 0.0, 150)])
    rows, trace = read_then_run(SimRobotParams(pulley=PulleyTransmissionParams()), 4, lambda g: poses2lengths(q, g))
    assert all(np.all(x["t_motor"] >= 0) for _, x in rows)   # a releasing cable may go slack at the motor
    assert np.allclose(trace.t_fsr, np.array([x["t_fsr"] for _, x in rows]), atol=1e-9)
    assert np.array_equal(trace.counts, np.array([c for c, _ in rows]))
    assert np.ptp(trace.t_fsr) > 0.3   # the contact and the chain's friction move the FSR tension


def test_toml_url_and_their_errors(tmp_path):
    toml = tmp_path / "pulley.toml"
    toml.write_text("[pulley_transmission]\nmu = 0.08\nEI_N_m2 = 5e-7\n"
                    "layout_m = [[0, 0, 0], [-0.01, 0.004, 0.002], [-0.3, 0.03, 0]]\n")
    robot = open_device(f"sim://robot?plant=pulley&cable_params={toml}")
    pp = robot.params.pulley
    assert pp.mu == 0.08 and pp.EI == 5e-7 and len(pp.chain().pulleys) == 1
    assert robot.params.cable is None and robot.params.plant is None
    assert open_device("sim://robot?plant=pulley").params.pulley == PulleyTransmissionParams()
    assert with_named_plant(SimRobotParams(), "distributed", 0).pulley is None
    bad = tmp_path / "bad.toml"
    for text, match in (("[pulley_transmission]\nEI = 1e-6\n", "unknown key"),
                        ("[pulley_transmission]\nEA_N = -3\n", "EA"),
                        ("[pulley_transmission]\nlayout_m = [[0, 0]]\n", "layout_m"),
                        ("[pulley_transmission]\nlayout_m = [[0, 0, 0], [0.0001, 0, 0.002], [0.1, 0, 0]]\n",
                         "no free cable"),
                        ("[tendon_sheath]\nmu_c = 0.05\n", "no \\[pulley_transmission\\]")):
        bad.write_text(text)
        with pytest.raises(InputError, match=match):
            open_device(f"sim://robot?plant=pulley&cable_params={bad}")
    with pytest.raises(InputError, match="plant of its own"):
        SimRobotParams(pulley=PulleyTransmissionParams(), cable=TendonSheathParams())
    with pytest.raises(InputError, match="sensor_after"):
        PulleyTransmissionParams(sensor_after=9)


@pytest.mark.parametrize("argv", [
    ["palpate", "--test", "z", "--plant", "pulley"],
    ["bench", "sim", "--plant", "pulley"],
    ["blind-test", "--plant", "pulley"],
    ["bench", "feedforward", "--plant", "pulley"],
])
def test_plant_pulley_is_accepted(argv):
    assert build_parser().parse_args(argv).plant == "pulley"


def test_a_short_session_on_the_pulley_plant_enables(tmp_path):
    js = tmp_path / "s.json"
    assert main(["session", "--robot", "sim://robot?plant=pulley", "--seconds", "0.5", "--sim-clock",
                 "--robot-inline", "--json", str(js)]) == 0
    out = json.loads(js.read_text())
    states = [e["dst"] for e in out["events"]]
    assert "ENABLED" in states and "FAULT" not in states
