"""The backlash feed-forward of the robot's command path (teleop.core.control.feedforward.BacklashFeedforward)."""

import numpy as np
import pytest

from teleop.core.control.feedforward import BacklashFeedforward, model_backlash_width
from teleop.core.physics.links import Link, LinkModel
from teleop.io.model_io import IdentifiedModel
from teleop.core.errors import InputError
from teleop.core.physics.backlash import backlash

W = 0.5e-3       # play width [m]
DT = 1e-3        # command period [s]
V_MAX = 0.020    # [m/s]


def _wanted(n=4000, seed=0):
    """(n, 3) wanted lengths [m]: three sines of different periods around 25 mm, plus 1 um RMS noise."""
    t = np.arange(n) * DT
    rng = np.random.default_rng(seed)
    y = 0.025 + np.column_stack([1.5e-3 * np.sin(2 * np.pi * f * t) for f in (0.5, 0.8, 1.3)])
    return y + rng.normal(0.0, 1e-6, y.shape)


def _run(ff, y):
    return np.array([ff.step(row).copy() for row in y])


def _play(x, y0):
    return np.column_stack([backlash(np.r_[y0[i], x[:, i]], W)[1:] for i in range(x.shape[1])])


def test_the_play_delivers_the_wanted_lengths():
    y = _wanted()
    x = _run(BacklashFeedforward(W, 3, DT, V_MAX), y)
    err = np.abs(_play(x, y[0]) - y)
    plain = np.abs(_play(y, y[0]) - y)
    rms = lambda e: float(np.sqrt(np.mean(e[500:] ** 2)))
    assert rms(plain) == pytest.approx(W / 2, rel=0.15)
    assert rms(err) < rms(plain) / 5
    assert np.median(err[500:]) < 5e-6      # away from the reversals the cable is where it is wanted


def test_each_command_moves_at_most_v_max_dt_and_stays_within_limits():
    y = _wanted()
    lo, hi = 0.0240, 0.0262   # the wanted lengths touch both limits
    x = _run(BacklashFeedforward(W, 3, DT, V_MAX, lo=lo, hi=hi), np.clip(y, lo, hi))
    assert np.abs(np.diff(x, axis=0)).max() <= V_MAX * DT * (1 + 1e-12)
    assert x.min() >= lo and x.max() <= hi
    assert np.abs(x - np.clip(y, lo, hi)).max() <= W / 2 * (1 + 1e-12)   # never more than half the play ahead


def test_a_wanted_length_at_rest_holds_the_cable_whatever_the_noise():
    rng = np.random.default_rng(3)
    y = 0.025 + rng.normal(0.0, 3e-6, (3000, 1))    # a cable held still, with 3 um of noise per command
    x = _run(BacklashFeedforward(W, 1, DT, V_MAX), y)
    real = _play(x, y[0])[:, 0]
    # the noise moves the motor inside the play only: the cable stays within the noise's own band
    assert np.abs(real - 0.025).max() <= np.abs(y - 0.025).max()
    assert np.abs(x[:, 0] - y[:, 0]).max() < W / 2


def test_reset_centres_the_play_again():
    ff = BacklashFeedforward(W, 1, DT, 10.0)
    assert ff.step(np.array([0.025]))[0] == 0.025               # at rest: centred
    assert ff.step(np.array([0.026]))[0] == pytest.approx(0.026 + W / 2)   # fast rise: the full side
    ff.reset()
    assert ff.step(np.array([0.027]))[0] == 0.027


@pytest.mark.parametrize("kw", [{"width": -1e-3}, {"width": np.nan}, {"period": 0.0}, {"v_max": 0.0}, {"v0": 0.0},
                                {"tau": -1.0}, {"lo": 1.0, "hi": 0.0}])
def test_bad_settings_are_input_errors(kw):
    args = {"width": W, "period": DT, "v_max": V_MAX} | kw
    with pytest.raises(InputError):
        BacklashFeedforward(args.pop("width"), 6, **args)


def test_the_width_comes_from_the_position_link_of_a_model():
    pos = LinkModel(Link("position", "tip_pos", "motor_pos", "motor_pos"), 1.0, 0.0,
                    effects=(("backlash", {"width": 4e-4}),))
    assert model_backlash_width(IdentifiedModel("x", {"position": pos})) == 4e-4
    bare = LinkModel(Link("position", "tip_pos", "motor_pos", "motor_pos"), 1.0, 0.0)
    with pytest.raises(InputError, match="M.json: no backlash"):
        model_backlash_width(IdentifiedModel("x", {"position": bare}), "M.json")


def test_uneven_commands_take_the_rate_over_the_time_that_passed():
    """A loop running late sends commands unevenly: the same path, sampled at uneven times with those times
    given, drives the same side as the even sampling (the rate is per second, not per command)."""
    rng = np.random.default_rng(5)
    t_even = np.arange(2000) * DT
    t_uneven = np.cumsum(rng.choice([0.2e-3, 1.8e-3], 2000))   # bursts and gaps, 1 ms on average
    path = lambda t: 0.025 + 1.5e-3 * np.sin(2 * np.pi * 0.7 * t)
    even, uneven = BacklashFeedforward(W, 1, DT, 10.0), BacklashFeedforward(W, 1, DT, 10.0)
    s_even = [(even.step(path(np.array([t])))[0] - path(t)) / (W / 2) for t in t_even]
    s_uneven, prev = [], None
    for t in t_uneven:
        x = uneven.step(path(np.array([t])), None if prev is None else t - prev)[0]
        prev = t
        s_uneven.append((x - path(t)) / (W / 2))
    # away from the reversals both drive on the full side; the per-command rate would halve it in the bursts
    moving = lambda t: (np.abs(np.cos(2 * np.pi * 0.7 * t)) > 0.5) & (t > 0.05)   # after the filter's start
    assert np.abs(np.array(s_uneven)[moving(t_uneven)]).min() > 0.99
    assert np.abs(np.array(s_even)[moving(t_even)]).min() > 0.99
