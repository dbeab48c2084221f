"""Fitted parameters that contradict an effect's defining signature do not name it (identify.wrong_form)."""

import numpy as np

from teleop.diagnosis.identify import wrong_form
from teleop.core.physics.links import Link, LinkData


def test_a_dahl_transition_shorter_than_one_sample_of_drive_travel_is_coulomb_not_dahl():
    # a session's drive moves ~3 um a sample; a Dahl of Fc/sigma = 0.03 um switches within one sample: it is
    # the Coulomb law's jump (it had won a few per cent by splitting the reversal's sample); 150 um is a
    # pre-sliding regime the data resolve
    t = np.arange(2000) * 1e-3
    x = 1.5e-3 * np.sin(np.pi * t)
    d = LinkData(Link("force", "motor_force", "tip_force", "motor_pos"), t, np.ones_like(t), np.ones_like(t),
                 x, None, None, None)
    assert wrong_form("dahl_hysteresis", {"sigma": 1e7, "Fc": 0.3}, d)
    assert not wrong_form("dahl_hysteresis", {"sigma": 2000.0, "Fc": 0.3}, d)
