"""The lags' step kernels against closed forms: a transport delay shifts a signal by whole samples exactly and by
fractions of one as linear interpolation does, whatever the sample rate; a first-order lag's step and ramp
responses are the ODE's exact solutions; the real-time Step and the batch run are the one kernel."""

import math

import numpy as np
import pytest

from teleop.core.physics import Signals, first_order_lag, get_effect, transport_delay
from teleop.core.physics.lag import BUFFER, MAX_DELAY_S

DT = 2.0 ** -10      # a sample interval that binary floats hold exactly: t - k DT lands on a sample


def _signal(n: int = 4000, dt: float = DT):
    t = np.arange(n) * dt
    return t, np.sin(2 * np.pi * 1.3 * t) + 0.3 * np.sin(2 * np.pi * 4.1 * t + 0.5)


@pytest.mark.parametrize("k", [0, 1, 7, 200])
def test_whole_sample_delay_is_an_exact_shift(k):
    t, x = _signal()
    y = transport_delay(t, x, k * DT)
    np.testing.assert_array_equal(y[k:], x[: x.size - k])
    np.testing.assert_array_equal(y[:k], x[0])          # before the record: its first value held


@pytest.mark.parametrize("delay", [0.3 * DT, 7.3e-3, 0.1234])
def test_fractional_delay_interpolates_linearly_and_tracks_the_true_shift(delay):
    t, x = _signal()
    y = transport_delay(t, x, delay)
    # the closed form of linear interpolation between the bracketing samples
    k = np.floor((t - delay) / DT).astype(int)
    ok = k >= 0
    frac = (t[ok] - delay) / DT - k[ok]
    ref = x[k[ok]] + frac * (x[np.minimum(k[ok] + 1, x.size - 1)] - x[k[ok]])
    np.testing.assert_allclose(y[ok], ref, rtol=0, atol=1e-12)
    # against the continuous signal read delay late: within the interpolation bound DT^2 / 8 max|x''|
    t0 = t - delay
    true = np.sin(2 * np.pi * 1.3 * t0) + 0.3 * np.sin(2 * np.pi * 4.1 * t0 + 0.5)
    bound = DT ** 2 / 8 * ((2 * np.pi * 1.3) ** 2 + 0.3 * (2 * np.pi * 4.1) ** 2)
    assert np.max(np.abs(y[ok] - true[ok])) <= bound * 1.0001


def test_the_delay_is_in_seconds_whatever_the_sampling():
    # a piecewise-linear input with its corners on the coarse grid: the delay read on every 8th sample is
    # the full-rate output at those samples (a fit on decimated samples means the same delay)
    t = np.arange(8001) * 1e-3
    x = np.interp(t, t[::400], np.random.default_rng(2).normal(0, 1, t[::400].size))
    full = transport_delay(t, x, 0.0437)
    coarse = transport_delay(t[::8], x[::8], 0.0437)
    np.testing.assert_allclose(coarse, full[::8], rtol=0, atol=1e-12)


def test_a_delay_longer_than_the_buffer_reads_the_oldest_sample_kept():
    dt = 1e-4                                  # 10 kHz: MAX_DELAY_S is more than BUFFER samples
    assert MAX_DELAY_S / dt > BUFFER
    t, x = _signal(3 * BUFFER, dt)
    y = transport_delay(t, x, MAX_DELAY_S)
    k = np.arange(BUFFER, t.size)
    np.testing.assert_array_equal(y[k], x[k - BUFFER + 1])


def test_first_order_lag_step_response():
    tau = 0.05
    t = np.arange(3000) * DT
    s = 500                                    # the input steps from 0 to 1 between samples s - 1 and s
    x = (np.arange(t.size) >= s).astype(float)
    y = first_order_lag(t, x, tau)
    np.testing.assert_array_equal(y[:s], 0.0)
    # exact for the input linear between samples (the hold the kernel integrates): a ramp over one interval
    after = t[s:] - t[s]
    exact = 1.0 - tau / DT * (-math.expm1(-DT / tau)) * np.exp(-after / tau)
    np.testing.assert_allclose(y[s:], exact, rtol=0, atol=1e-12)
    # which is 1 - exp(-t / tau) from the middle of that interval, to (DT / tau)^2
    step = 1.0 - np.exp(-(after + DT / 2) / tau)
    assert np.max(np.abs(y[s:] - step)) < (DT / tau) ** 2
    assert y[-1] == pytest.approx(1.0, abs=1e-10)


def test_first_order_lag_ramp_and_sine_responses_at_any_rate():
    tau, m = 0.04, 3.0
    for dt in (DT, 8 * DT, 0.02):              # up to half of tau per sample
        t = np.arange(int(2.0 / dt)) * dt
        y = first_order_lag(t, m * t, tau)
        np.testing.assert_allclose(y, m * (t - tau * (1.0 - np.exp(-t / tau))), rtol=0, atol=1e-12)
    # steady state on a sine (its start's transient gone): gain 1 / sqrt(1 + (w tau)^2), phase lag atan(w tau),
    # to the linear hold's error on a sine, (w DT)^2 / 8
    w = 2 * np.pi * 2.0
    t = np.arange(20000) * DT
    y = first_order_lag(t, np.sin(w * t), tau)
    ref = np.sin(w * t - math.atan(w * tau)) / math.hypot(1.0, w * tau)
    late = t > 20 * tau
    assert np.max(np.abs(y[late] - ref[late])) < (w * DT) ** 2 / 8


@pytest.mark.parametrize("name, params", [("transport_delay", {"delay": 0.0173}), ("first_order_lag", {"tau": 0.03})])
def test_real_time_step_is_the_batch(name, params):
    eff = get_effect(name)
    t, x = _signal(2 * BUFFER + 300)
    batch = eff.apply(Signals(t=t, x=x), params)
    st = eff.make_step(params)
    steps = np.array([st.step(t=float(a), x=float(b)) for a, b in zip(t, x)])
    np.testing.assert_array_equal(steps, batch)
    st.reset()                                  # after a reset the same run again, in two batches
    first = st.run(t=t[:1000], x=x[:1000])
    np.testing.assert_array_equal(np.concatenate([first, st.run(t=t[1000:], x=x[1000:])]), batch)


def test_lags_are_the_links_input_and_bad_values_are_refused():
    from teleop.core.errors import InputError
    t, x = _signal(100)
    for name in ("transport_delay", "first_order_lag"):
        eff = get_effect(name)
        assert eff.link == "position" and eff.inputs == ("t", "x") and eff.output == "x"
        assert eff.rules.reading and eff.rules.primary
    with pytest.raises(InputError, match="'tau' must be > 0"):
        get_effect("first_order_lag").apply(Signals(t=t, x=x), {"tau": 0.0})
    with pytest.raises(InputError, match="'delay' must be >= 0"):
        get_effect("transport_delay").apply(Signals(t=t, x=x), {"delay": -0.01})
