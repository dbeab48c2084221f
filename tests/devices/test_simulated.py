"""sim:// stylus: deterministic by seed, the operator feels the commanded force, scripts and buttons."""

import numpy as np
import pytest

from teleop.loop.devices_by_url import open_device
from devices.simulated import OperatorParams, Script, SimulatedStylus
from teleop.core.errors import InputError


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def trace(dev, clock, n, force=None, dt=1e-3):
    out = []
    with dev:
        for k in range(n):
            clock.t = k * dt
            s = dev.read()
            out.append(s.measured_cp)
            if force is not None:
                dev.servo_cf(force)
    return np.array(out)


def test_deterministic_by_seed_whatever_the_read_timing():
    c1, c2, c3 = Clock(), Clock(), Clock()
    a = trace(SimulatedStylus(Script(kind="sine"), seed=5, clock=c1), c1, 400)
    b = trace(SimulatedStylus(Script(kind="sine"), seed=5, clock=c2), c2, 400)
    assert np.array_equal(a, b)
    c = trace(SimulatedStylus(Script(kind="sine"), seed=6, clock=c3), c3, 400)
    assert not np.array_equal(a, c)
    # reading every 4 ms instead of every 1 ms gives the same states at the common times
    c4 = Clock()
    d = trace(SimulatedStylus(Script(kind="sine"), seed=5, clock=c4), c4, 100, dt=4e-3)
    assert np.allclose(d[1:], a[4::4][:99], atol=0, rtol=0)


def test_operator_feels_the_force_spring_equilibrium():
    op = OperatorParams(k=200.0, tremor=0.0)
    clock = Clock()
    p = trace(SimulatedStylus(Script(kind="hold"), op, clock=clock), clock, 3000, force=np.array([0.0, 0.0, 0.5]))
    assert p[-1][2] == pytest.approx(0.5 / 200.0, rel=1e-3)  # F = k dx: pushed 2.5 mm off target


def test_pokes_script_and_buttons():
    s = Script(kind="pokes", axis=(0.0, 0.0, -1.0), amplitude=0.01, period=1.0, duty=0.5,
               clutch=((0.2, 0.3),), absent=((0.8, 0.9),))
    assert np.allclose(s.target(0.25), [0, 0, -0.01]) and np.allclose(s.target(0.75), 0)
    assert s.buttons(0.25) == (3, True) and s.buttons(0.85) == (0, False) and s.buttons(0.5) == (1, True)


def test_recorded_script_from_csv(tmp_path):
    f = tmp_path / "path.csv"
    f.write_text("t_s,x_m,y_m,z_m\n0,0,0,0\n1,0.01,0,0\n")
    dev = open_device(f"sim://?script=recorded&file={f}")
    assert np.allclose(dev.script.target(0.5), [0.005, 0, 0])
    bad = tmp_path / "bad.csv"
    bad.write_text("t,x\n0,1\n")
    with pytest.raises(InputError, match="bad.csv: expected CSV columns"):
        open_device(f"sim://?script=recorded&file={bad}")


@pytest.mark.parametrize("url, msg", [("sim://?script=dance", "unknown"), ("sim://?amp_mm=abc", "number"),
                                      ("sim://?clutch=3-1", "t1 > t0"), ("sim://?axis=w", "axis"),
                                      ("sim://?bogus=1", "unknown option"), ("sim://?spec=phantom", "spec")])
def test_bad_url_options(url, msg):
    with pytest.raises(InputError, match=msg):
        open_device(url)


def test_replaced_script_and_operator_take_effect_mid_run():
    """The blind-test rig swaps scripts (and tests swap operators) on an open stylus: the hand follows the
    new target from the next read, as a fresh stylus with that script would from the same state."""
    clock = Clock()
    dev = SimulatedStylus(Script(kind="hold"), OperatorParams(tremor=0.0), clock=clock)
    with dev:
        for k in range(100):
            clock.t = k * 1e-3
            dev.read()
        assert np.allclose(dev.p, 0.0)
        dev.script = Script(kind="hold", center=(0.0, 0.0, -0.01))
        for k in range(100, 1100):
            clock.t = k * 1e-3
            dev.read()
        assert dev.p[2] == pytest.approx(-0.01, abs=1e-4)  # settled on the new target (k = 150 N/m)
        dev.operator = OperatorParams(k=1500.0, b=30.0, tremor=0.0)
        dev.servo_cf([0.0, 0.0, 1.5])
        for k in range(1100, 2100):
            clock.t = k * 1e-3
            dev.read()
            dev.servo_cf([0.0, 0.0, 1.5])
        assert dev.p[2] == pytest.approx(-0.01 + 1.5 / 1500.0, abs=1e-4)  # the stiffer hand yields F / k
