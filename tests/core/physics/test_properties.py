"""Physical properties of the models (hypothesis, seeded) and the catalogue's driver against plain loops over
the step kernels."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from teleop.core.physics import (CapstanCompensator, Signals, cable_stretch, chain, dahl, get_effect, hysteresis_offset,
                            linear_force, motor2tip_transitions, sls_force, stribeck)
from teleop.core.physics import REGISTRY
from ._signals import all_channels

SETTINGS = settings(derandomize=True, max_examples=40, deadline=None)
walk = st.lists(st.floats(-1e-3, 1e-3), min_size=2, max_size=120)


@pytest.mark.parametrize("name", [n for n, e in REGISTRY.items() if e.kernel is not None])
def test_driver_is_a_plain_loop_over_the_step_kernel(name):
    # the array form is the compiled driver over the effect's step kernel: the same numbers as calling the
    # kernel's Python source sample by sample
    eff = get_effect(name)
    sig = all_channels(600, seed=4)
    p = eff.check(None)
    cols = [sig[c] if sig[c] is not None else np.full(sig.n, p[c]) for c in eff.inputs + eff.optional]
    s = np.array(eff.kernel.state, dtype=float)
    pv = eff.packed(p)
    ref = [eff.kernel.step.py_func(s, np.array(u), pv) for u in zip(*cols)]
    np.testing.assert_allclose(eff.apply(sig, p), ref, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("name", ["backlash", "dahl_hysteresis", "pulley_friction", "viscoelasticity",
                                  "sensor_hysteresis", "capstan_friction"])
def test_a_step_runs_a_batch_from_its_state_and_keeps_the_last(name):
    # Step.run continues from the Step's state: two batches give the one run of the whole signal
    eff = get_effect(name)
    sig = all_channels(400, seed=5)
    names = eff.inputs + tuple(c for c in eff.optional if sig[c] is not None)
    st = eff.make_step(eff.defaults())
    first = st.run(**{c: sig[c][:150] for c in names})
    second = st.run(**{c: sig[c][150:] for c in names})
    np.testing.assert_array_equal(np.concatenate([first, second]), eff.apply(sig, eff.defaults()))
    assert st.step(**{c: float(sig[c][-1]) for c in names}) == pytest.approx(second[-1], rel=1e-9, abs=1e-12)


def test_hysteresis_offset_runs_trailing_axes_independently():
    # (n, 6) sensors with one start each: each column is its own recursion
    rng = np.random.default_rng(3)
    F = np.cumsum(rng.normal(0, 0.3, (500, 6)), axis=0)
    z0 = F[0] + rng.uniform(-0.2, 0.2, 6)
    out = hysteresis_offset(F, 0.4, 0.5, z0)
    assert out.shape == (500, 6)
    for j in range(6):
        np.testing.assert_array_equal(out[:, j], hysteresis_offset(F[:, j], 0.4, 0.5, z0[j]))
    assert np.all(np.abs(out) <= 0.4 + 1e-12) and np.any(out[0] != 0)


@SETTINGS
@given(steps=walk, start=st.floats(-3e-3, 3e-3), k=st.floats(10.0, 1e5), g=st.floats(0.05, 1.0),
       tau=st.floats(1e-3, 10.0), c=st.floats(0.0, 500.0))
def test_contact_force_is_zero_without_contact_and_never_negative(steps, start, k, g, tau, c):
    t = np.arange(len(steps)) * 1e-3
    d = start + np.cumsum(steps)
    sig = Signals(t=t, d=d)
    forces = [get_effect("linear_contact").apply(sig, {"k": k}),
              get_effect("hertz_contact").apply(sig, {"k": k}),
              chain("linear_contact", "viscoelasticity").apply(
                  sig, {"linear_contact.k": k, "viscoelasticity.g": g, "viscoelasticity.tau": tau}),
              chain("hertz_contact", "contact_damping").apply(sig, {"hertz_contact.k": k, "contact_damping.c": c})]
    for F in forces:
        assert np.all(F >= 0.0)
        assert np.all(F[d <= 0] == 0.0)


def test_sls_relaxes_under_a_held_indentation_and_stiffens_with_rate():
    k, g, tau, depth = 800.0, 0.6, 0.5, 3e-3
    t = np.arange(6000) * 1e-3
    d = np.minimum(t / 0.1, 1.0) * depth  # 0.1 s ramp, then hold
    F = sls_force(t, linear_force(d, k), d, g, tau)
    assert F.max() > 0.9 * k * depth  # nearly the instantaneous stiffness at the end of a fast ramp
    assert F[-1] == pytest.approx(g * k * depth, rel=1e-4)  # fully relaxed after ~12 tau
    assert np.all(np.diff(F[200:]) <= 1e-12)  # monotone relaxation during the hold
    # rate dependence: the same depth reached 10x slower peaks lower
    d_slow = np.minimum(t / 1.0, 1.0) * depth
    assert sls_force(t, linear_force(d_slow, k), d_slow, g, tau).max() < F.max() - 0.1 * k * depth


@SETTINGS
@given(h=st.floats(0.01, 2.0), delta=st.floats(0.01, 1.0), span=st.floats(2.5, 10.0))
def test_sensor_hysteresis_offsets_plus_h_rising_and_minus_h_falling(h, delta, span):
    up = np.linspace(0.0, span * delta, 400)
    F = np.concatenate([up, up[::-1]])
    off = hysteresis_offset(F, h, delta)
    assert np.all(np.abs(off) <= h * (1 + 1e-12))
    rising_done = up >= 2 * delta + 1e-9
    np.testing.assert_allclose(off[:400][rising_done], h, rtol=1e-9)
    falling_done = up[::-1] <= span * delta - 2 * delta - 1e-9
    np.testing.assert_allclose(off[400:][falling_done], -h, rtol=1e-9)


@SETTINGS
@given(steps=walk, sigma=st.floats(10.0, 1e6), Fc=st.floats(0.01, 5.0))
def test_dahl_force_stays_within_coulomb_level(steps, sigma, Fc):
    F = dahl(np.cumsum(steps), sigma, Fc)
    assert np.all(np.abs(F) <= Fc * (1 + 1e-12))


def test_dahl_reaches_coulomb_after_sliding_with_initial_slope_sigma():
    sigma, Fc = 1e4, 0.3
    x = np.linspace(0, 0.01, 10001)
    F = dahl(x, sigma, Fc)
    assert F[-1] == pytest.approx(Fc, rel=1e-9)
    # initial slope sigma from rest, 2 sigma right after a reversal from sliding (dF/dx = sigma (1 + F/Fc))
    fine = np.linspace(0, 1e-8, 11)
    assert dahl(fine, sigma, Fc)[1] / fine[1] == pytest.approx(sigma, rel=1e-3)
    back = np.concatenate([x, x[-1] - fine[1:]])
    Fr = dahl(back, sigma, Fc)
    assert (Fr[10002] - Fr[10001]) / fine[1] == pytest.approx(-2 * sigma, rel=1e-3)
    assert dahl(np.concatenate([x, x[::-1]]), sigma, Fc)[-1] == pytest.approx(-Fc, rel=1e-6)


@SETTINGS
@given(v=st.floats(1e-4, 1.0), Fc=st.floats(0.0, 2.0), Fs=st.floats(0.0, 3.0), vs=st.floats(1e-4, 1e-2))
def test_stribeck_curve_limits_and_symmetry(v, Fc, Fs, vs):
    assert stribeck(v, Fc, Fs, vs) == pytest.approx(-stribeck(-v, Fc, Fs, vs))
    assert stribeck(1e-9 * vs, Fc, Fs, vs) == pytest.approx(Fs, rel=1e-9, abs=1e-12)
    assert stribeck(50 * vs, Fc, Fs, vs) == pytest.approx(Fc, rel=1e-9, abs=1e-12)
    assert stribeck(0.0, Fc, Fs, vs) == 0.0


@SETTINGS
@given(x=st.lists(st.floats(-0.1, 0.1), min_size=2, max_size=20), k=st.floats(1e2, 1e7))
def test_compliance_stretch_is_load_over_k(x, k):
    x = np.array(x)
    np.testing.assert_array_equal(cable_stretch(x, 0.0, k), x)
    np.testing.assert_allclose(x - cable_stretch(x, 5.0, k), 5.0 / k, rtol=1e-9)


def test_capstan_compensator_runs_six_cables_at_once_like_six_scalar_runs():
    rng = np.random.default_rng(0)
    F_m = 3.0 + np.cumsum(rng.normal(0, 0.05, (300, 6)), axis=0)
    mu, theta = 0.1, np.linspace(2.0, 3.0, 6)
    comp = CapstanCompensator(mu, theta)
    many = np.array([comp.step(row) for row in F_m])
    for i in range(6):
        np.testing.assert_allclose(many[:, i], motor2tip_transitions(F_m[:, i], mu, theta[i]), rtol=1e-12)
