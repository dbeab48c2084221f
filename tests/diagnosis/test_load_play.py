"""Backlash's dead zone growing with the recorded tip load (Kaneko's tendon-sheath play under an external
force, whose tension is no function of the tip's position): the kernel's closed form, and the diagnosis on
recordings of a test-side quasi-static distributed cable pulling a varying force that shares no code with
the catalogue (its tension profile along the sheath clamped from the tip end as the force changes and from
the motor end as the motor moves, the tip sliding once the motor's turn-over reaches it)."""

import math

import numpy as np
import pytest

from teleop.core.physics import Signals, get_effect
from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange, write_interchange
from tests._signals import multisine


def test_no_load_recorded_is_the_general_play():
    # the stand-in load (the reference itself) grows nothing, whatever load_tension
    rng = np.random.default_rng(0)
    t = np.arange(4000) / 500.0
    x = multisine(rng, t, 0.01, 3, 0.1, 0.6)
    eff = get_effect("backlash")
    general = {"width": 2e-3, "elastic": 0.2, "tail": 0.1, "grow": 3.0, "start": 0.3, "load": 4.0}
    y0 = eff.apply(Signals(t=t, x=x), general)
    y1 = eff.apply(Signals(t=t, x=x), {**general, "load_tension": 0.3})
    assert np.array_equal(y0, y1)
    # and a recorded load at the reference magnitude, either sign, is the same play
    y2 = eff.apply(Signals(t=t, x=x, load=np.full(t.size, -4.0)), {**general, "load_tension": 0.3})
    assert np.max(np.abs(y2 - y0)) < 1e-15


@pytest.mark.parametrize("c", [1.0, 0.4])
def test_dead_zone_grows_linearly_with_the_load_at_the_reversal(c):
    # pull under a load T, reverse: the tip stays put for w (1 + c (|T| - ref) / ref) of motor travel
    eff = get_effect("backlash")
    w, ref = 1e-3, 5.0
    p = {"width": w, "load_tension": c, "load": ref}
    for T in (2.0, 5.0, 9.0):
        up = np.linspace(-4e-3, 2e-3, 4001)
        down = np.linspace(2e-3, -3e-3, 20001)[1:]
        x = np.r_[up, down]
        y = eff.apply(Signals(t=np.arange(x.size) * 1.0, x=x, load=np.full(x.size, T)), p)
        z = y[up.size - 1]
        assert 2e-3 - z == pytest.approx(w / 2 * (1 + c * (T - ref) / ref), rel=1e-9)   # the pulling envelope
        moved = np.flatnonzero(np.abs(y[up.size:] - z) > 0)[0]
        dead = w * (1 + c * (T - ref) / ref)
        assert 2e-3 - down[moved - 1] <= dead + 1e-12 and 2e-3 - down[moved] >= dead - 1e-12   # to the sample


# ---------------------------------------------------------------- the test-side distributed cable
L, EA, MU, THETA, T0, N = 1.0, 5000.0, 0.1, 2 * math.pi, 5.0, 120


def kaneko_dead_zone(T: float) -> float:
    """Motor travel [m] after a reversal before the tip moves, tip tension T [N] (uniform bend THETA)."""
    mt = MU * THETA
    return 2 * T * L * (math.cosh(mt) - 1) / (EA * mt)


def distributed_force(x: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(n,) tip travel [m] of a cable of N elements in a uniformly bent sheath as the motor hauls in x (n,)
    [m] against the tip force F (n,) [N], quasi-static: the element tensions T_j are held by friction. Each
    sample the force's change reaches in from the tip (T_j clamped within F e^(-+mu kappa (L - s_j)), the
    motor held), then the motor's move from the motor end (T_j within T_m e^(-+mu kappa s_j), T_m solved by
    bisection so that the stretch sum T_j l / EA takes up the motor's travel with the tip at rest); once the
    motor's turn-over reaches the tip element the tip slides, the whole profile F e^(+-mu kappa (L - s)).
    The tip is where the motor is less the stretch sum."""
    l = L / N
    s = (np.arange(N) + 0.5) * l                    # element centres from the motor
    a = MU * THETA / L * s                          # wrap from the motor to each element
    tw = MU * THETA / L * (L - s)                   # wrap from each element to the tip
    T = np.full(N, F[0])
    c0 = x[0] - T.sum() * l / EA                    # the motor's zero: the tip at 0 at rest
    out = np.empty_like(x)
    xp = x[0]
    for k, xk in enumerate(x):
        T = np.clip(T, F[k] * np.exp(-tw), F[k] * np.exp(tw))
        d = np.sign(xk - xp) if xk != xp else 0.0
        if d != 0.0:
            need = xk - xp + T.sum() * l / EA        # the stretch with the tip at rest
            lo, hi = 0.0, 10.0 * (T.max() + 1.0)
            for _ in range(60):
                tm = 0.5 * (lo + hi)
                if np.clip(T, tm * np.exp(-a), tm * np.exp(a)).sum() * l / EA > need:
                    hi = tm
                else:
                    lo = tm
            Tn = np.clip(T, lo * np.exp(-a), lo * np.exp(a))
            T = F[k] * np.exp(d * tw) if abs(Tn[-1] - T[-1]) > 1e-9 * T0 else Tn
        xp = xk
        out[k] = xk - c0 - T.sum() * l / EA
    return out


@pytest.mark.parametrize("force", [3.0, 8.0])
def test_test_side_cable_has_kanekos_dead_zone_under_a_force(force):
    up = np.linspace(0.0, 6e-3, 1201)
    down = np.linspace(6e-3, 2e-3, 801)[1:]
    x = np.r_[up, down]
    y = distributed_force(x, np.full(x.size, force))
    z = y[up.size - 1]
    moved = np.flatnonzero(y[up.size:] < z - 1e-12)[0]
    assert 6e-3 - down[moved] == pytest.approx(kaneko_dead_zone(force), rel=0.02)


def test_diagnosis_names_the_load_play_and_kanekos_numbers(tmp_path):
    # a force swinging +-50 % about T0: the dead zone swings with it; a constant width leaves ~40x the noise
    fs, seconds = 250.0, 16.0
    t = np.arange(int(fs * seconds)) / fs
    rng = np.random.default_rng(7)
    x = multisine(rng, t, 4e-3, 3, 0.1, 0.5)
    F = T0 * (1 + 0.5 * np.sin(2 * np.pi * 0.13 * t + 1.0))
    y = distributed_force(x, F)
    sigma = 3e-6
    path = write_interchange(tmp_path / "kaneko_force.csv", t,
                             {"motor_pos": x, "tip_pos": y + rng.normal(0, sigma, t.size),
                              "tip_force": F + rng.normal(0, 0.01, t.size)},
                             {"motor_pos": "m", "tip_pos": "m", "tip_force": "N"}, {"load": "external"})
    doc = diagnose(read_interchange(path)).as_dict()
    play = next(f for f in doc["findings"] if f["effect"] == "backlash" and f["channel"] == "tip_pos")
    p = play["params"]
    T_ref = p["load"]["value"]
    assert T_ref == pytest.approx(np.mean(F), rel=0.01)                  # held at the mean load
    assert p["load_tension"]["value"] == pytest.approx(1.0, rel=0.15)   # width proportional to T: Kaneko's
    assert p.get("take_up", {"value": 0.0})["value"] == 0.0              # a sharp take-up: no rounding pays
    assert p["width_input"]["value"] == pytest.approx(kaneko_dead_zone(T_ref), rel=0.1)
    assert doc["channels"]["tip_pos"]["rmse_model"] < 10 * sigma
