"""Backlash's dead zone growing with the tension (Kaneko's tendon-sheath play under a spring): the kernel's
closed form, and the diagnosis on recordings of a test-side quasi-static distributed cable that shares no
code with the catalogue (its tension profile along the sheath clamped from the motor end, the tip moving
only once the turn-over of the profile reaches it)."""

import math

import numpy as np
import pytest

from teleop.core.physics import Signals, get_effect
from teleop.core.physics.backlash import backlash
from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange, write_interchange
from tests._signals import multisine


def test_tension_zero_is_the_general_play_and_plain_play():
    rng = np.random.default_rng(0)
    t = np.arange(4000) / 500.0
    x = multisine(rng, t, 0.01, 3, 0.1, 0.6)
    eff = get_effect("backlash")
    assert np.array_equal(eff.apply(Signals(t=t, x=x), {"width": 2e-3}), backlash(x, 2e-3))
    general = {"width": 2e-3, "elastic": 0.2, "tail": 0.1, "grow": 3.0, "start": 0.3}
    y0 = eff.apply(Signals(t=t, x=x), general)
    y1 = eff.apply(Signals(t=t, x=x), {**general, "tension": 1e-9})
    assert np.max(np.abs(y1 - y0)) < 1e-12


@pytest.mark.parametrize("tension", [150.0, -80.0])
def test_dead_zone_grows_linearly_with_the_position_at_the_reversal(tension):
    # pull to a position z, reverse: the motor travels h(z_fwd) + h(z_back) ... the tip stays put until
    # x - z = +w/2 (1 + tension z) on the way back
    eff = get_effect("backlash")
    w = 1e-3
    p = {"width": w, "tension": tension}
    for top in (0.5e-3, 2e-3, 4e-3):
        up = np.linspace(-4e-3, top, 4001)
        down = np.linspace(top, top - 5e-3, 20001)[1:]
        x = np.r_[up, down]
        y = eff.apply(Signals(t=np.arange(x.size) * 1.0, x=x), p)
        z = y[up.size - 1]
        assert top - z == pytest.approx(w / 2 * (1 + tension * z), rel=1e-9)     # the pulling envelope
        moved = np.flatnonzero(np.abs(y[up.size:] - z) > 0)[0]
        travel = top - down[moved]
        assert travel == pytest.approx(w * (1 + tension * z), abs=2.5e-7)        # the whole dead zone


# ---------------------------------------------------------------- the test-side distributed cable
L, EA, MU, THETA, KS, T0, N = 1.0, 5000.0, 0.1, 2 * math.pi, 800.0, 5.0, 120


def kaneko_dead_zone(T: float) -> float:
    """Motor travel [m] after a reversal before the tip moves, tip tension T [N] (uniform bend THETA)."""
    mt = MU * THETA
    return 2 * T * L * (math.cosh(mt) - 1) / (EA * mt)


def distributed_spring(x: np.ndarray) -> np.ndarray:
    """(n,) tip travel y [m] of a cable of N elements in a uniformly bent sheath pulling a spring (tension
    T0 + KS y) as the motor hauls in x (n,) [m], quasi-static: the element tensions T_j are held by friction
    within T_m e^(-+mu kappa s_j) of the motor tension T_m; while the tip stands the motor end's T_m is
    solved (bisection) so that the stretch sum T_j l / EA takes up the motor's travel; once the profile's
    turn-over reaches the tip element the tip slides, the whole profile then T_tip e^(+-mu kappa (L - s))."""
    l = L / N
    s = (np.arange(N) + 0.5) * l                    # element centres from the motor
    a = MU * THETA / L * s                          # wrap from the motor to each element
    tip_wrap = MU * THETA / L * (L - s)             # wrap from each element to the tip
    y = 0.0
    T = np.full(N, T0)
    c0 = x[0] - (y + T.sum() * l / EA)              # the motor's zero: the cable at rest, tension T0
    out = np.empty_like(x)
    xp = x[0]
    for k, xk in enumerate(x):
        need = xk - c0 - y                          # stretch with the tip at rest
        d = np.sign(xk - xp) if xk != xp else 0.0
        xp = xk
        if d != 0.0:
            lo, hi = 0.0, 10.0 * (T.max() + 1.0)
            for _ in range(60):
                tm = 0.5 * (lo + hi)
                Tn = np.clip(T, tm * np.exp(-a), tm * np.exp(a))
                if Tn.sum() * l / EA > need:
                    hi = tm
                else:
                    lo = tm
            Tn = np.clip(T, lo * np.exp(-a), lo * np.exp(a))
            if abs(Tn[-1] - T[-1]) > 1e-9 * T0:     # the turn-over has reached the tip: it slides
                g = np.exp(d * tip_wrap).sum() * l / EA
                y = (xk - c0 - T0 * g) / (1 + KS * g)
                Tn = (T0 + KS * y) * np.exp(d * tip_wrap)
            T = Tn
        out[k] = y
    return out


def test_test_side_cable_has_kanekos_dead_zone():
    up = np.linspace(0.0, 6e-3, 1201)
    down = np.linspace(6e-3, 2e-3, 801)[1:]
    y = distributed_spring(np.r_[up, down])
    z = y[up.size - 1]
    moved = np.flatnonzero(y[up.size:] < z - 1e-12)[0]
    assert 6e-3 - down[moved] == pytest.approx(kaneko_dead_zone(T0 + KS * z), rel=0.02)


def test_diagnosis_names_the_tension_play_and_kanekos_numbers(tmp_path):
    fs, seconds = 250.0, 16.0
    t = np.arange(int(fs * seconds)) / fs
    rng = np.random.default_rng(7)
    x = multisine(rng, t, 4e-3, 3, 0.1, 0.5)
    y = distributed_spring(x)
    sigma = 3e-6
    path = write_interchange(tmp_path / "kaneko.csv", t,
                             {"motor_pos": x, "tip_pos": y + rng.normal(0, sigma, t.size)},
                             {"motor_pos": "m", "tip_pos": "m"}, {"load": "spring"})
    doc = diagnose(read_interchange(path)).as_dict()
    first = doc["findings"][0]
    assert first["effect"] == "backlash" and first["channel"] == "tip_pos"
    p = first["params"]
    x_ref = p["x_ref"]["value"]
    T_ref = T0 + KS * x_ref                         # the spring law at the play's reference position
    assert p["width_input"]["value"] == pytest.approx(kaneko_dead_zone(T_ref), rel=0.1)
    assert p["tension"]["value"] == pytest.approx(KS / T_ref, rel=0.15)   # 1 / (x_ref - the slack position)
    assert p.get("take_up", {"value": 0.0})["value"] == 0.0              # a sharp take-up: no rounding pays
    assert doc["channels"]["tip_pos"]["rmse_model"] < 1.3 * sigma
