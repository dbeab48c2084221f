"""The position-link models on a real instrument (MRDLab mis-tool-characterization, da Vinci tool 4).

Contains data from the MRDLab mis-tool-characterization dataset, ODbL 1.0.
"""


import numpy as np
import pytest

from teleop.core.physics import Signals, fit

from tests._data import MRDLAB as DATA, needs_mrdlab

pytestmark = needs_mrdlab


@pytest.mark.parametrize("run", ["tool4_left_03.TXT", "tool4_left_43.TXT"])
def test_backlash_explains_the_jaw_lag_of_a_real_instrument(run):
    a = np.loadtxt(DATA / run, comments="%", delimiter=",")
    t = np.arange(a.shape[0]) * 1e-3
    spindle = a[:, 1] / 8192 * 2 * np.pi  # rad
    jaw = a[:, 4] / 4000 * 2 * np.pi      # rad
    gain, offset = np.polyfit(spindle, jaw, 1)
    x = gain * spindle + offset           # rigid transmission prediction of the jaw angle
    rigid = float(np.sqrt(np.mean((x - jaw) ** 2)))
    res = fit("backlash", Signals(t=t, x=x), jaw)
    # the play operator halves the error of a rigid transmission; the play is a couple of degrees
    assert res.rmse < 0.5 * rigid
    assert np.deg2rad(0.5) < res.params["width"] < np.deg2rad(5.0)
