"""The rich plant (scenes.rich_plant): effects the estimators do not model, on top of the simulated robot's
own physics. Each effect adds exactly its catalogue formula, the batch and per-reading paths agree, and the
per-cable draw is seeded."""

import dataclasses
import math

import numpy as np
import pytest

from scenes.rich_plant import EFFECTS, RichPlantParams, draw_cables, plant_params, with_plant
from scenes.sim_robot import SimRobot, SimRobotParams, home_pose
from teleop.core.errors import InputError
from teleop.core.kinematics import poses2lengths
from teleop.core.physics import dahl, get_effect, stribeck


def _lengths(n=300, amp=1e-3, cycles=2):
    g = SimRobotParams().geometry
    poses = np.repeat(home_pose()[None], n, axis=0)
    poses[:, 2] += amp * np.sin(np.linspace(0, 2 * np.pi * cycles, n))  # along z and back: both directions
    return poses2lengths(poses, g)


def _run(plant, L, seed=2, split=None):
    with SimRobot(params=with_plant(SimRobotParams(), plant), seed=seed) as robot:
        if split is None:
            return robot.run(L)
        a, b = robot.run(L[:split]), robot.run(L[split:])
    return a, b


def test_batch_and_per_reading_paths_agree():
    L = _lengths(240)
    plant = RichPlantParams(seed=3)
    a, b = _run(plant, L, split=101)
    with SimRobot(params=with_plant(SimRobotParams(), plant), seed=2) as robot:
        reads = []
        for row in L:
            robot.command_lengths(row)
            reads.append(robot.read())
    t_read = np.array([r.extras["t_fsr"] for r in reads])
    assert np.allclose(np.vstack([a.t_fsr, b.t_fsr]), t_read, rtol=0, atol=1e-9)
    assert np.array_equal(np.vstack([a.counts, b.counts]), np.array([r.fsr_counts for r in reads]))


def test_matched_plant_is_the_default_robot():
    L = _lengths(80)
    plain = _run(None, L)
    assert plant_params("matched", 1) is None
    again = _run(plant_params("matched", 1), L)
    assert np.array_equal(plain.counts, again.counts)


@pytest.mark.parametrize("effect", ["stribeck_friction", "dahl_hysteresis", "thermal_drift_time"])
def test_each_additive_effect_adds_its_catalogue_formula(effect):
    L = _lengths(200)
    plant = RichPlantParams(effects=(effect,), seed=4, spread=0.0)
    rich, plain = _run(plant, L), _run(None, L)
    x = -L
    t = plain.t
    p = plant.nominal()[effect]
    extra = rich.t_fsr - plain.t_fsr
    for i in range(6):
        if effect == "stribeck_friction":
            v = np.concatenate([[0.0], np.diff(x[:, i]) / np.diff(t)])
            want = stribeck(v, p["Fc"], p["Fs"], p["vs"])
        elif effect == "dahl_hysteresis":
            want = dahl(x[:, i], p["sigma"], p["Fc"])
        else:
            want = p["rate"] * t
        assert np.allclose(extra[:, i], want, rtol=0, atol=1e-12)
        assert np.abs(want).max() > 0                                   # the effect is not nil


def test_pulley_widens_the_band():
    L = _lengths(300)
    plain = _run(None, L)
    pul = _run(RichPlantParams(effects=("pulley_friction",), seed=1, spread=0.0), L)
    # the guide pulley multiplies the band by exp(+-mu wrap) and adds its bending loss: hauling in reads more
    pulling = np.diff(-L[:, 0]) > 0
    d = (pul.t_fsr - plain.t_fsr)[1:, 0]
    assert d[pulling][20:].mean() > 0 > d[~pulling][20:].mean()


def test_backlash_is_the_robots_motor_play_and_the_cable_friction_waits_for_it():
    w = RichPlantParams().backlash_width
    plant = RichPlantParams(effects=("backlash",), seed=1, spread=0.0)
    sim = with_plant(SimRobotParams(), plant)
    assert sim.backlash == w and sim.plant is plant
    assert with_plant(SimRobotParams(), RichPlantParams(effects=("stribeck_friction",))).backlash == 0.0
    # out along z, then back by less than half the play: the cables stay put, and so does their friction
    L = _lengths(200, amp=1e-3, cycles=0.25)
    back = L[-1] + (L[-2] - L[-1]) * np.linspace(0, 0.2 * w / np.abs(L[-2] - L[-1]).max(), 40)[:, None]
    Ls = np.vstack([L, back])
    with SimRobot(params=sim, seed=2) as robot:
        rich = robot.run(Ls)
    with SimRobot(params=dataclasses.replace(SimRobotParams(), backlash=w), seed=2) as robot:
        motor = robot.run(Ls)                  # the play alone: the capstan follows the motor, not the cable
    assert np.abs(np.diff(rich.t_fsr[-40:], axis=0)).max() < 1e-9
    assert np.abs(np.diff(motor.t_fsr[-40:], axis=0)).max() > 1e-3


def test_cable_draw_is_seeded_and_physical():
    p = RichPlantParams(seed=7)
    a, b = draw_cables(p, 6), draw_cables(p, 6)
    assert a == b
    assert draw_cables(dataclasses.replace(p, seed=8), 6) != a
    nominal = draw_cables(dataclasses.replace(p, spread=0.0), 6)
    assert all(c == {e: get_effect(e).check(v) for e, v in p.nominal().items() if e != "backlash"} for c in nominal)
    for cable in a:
        assert set(cable) == set(EFFECTS) - {"backlash"}     # the robot's own play, one width
        assert cable["stribeck_friction"]["Fs"] >= cable["stribeck_friction"]["Fc"]
        assert cable["pulley_friction"]["wrap"] == p.pulley_wrap        # geometry, not scatter
        for eff, vals in cable.items():
            for spec in get_effect(eff).params:
                assert spec.lower <= vals[spec.name] <= spec.upper
    ratios = [c["dahl_hysteresis"]["Fc"] / p.dahl_Fc for c in a]
    assert len(set(ratios)) == 6 and all(math.exp(-4 * p.spread) < r < math.exp(4 * p.spread) for r in ratios)


def test_bad_plant_options_say_what_was_expected():
    with pytest.raises(InputError, match="unknown plant 'fancy'"):
        plant_params("fancy", 1)
    with pytest.raises(InputError, match="unknown effect 'gremlins'"):
        RichPlantParams(effects=("gremlins",))
    with pytest.raises(InputError, match="spread"):
        RichPlantParams(spread=-1.0)


def test_url_option_switches_the_rich_plant_on():
    from teleop.loop.devices_by_url import open_device

    with open_device("sim://robot?plant=rich&seed=3") as robot:
        assert robot.params.plant == RichPlantParams(seed=3)
        assert robot.params.backlash == RichPlantParams().backlash_width
        robot.read()
    with open_device("sim://robot?plant=rich&seed=3&backlash_mm=0") as robot:
        assert robot.params.backlash == 0.0 and robot.params.plant is not None
    with open_device("sim://robot?plant=matched") as robot:
        assert robot.params.plant is None
    with pytest.raises(InputError, match="unknown plant 'fancy'"):
        open_device("sim://robot?plant=fancy")
