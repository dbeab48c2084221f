"""Backlash's rounded take-up (`take_up`: pre-sliding along the sheath, Dahl's exponential approach): 0 is
the sharp play bit for bit; the closed form over a sample is exact (any split of the envelope's travel, the
ODE it solves) and does not overflow; after a reversal the tip joins the motion along that closed form and
keeps the sharp play's lag once it has; the step and array forms agree. On a recording of the distributed
tendon-sheath plant (scenes.tendon_sheath: LuGre bristles per element, no catalogue kernel) pulling a spring,
the diagnosis keeps a rounded take-up, which brings the tip closer to its noise floor than the sharp play."""


import numpy as np
import pytest
from scipy.integrate import solve_ivp

from teleop.apps.bench.diagnose_distributed import distributed_plan, simulate_case
from teleop.core.kernels.tension_play import take_up_gap
from teleop.core.physics import Signals, get_effect
from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange, write_interchange
from tests._signals import multisine

GENERAL = {"width": 2e-3, "elastic": 0.2, "tail": 0.1, "grow": 3.0, "start": 0.3, "tension": 120.0}


def _trajectory(seed: int):
    rng = np.random.default_rng(seed)
    t = np.arange(4000) / 500.0
    return t, multisine(rng, t, 0.01, 3, 0.1, 0.6)


def _sharp(x: np.ndarray, r: float) -> np.ndarray:
    """The play operator written out: y = clamp(y, x - r, x + r), starting at x[0]."""
    y, out = x[0], np.empty_like(x)
    for k, v in enumerate(x):
        y = min(max(y, v - r), v + r)
        out[k] = y
    return out


def test_take_up_zero_is_the_sharp_play_bit_for_bit():
    t, x = _trajectory(0)
    eff = get_effect("backlash")
    assert np.array_equal(eff.apply(Signals(t=t, x=x), {"width": 2e-3, "take_up": 0.0}), _sharp(x, 1e-3))
    load = 4.0 + np.sin(t)
    for p in (GENERAL, {**GENERAL, "load_tension": 0.7, "load": 4.0}):
        sig = Signals(t=t, x=x, load=load)
        y0 = eff.apply(sig, p)
        assert np.array_equal(eff.apply(sig, {**p, "take_up": 0.0}), y0)
        # and the rounded form tends to it: a take-up far below a sample's travel is the sharp corner
        assert np.max(np.abs(eff.apply(sig, {**p, "take_up": 1e-9}) - y0)) < 1e-12


def test_take_up_gap_is_exact_over_any_split_and_solves_its_law():
    lam = 2e-4
    for gap in (0.0, 1e-5, 3e-4, 2e-3):
        for travel in (1e-6, 2e-4, 1e-3, 5e-3):
            whole = take_up_gap(gap, travel, lam)
            split = gap
            for _ in range(7):
                split = take_up_gap(split, travel / 7, lam)
            assert split == pytest.approx(whole, rel=1e-12, abs=1e-18)
            assert 0.0 <= whole <= gap
            ode = solve_ivp(lambda e, d: -(1.0 - np.exp(-d / lam)), (0.0, travel), [gap], rtol=1e-11, atol=1e-16)
            assert whole == pytest.approx(ode.y[0, -1], rel=1e-7, abs=1e-15)
    # a gap of ten thousand take-up lengths: no overflow, the gap closed one for one with the travel
    assert take_up_gap(1.0, 0.25, 1e-4) == pytest.approx(0.75, rel=1e-12)


@pytest.mark.parametrize("take_up", [0.05, 0.3])
def test_tip_joins_the_motion_along_the_closed_form_after_a_reversal(take_up):
    w = 1e-3
    r, lam = w / 2, take_up * w / 2
    eff = get_effect("backlash")
    up = np.linspace(-4e-3, 2e-3, 3001)
    for n in (2001, 20001):                       # coarse and fine sampling: the same curve
        down = np.linspace(2e-3, -2e-3, n)[1:]
        x = np.r_[up, down]
        y = eff.apply(Signals(t=np.arange(x.size) * 1.0, x=x), {"width": w, "take_up": take_up})
        assert y[up.size - 1] == pytest.approx(2e-3 - r, abs=1e-15)    # pulled far: the sharp play's lag
        E = 2e-3 - down                               # the upper envelope's travel towards the tip
        D = lam * np.log1p(np.expm1(2 * r / lam) * np.exp(-E / lam))
        assert np.max(np.abs(y[up.size:] - (down + r - D))) < 1e-15
        # and back on the other envelope, the gap closing as e^(-travel / lam) past the dead zone
        assert -1e-18 <= (-2e-3 + r) - y[-1] <= 1.01 * lam * np.exp(-(4e-3 - w) / lam) + 1e-18
    # the tip all but stands over the dead zone and has joined a few take-up lengths after it
    moved = (2e-3 - r) - y[up.size:]
    assert moved[E < w - 3 * lam].max() < 0.06 * lam
    assert np.max(np.abs(moved - np.maximum(E - w, 0.0))[E > w + 8 * lam]) < 1e-3 * lam


def test_step_and_array_forms_agree():
    t, x = _trajectory(1)
    eff = get_effect("backlash")
    load = 4.0 + np.sin(t)
    for p in ({"width": 2e-3, "take_up": 0.2}, {**GENERAL, "take_up": 0.5, "load_tension": 0.7, "load": 4.0}):
        st = eff.make_step(p)
        stepped = np.array([st.step(x=float(a), load=float(b)) for a, b in zip(x, load)])
        assert np.max(np.abs(eff.apply(Signals(t=t, x=x, load=load), p) - stepped)) < 1e-15


def test_presliding_plant_keeps_a_rounded_take_up(tmp_path):
    # the bench's spring case with the plant's pre-sliding (10 um of bristle travel per node) rounding each
    # take-up: the sharp play leaves the tip several times its noise (the corners), the rounded one less
    case = distributed_plan(3)[2]
    assert case["load"] == "spring"
    sim = simulate_case(case, seed=1, duration_s=5.0)
    src = tmp_path / "plant.csv"
    src.write_text(sim["csv"], encoding="utf-8")
    rec = read_interchange(src)
    path = write_interchange(tmp_path / "position.csv", rec.t,
                             {"motor_pos": rec.channels["motor_pos"], "tip_pos": rec.channels["tip_pos"]},
                             {"motor_pos": "m", "tip_pos": "m"}, {"load": "spring"})
    doc = diagnose(read_interchange(path)).as_dict()
    play = next(f for f in doc["findings"] if f["channel"] == "tip_pos")
    assert play["effect"] == "backlash"
    p = play["params"]
    assert 0.02 < p["take_up"]["value"] < 0.6
    assert p["tension"]["value"] > 0
    assert doc["channels"]["tip_pos"]["rmse_model"] < 3.5 * sim["noise"]["tip_pos"]
