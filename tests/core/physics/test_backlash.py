import numpy as np
from hypothesis import given, settings, strategies as st

from teleop.core.physics import Signals, backlash, fit, get_effect

from ._signals import assert_params_close, noisy, step_matches_apply, sum_of_sines, time_axis, triangle

EFFECT = get_effect("backlash")


def test_round_trip_recovers_width_within_5_percent():
    t = time_axis(6.0)
    x = sum_of_sines(t, 5e-3) + triangle(t, 1e-3, 0.7)
    truth = {"width": 0.8e-3}
    sig = Signals(t=t, x=x)
    y = noisy(EFFECT.apply(sig, truth), 10e-6)
    res = fit(EFFECT, sig, y)
    assert_params_close(res.params, truth)
    assert res.rmse < 15e-6
    assert 0 < res.stderr["width"] < 0.01 * truth["width"]


def test_step_equals_apply():
    t = time_axis(2.0)
    sig = Signals(t=t, x=sum_of_sines(t, 3e-3, seed=4))
    step_matches_apply(EFFECT, sig, {"width": 1e-3})


@settings(derandomize=True, max_examples=40, deadline=None)
@given(steps=st.lists(st.floats(-1e-3, 1e-3), min_size=2, max_size=200), width=st.floats(1e-6, 2e-3))
def test_dead_band_and_driving(steps, width):
    x = np.cumsum(steps)
    y = backlash(x, width)
    r = width / 2
    # never further than half the play from the input
    assert np.all(np.abs(x - y) <= r * (1 + 1e-9) + 1e-15)
    moved = np.flatnonzero(np.abs(np.diff(y)) > 1e-15) + 1
    # whenever the output moves, it is being driven: exactly input -/+ width/2
    np.testing.assert_allclose(np.abs(x[moved] - y[moved]), r, rtol=1e-9, atol=1e-15)
    # while the input stays inside the dead band, the output does not move
    still = np.flatnonzero(np.abs(x[1:] - y[:-1]) < r * (1 - 1e-9)) + 1
    np.testing.assert_array_equal(y[still], y[still - 1])
