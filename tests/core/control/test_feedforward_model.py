"""Backlash pre-compensation on a simulated position link, and the saved model loading back."""

import numpy as np
import pytest

from teleop.diagnosis.diagnose import diagnose
from teleop.core.control.feedforward import backlash_inverse, precompensate
from teleop.diagnosis.generator import make_case
from teleop.core.physics.links import Link, LinkModel, predict
from teleop.diagnosis.links import link_data
from teleop.io.model_io import load_model, save_model
from teleop.io.recording_io import read_interchange
from teleop.core.physics import Signals, get_effect


def _simulated_tip(motor, gain, offset, width):
    """The simulated robot's position link, sample by sample (physics Step): tip = play(g x + c)."""
    st = get_effect("backlash").make_step({"width": width})
    return np.array([st.step(x=gain * m + offset) for m in motor])


def test_backlash_inverse_is_exact_for_the_play_operator():
    t = np.linspace(0, 4, 2001)
    y_d = 2e-3 * np.sin(2 * np.pi * 0.7 * t) + 0.5e-3 * np.sin(2 * np.pi * 1.9 * t)
    x = backlash_inverse(y_d, 0.6e-3)
    y = get_effect("backlash").apply(Signals(t=t, x=x), {"width": 0.6e-3})
    # after the first motion the tip follows the wanted path exactly
    np.testing.assert_allclose(y[5:], y_d[5:], atol=1e-12)


def test_precompensation_cuts_tip_tracking_error_on_simulated_link():
    gain, offset, width = -0.9, 0.2, 0.04          # rad/rad, rad, rad (a da Vinci-like jaw)
    model = LinkModel(Link("position", "tip_pos", "motor_pos", "motor_pos"), gain, offset,
                      effects=(("backlash", {"width": width}),))
    t = np.arange(0, 10, 1e-3)
    target = 0.5 + 0.3 * np.sin(2 * np.pi * 0.5 * t)
    plain = (target - offset) / gain                # the ideal-link command
    comp = precompensate(model, target)
    e_plain = target - _simulated_tip(plain, gain, offset, width)
    e_comp = target - _simulated_tip(comp, gain, offset, width)
    rms = lambda e: float(np.sqrt(np.mean(e[1000:] ** 2)))
    assert rms(e_plain) == pytest.approx(width / 2, rel=0.1)
    assert rms(e_comp) < rms(e_plain) / 20


def test_identified_backlash_saved_loaded_and_precompensates(tmp_path):
    case = make_case(0, "backlash", "rig", seed=7)
    case.write(tmp_path / "c.csv")
    diag = diagnose(read_interchange(tmp_path / "c.csv"))
    save_model(tmp_path / "m.json", [r.final.model for r in diag.links], "c.csv")
    model = load_model(tmp_path / "m.json")
    assert [n for n, _ in model.effects("position")] == ["backlash"]
    steps = model.steps("position")                  # per-sample physics objects for sim and estimator
    assert steps[0].step(x=0.0) == 0.0
    pos = model.model("position")
    true_w = case.params["width"]
    assert pos.effects[0][1]["width"] == pytest.approx(true_w, rel=0.2)
    t = np.arange(0, 8, 2e-3)
    target = 3e-3 * np.sin(2 * np.pi * 0.4 * t)
    plain = (target - pos.offset) / pos.gain
    comp = precompensate(pos, target)
    # the true link (true width) with the identified gain/offset: error falls with the identified inverse
    e_plain = target - _simulated_tip(plain, pos.gain, pos.offset, true_w)
    e_comp = target - _simulated_tip(comp, pos.gain, pos.offset, true_w)
    assert np.sqrt(np.mean(e_comp[500:] ** 2)) < 0.3 * np.sqrt(np.mean(e_plain[500:] ** 2))
    rec = read_interchange(tmp_path / "c.csv")
    pred = predict(link_data(rec, pos.link), pos)
    assert np.sqrt(np.mean((pred - rec.channels["tip_pos"]) ** 2)) < 0.2 * true_w
