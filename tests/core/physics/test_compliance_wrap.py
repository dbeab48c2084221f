"""cable_compliance's general form: a load read at the motor, beyond the sheath's friction (wrap = mu Theta),
stretches the cable by the capstan's tip tension, not by the reading's switch at each reversal."""

import numpy as np

from teleop.core.physics import Signals, get_effect
from teleop.core.physics.capstan import tip2motor_transitions
from teleop.core.physics.compliance import cable_stretch

EFF = get_effect("cable_compliance")


def _drive():
    t = np.linspace(0.0, 8.0, 4001)
    return t, 5e-3 * np.sin(2 * np.pi * 0.5 * t)


def test_wrap_zero_is_the_plain_law():
    t, x = _drive()
    load = 10.0 + 2.0 * np.sin(2 * np.pi * 0.2 * t)
    assert np.array_equal(EFF.apply(Signals(t=t, x=x, load=load), {"k": 3e3}), cable_stretch(x, load, 3e3))
    assert EFF.plain_form() == {"wrap": 0.0}


def test_a_constant_tip_tension_read_at_the_motor_stretches_the_cable_by_itself():
    t, x = _drive()
    mt = 0.8
    F_m = tip2motor_transitions(x, np.full(t.shape, 10.0), mt, 1.0, 5e3)   # switches by e^(+-0.8) each turn
    tip = EFF.apply(Signals(t=t, x=x, load=F_m), {"k": 3e3, "wrap": mt})
    after = t > 1.0   # past the first turn: the compensator has met the band
    assert np.allclose((x - tip)[after], 10.0 / 3e3, rtol=1e-9, atol=1e-12)
    plain = EFF.apply(Signals(t=t, x=x, load=F_m), {"k": 3e3})
    assert np.ptp((x - plain)[after]) > 0.5 * 10.0 * (np.exp(mt) - np.exp(-mt)) / 3e3


def test_step_form_matches_the_array_form():
    t, x = _drive()
    rng = np.random.default_rng(3)
    load = tip2motor_transitions(x, 8.0 + rng.normal(0.0, 0.2, t.size), 0.5, 1.0, 4e3)
    p = {"k": 2e3, "wrap": 0.5}
    arr = EFF.apply(Signals(t=t, x=x, load=load), p)
    st = EFF.make_step(p)
    per = np.array([st.step(x=float(a), load=float(b)) for a, b in zip(x, load)])
    assert np.allclose(per, arr, rtol=0, atol=1e-15)
