"""links.smooth at the record's ends: a sloping signal is not lagged and the end samples do not keep their own
noise (a stateful effect starts from the first sample; a window shrunk to it there hid the MRDLab run's
pulley elongation and parallel spring, tests/diagnosis/test_parallel_spring.py)."""

import numpy as np

from teleop.diagnosis.links import smooth


def test_a_line_is_kept_to_the_ends():
    x = 0.3 + 2.0 * np.arange(200) * 1e-3
    np.testing.assert_allclose(smooth(x, 31), x, rtol=0, atol=1e-12)


def test_the_interior_is_the_centred_moving_average():
    x = np.random.default_rng(1).normal(size=300)
    y = smooth(x, 21)
    ref = np.convolve(x, np.ones(21) / 21, mode="valid")
    np.testing.assert_allclose(y[10:-10], ref, rtol=0, atol=1e-12)


def test_end_samples_do_not_keep_their_own_noise():
    noise = np.random.default_rng(2).normal(size=(400, 200))
    ends = np.array([smooth(r, 31)[[0, -1]] for r in noise])
    # a line through the 16 samples the record holds at an end: about half the noise there (not all of it)
    assert ends.std() < 0.7
