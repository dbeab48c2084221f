"""The backlash feed-forward of the robot's command path (teleop.diagnosis.feedforward.BacklashFeedforward)."""

import numpy as np
import pytest

from teleop.diagnosis.feedforward import BacklashFeedforward, backlash_inverse, model_backlash_width
from teleop.diagnosis.links import Link, LinkModel
from teleop.diagnosis.model_io import IdentifiedModel
from teleop.errors import InputError
from teleop.physics.backlash import backlash

W = 0.5e-3  # play width [m]


def _wanted(n=4000, dt=1e-3, seed=0):
    """(n, 3) wanted lengths [m]: three sines of different periods around 25 mm, plus 2 um RMS noise."""
    t = np.arange(n) * dt
    rng = np.random.default_rng(seed)
    y = 0.025 + np.column_stack([1.5e-3 * np.sin(2 * np.pi * f * t) for f in (0.5, 0.8, 1.3)])
    return t, y + rng.normal(0.0, 2e-6, y.shape)


def _run(ff, y):
    return np.array([ff.step(row).copy() for row in y])


def test_the_play_delivers_the_wanted_lengths_after_each_reversal():
    t, y = _wanted()
    ff = BacklashFeedforward(W, 3, max_step=0.02 * 1e-3)        # v_max 20 mm/s at 1 kHz
    x = _run(ff, y)
    real = np.column_stack([backlash(x[:, i], W) for i in range(3)])
    err = np.abs(real - y)
    plain = np.abs(np.column_stack([backlash(y[:, i], W) for i in range(3)]) - y)
    rms = lambda e: float(np.sqrt(np.mean(e[500:] ** 2)))
    assert rms(plain) == pytest.approx(W / 2, rel=0.15)
    assert rms(err) < rms(plain) / 5
    # between reversals (away from the crossings) the cable is where it is wanted, to the noise
    assert np.median(err[500:]) < 5e-6


def test_each_command_moves_at_most_max_step_and_stays_within_limits():
    t, y = _wanted()
    step = 0.02e-3
    lo, hi = 0.0240, 0.0262   # the wanted lengths touch both limits
    ff = BacklashFeedforward(W, 3, max_step=step, lo=lo, hi=hi)
    x = _run(ff, np.clip(y, lo, hi))
    assert np.abs(np.diff(x, axis=0)).max() <= step * (1 + 1e-12)
    assert x.min() >= lo and x.max() <= hi
    # a reversal's jump of a whole width is spread over several commands
    jumps = np.abs(np.diff(x, axis=0)) > 0.9 * step
    assert jumps.sum() >= W / step


def test_the_dead_band_keeps_noise_from_chattering_the_command():
    rng = np.random.default_rng(3)
    y = 0.025 + rng.normal(0.0, 3e-6, (2000, 1))    # a cable held still, with 3 um of noise
    ff = BacklashFeedforward(W, 1, max_step=1.0, deadband=20e-6)
    x = _run(ff, y)[:, 0]
    assert np.abs(x - y[:, 0]).max() < 1e-12           # never left the centre: no crossing of the play
    ff0 = BacklashFeedforward(W, 1, max_step=1.0, deadband=0.0)
    x0 = _run(ff0, y)[:, 0]
    assert np.count_nonzero(np.abs(np.diff(x0)) > W / 2) > 100   # without it: a crossing at nearly every sample


def test_the_array_form_is_the_same_kernel_without_limits():
    t, y = _wanted(n=1500)
    ff = BacklashFeedforward(W, 1, max_step=np.inf, deadband=0.0)
    np.testing.assert_array_equal(_run(ff, y[:, :1])[:, 0], backlash_inverse(y[:, 0], W))


def test_reset_centres_the_play_again():
    ff = BacklashFeedforward(W, 1, max_step=1.0, deadband=0.0)
    ff.step(np.array([0.025]))
    assert ff.step(np.array([0.026]))[0] == pytest.approx(0.026 + W / 2)
    ff.reset()
    assert ff.step(np.array([0.027]))[0] == 0.027


@pytest.mark.parametrize("kw", [{"width": -1e-3}, {"width": np.nan}, {"max_step": 0.0}, {"deadband": -1.0},
                                {"lo": 1.0, "hi": 0.0}])
def test_bad_settings_are_input_errors(kw):
    args = {"width": W, "max_step": 1e-5} | kw
    with pytest.raises(InputError):
        BacklashFeedforward(args.pop("width"), 6, **args)


def test_the_width_comes_from_the_position_link_of_a_model():
    pos = LinkModel(Link("position", "tip_pos", "motor_pos", "motor_pos"), 1.0, 0.0,
                    effects=(("backlash", {"width": 4e-4}),))
    assert model_backlash_width(IdentifiedModel("x", {"position": pos})) == 4e-4
    bare = LinkModel(Link("position", "tip_pos", "motor_pos", "motor_pos"), 1.0, 0.0)
    with pytest.raises(InputError, match="M.json: no backlash"):
        model_backlash_width(IdentifiedModel("x", {"position": bare}), "M.json")
