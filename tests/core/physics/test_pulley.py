"""The cable-pulley transmission (seed 002): properties of the chain (hypothesis, seeded), its relation to
the capstan law, the stick transitions and the elongation."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from teleop.core.physics import (Pulley, PulleyChain, Signals, capstan_band, get_effect, pulley_band,
                            pulley_elongation, pulley_motor_force, tip2motor_transitions)
from teleop.core.physics.pulley import segment_tensions

SETTINGS = settings(derandomize=True, max_examples=40, deadline=None)
pulleys = st.lists(st.tuples(st.floats(0.0, math.pi), st.floats(2e-3, 0.05), st.floats(0.0, 0.4),
                             st.floats(0.0, 0.5)), min_size=1, max_size=6)


def _chain(ps, EI=0.0, EA=math.inf, d_tip=0.0):
    return PulleyChain(tuple(Pulley(th, R, mu, d) for th, R, mu, d in ps), EI=EI, EA=EA, d_tip=d_tip)


@SETTINGS
@given(ps=pulleys, EI=st.floats(0.0, 1e-5), T=st.lists(st.floats(0.0, 50.0), min_size=1, max_size=30))
def test_band_brackets_the_load_and_rises_with_it(ps, EI, T):
    ch = _chain(ps, EI)
    T = np.sort(np.array(T))
    lo, hi = pulley_band(T, ch)
    assert np.all(lo >= 0) and np.all(lo <= T + 1e-12) and np.all(hi >= T - 1e-12)
    assert np.all(np.diff(lo) >= -1e-12) and np.all(np.diff(hi) >= -1e-12)   # more load, more motor force
    # each pulley only adds loss: the pulling line grows, the releasing line shrinks, pulley by pulley
    pull, rel = segment_tensions(T, ch, True), segment_tensions(T, ch, False)
    assert np.all(np.diff(pull, axis=0) >= -1e-12) and np.all(np.diff(rel, axis=0) <= 1e-12)


@SETTINGS
@given(thetas=st.lists(st.floats(0.0, math.pi), min_size=1, max_size=6), mu=st.floats(0.0, 0.4),
       T=st.floats(0.0, 50.0))
def test_without_bending_the_chain_is_the_capstan_law_over_the_total_wrap(thetas, mu, T):
    ch = _chain([(th, 0.01, mu, 0.0) for th in thetas])
    lo, hi = pulley_band(np.array([T]), ch)
    clo, chi = capstan_band(T, mu, sum(thetas))
    assert lo[0] == pytest.approx(float(clo), rel=1e-12, abs=1e-12)
    assert hi[0] == pytest.approx(float(chi), rel=1e-12, abs=1e-12)


@SETTINGS
@given(seed=st.integers(0, 1000), mu=st.floats(0.01, 0.3), wrap=st.floats(0.1, 6.0), k=st.floats(1e2, 1e5))
def test_transitions_match_the_capstan_transitions_without_bending(seed, mu, wrap, k):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(0, 1e-4, 300))
    T = 2.0 + np.abs(np.cumsum(rng.normal(0, 0.05, 300)))
    ours = pulley_motor_force(x, T, _chain([(wrap, 0.01, mu, 0.0)]), k)
    np.testing.assert_allclose(ours, tip2motor_transitions(x, T, mu, wrap, k), rtol=1e-9, atol=1e-9)


@SETTINGS
@given(ps=pulleys, EI=st.floats(0.0, 1e-5), seed=st.integers(0, 1000), k=st.floats(10.0, 1e6))
def test_motor_force_stays_in_its_band_and_follows_the_lines_when_driving(ps, EI, seed, k):
    ch = _chain(ps, EI)
    rng = np.random.default_rng(seed)
    t = np.arange(400) / 100
    x = 5e-3 * np.sin(2 * np.pi * 0.5 * t + rng.uniform(0, 6))
    T = 3.0 + rng.uniform(0, 2) * np.sin(2 * np.pi * 0.2 * t)
    F = pulley_motor_force(x, T, ch, k)
    lo, hi = pulley_band(T, ch)
    assert np.all(F >= lo - 1e-9) and np.all(F <= hi + 1e-9)
    # a long steady haul in ends on the pulling line, a long pay-out on the releasing line
    ramp = np.r_[np.linspace(0, 0.05, 200), np.linspace(0.05, 0.0, 200)]
    F2 = pulley_motor_force(ramp, np.full(400, 4.0), ch, max(k, 1e3))
    lo2, hi2 = pulley_band(np.array([4.0]), ch)
    assert F2[199] == pytest.approx(hi2[0], rel=1e-9) and F2[-1] == pytest.approx(lo2[0], rel=1e-9, abs=1e-12)


@SETTINGS
@given(ps=pulleys, EI=st.floats(0.0, 1e-5), EA=st.floats(1e3, 1e6), d_tip=st.floats(0.0, 0.5),
       T=st.floats(0.1, 30.0))
def test_elongation_between_releasing_and_pulling_and_hookes_law_without_losses(ps, EI, EA, d_tip, T):
    ch = _chain(ps, EI, EA, d_tip)
    lo, hi = pulley_band(np.array([T]), ch)
    e_lo, e_hi = pulley_elongation(lo, [T], ch)[0], pulley_elongation(hi, [T], ch)[0]
    mid = pulley_elongation((lo + hi) / 2, [T], ch)[0]
    assert 0 <= e_lo <= mid + 1e-15 <= e_hi + 2e-15
    lossless = _chain([(0.0, R, mu, d) for _, R, mu, d in ps], 0.0, EA, d_tip)   # no wrap, no bending
    total = d_tip + sum(d for *_, d in ps)
    assert pulley_elongation([T], [T], lossless)[0] == pytest.approx(T * total / EA, rel=1e-12, abs=1e-18)
    assert pulley_elongation([T], [T], _chain(ps, EI))[0] == 0.0          # rigid cable


def test_catalogue_effects_are_the_one_pulley_chain():
    """pulley_friction and pulley_elongation in the registry are the lumped chain: same numbers."""
    t = np.arange(1000) / 200
    x = 4e-3 * np.sin(2 * np.pi * 0.4 * t)
    T = 3.0 + np.sin(2 * np.pi * 0.1 * t)
    p = {"mu": 0.12, "wrap": 2.0, "bend": 0.3, "k": 5e3}
    ch = PulleyChain((Pulley(theta=2.0, R=0.004, mu=0.12),), EI=0.3 * 0.004 ** 2)
    F = get_effect("pulley_friction").apply(Signals(t=t, x=x, load=T), p)
    np.testing.assert_allclose(F, pulley_motor_force(x, T, ch, 5e3), rtol=1e-12)
    tip = get_effect("pulley_elongation").apply(Signals(t=t, x=x, load=T), {**p, "c": 1e-4})
    np.testing.assert_allclose(tip, x - 1e-4 * 0.5 * (T + F), rtol=1e-12)
    # the pulling stretch is larger than the releasing one: a direction-dependent elongation
    v = np.gradient(x, t)
    s = x - tip
    assert s[v > 0.5 * v.max()].mean() > s[v < 0.5 * v.min()].mean()
