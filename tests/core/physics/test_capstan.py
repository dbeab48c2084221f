import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from teleop.core.physics import (CapstanCompensator, Signals, capstan_in, capstan_out, fit, get_effect, motor2tip,
                            motor2tip_transitions, tip2motor, tip2motor_transitions)

from ._signals import assert_params_close, noisy, step_matches_apply, time_axis, triangle

EFFECT = get_effect("capstan_friction")
finite = st.floats(0.01, 50.0)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(T=st.lists(finite, min_size=6, max_size=6), mu=st.floats(0.0, 1.0),
       theta=st.lists(st.floats(0.0, 10.0), min_size=6, max_size=6),
       pulling=st.lists(st.booleans(), min_size=6, max_size=6))
def test_compensation_inverts_capstan_per_cable(T, mu, theta, pulling):
    T, theta, pulling = np.array(T), np.array(theta), np.array(pulling)
    np.testing.assert_allclose(capstan_in(capstan_out(T, mu, theta), mu, theta), T, rtol=1e-12)
    F_m = tip2motor(T, mu, theta, pulling)
    np.testing.assert_allclose(motor2tip(F_m, mu, theta, pulling), T, rtol=1e-12)
    # pulling needs more motor force than the tip sees, releasing less
    assert np.all(F_m[pulling] >= T[pulling] * (1 - 1e-12))
    assert np.all(F_m[~pulling] <= T[~pulling] * (1 + 1e-12))


def test_capstan_law_seed_000_eq_3():
    # T_load = T_hold e^(mu theta): 60 deg bend, mu 0.2
    assert capstan_in(1.0, 0.2, np.pi / 3) == pytest.approx(np.exp(0.2 * np.pi / 3))
    assert capstan_out(np.exp(0.2 * np.pi / 3), 0.2, np.pi / 3) == pytest.approx(1.0)


def test_transitions_follow_the_two_lines_and_are_flat_in_tip_force():
    t = time_axis(4.0)
    x = triangle(t, 10e-3, 2.0)
    F_t = np.full(t.shape, 3.0)
    mu, th, k = 0.1, 3.0, 5e3
    F_m = tip2motor_transitions(x, F_t, mu, th, k)
    e = np.exp(mu * th)
    dx = np.diff(x)
    pulling_steady = np.flatnonzero((dx > 0) & (np.abs(F_m[1:] - 3.0 * e) < 1e-9)) + 1
    releasing_steady = np.flatnonzero((dx < 0) & (np.abs(F_m[1:] - 3.0 / e) < 1e-9)) + 1
    assert pulling_steady.size > 1000 and releasing_steady.size > 1000
    # during a reversal the motor force moves at k per metre of motor travel, inside the band
    inside = np.flatnonzero((F_m[1:] < 3.0 * e - 1e-9) & (F_m[1:] > 3.0 / e + 1e-9)) + 1
    assert inside.size > 0
    np.testing.assert_allclose(np.diff(F_m)[inside - 1], k * dx[inside - 1], rtol=1e-6)
    # the direction-free compensation gives back the constant tip force through the transitions
    np.testing.assert_allclose(motor2tip_transitions(F_m, mu, th), F_t, rtol=1e-12)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(steps=st.lists(st.floats(-1e-3, 1e-3), min_size=2, max_size=150), load=finite,
       mu=st.floats(0.0, 0.5), theta=st.floats(0.0, 6.0), k=st.floats(10.0, 1e6))
def test_transition_model_stays_in_band_and_compensation_inverts(steps, load, mu, theta, k):
    x = np.cumsum(steps)
    F_t = np.full(x.shape, load)
    F_m = tip2motor_transitions(x, F_t, mu, theta, k)
    e = np.exp(mu * theta)
    assert np.all(F_m <= load * e * (1 + 1e-9)) and np.all(F_m >= load / e * (1 - 1e-9))
    np.testing.assert_allclose(motor2tip_transitions(F_m, mu, theta), F_t, rtol=1e-9)
    comp = CapstanCompensator(mu, theta)
    np.testing.assert_allclose([comp.step(f) for f in F_m], F_t, rtol=1e-9)


def test_step_equals_apply_with_and_without_theta_channel():
    t = time_axis(2.0)
    x = triangle(t, 5e-3, 0.8)
    load = 2.0 + np.sin(1.3 * t)
    p = {"mu": 0.12, "theta": 2.5, "k": 4e3}
    step_matches_apply(EFFECT, Signals(t=t, x=x, load=load), p, rtol=1e-9, atol=1e-9)
    step_matches_apply(EFFECT, Signals(t=t, x=x, load=load, theta=2.0 + 0.3 * np.sin(t)), p,
                       rtol=1e-9, atol=1e-9)


def test_round_trip_recovers_mu_and_stick_stiffness_within_5_percent():
    t = time_axis(8.0)
    x = triangle(t, 10e-3, 2.0) + 2e-3 * np.sin(2 * np.pi * 0.9 * t)
    load = 3.0 + 1.5 * np.sin(2 * np.pi * 0.13 * t)
    theta = np.deg2rad(140.0) + 1.0
    truth = {"mu": 0.1, "k": 3e3}
    sig = Signals(t=t, x=x, load=load)
    y = noisy(EFFECT.apply(sig, dict(truth, theta=theta)), 0.02)
    res = fit(EFFECT, sig, y, fixed={"theta": theta})
    assert_params_close(res.params, truth)
    assert res.params["theta"] == theta and res.stderr["theta"] == 0.0
    assert res.rmse < 0.025
