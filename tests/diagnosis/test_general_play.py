"""Backlash's general form (a tendon in a sheath: an elastic part, a wide slow play, a lag growing with the
position, the play's start in its band): the per-sample and array forms agree, the plain form is the play
operator bit for bit, and the diagnosis takes the general form where a recording has it (recovering its
parameters) and keeps the plain play where it does not. The recordings are made sample by sample with the
Step form (the simulation's path), on trajectories unlike the real instrument's sine.
Contains data from the MRDLab mis-tool-characterization dataset, ODbL 1.0 (the real-run check)."""

import numpy as np
import pytest

from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange, read_recording, write_interchange
from teleop.core.physics import Signals, get_effect
from teleop.core.physics.backlash import backlash
from tests._data import MRDLAB, needs_mrdlab
from tests._signals import multisine

GENERAL = {"width": 0.06, "elastic": 0.3, "tail": 0.15, "grow": 0.4, "start": -0.7}


def _trajectory(seed: int, fs: float = 500.0, seconds: float = 20.0):
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    return t, multisine(rng, t, 0.6, 3, 0.1, 0.6) + 0.8


def _stepped(params: dict, x: np.ndarray) -> np.ndarray:
    st = get_effect("backlash").make_step(params)
    return np.array([st.step(x=float(v)) for v in x])


@pytest.mark.parametrize("seed", [0, 1])
def test_step_and_array_forms_agree(seed):
    t, x = _trajectory(seed)
    eff = get_effect("backlash")
    for p in (GENERAL, {"width": 0.05, "elastic": 0.0, "tail": 0.5, "grow": -0.3, "start": 1.0}):
        assert np.max(np.abs(eff.apply(Signals(t=t, x=x), p) - _stepped(p, x))) < 1e-12
    plain = eff.apply(Signals(t=t, x=x), {"width": 0.05})
    assert np.array_equal(plain, backlash(x, 0.05))          # the plain form: the play operator itself
    assert np.array_equal(plain, _stepped({"width": 0.05}, x))


def test_general_form_shape():
    eff = get_effect("backlash")
    e, tail, grow = GENERAL["elastic"], GENERAL["tail"], GENERAL["grow"]
    w1, w2 = (1 - e) * (1 - tail), (1 - e) * tail
    r1, r2 = GENERAL["width"] / 2, 4 * GENERAL["width"] / 2
    # driven far in one direction: the lag settles at the weighted half-widths, scaled by e^(grow x)
    x = np.linspace(0.0, 1.0, 2001)
    y = eff.apply(Signals(t=x, x=x), GENERAL)
    assert y[-1] == pytest.approx(1.0 - np.exp(grow) * (w1 * r1 + w2 * r2), rel=1e-12)
    # right after the reversal both plays hold: y = x + e^(grow x) (w1 (z1 - x) + w2 (z2 - x)) with z fixed,
    # whose slope is 1 - e^(grow x) (w1 + w2) + grow (y - x): the elastic part follows at once
    back = np.r_[x, 1.0 - np.linspace(0.0, 1e-4, 11)[1:]]
    yb = eff.apply(Signals(t=np.arange(back.size) * 1.0, x=back), GENERAL)
    slope = (yb[-1] - yb[-2]) / (back[-1] - back[-2])
    assert slope == pytest.approx(1 - np.exp(grow * back[-1]) * (w1 + w2) + grow * (yb[-1] - back[-1]), rel=1e-4)


@pytest.mark.parametrize("seed, general", [(3, True), (4, False)])
def test_diagnosis_takes_the_general_form_where_the_data_has_it(tmp_path, seed, general):
    t, x = _trajectory(seed)
    rng = np.random.default_rng(seed + 100)
    gain, offset = -0.9, 1.4
    params = GENERAL if general else {"width": GENERAL["width"]}
    tip = _stepped(params, gain * x + offset)
    path = write_interchange(tmp_path / "g.csv", t,
                             {"motor_pos": x + rng.normal(0, 2e-4, t.size),
                              "tip_pos": tip + rng.normal(0, 5e-4, t.size)},
                             {"motor_pos": "rad", "tip_pos": "rad"}, {"load": "external"})
    doc = diagnose(read_interchange(path)).as_dict()
    first = doc["findings"][0]
    assert first["effect"] == "backlash"
    p = first["params"]
    assert p["width"]["value"] == pytest.approx(GENERAL["width"], rel=0.2)   # the main play's width
    if general:
        # the fit refers the lag's scale to the record's mean tip position x_ref (the truth's reference is 0):
        # the part that follows at once there is 1 - (1 - elastic) e^(grow x_ref)
        x_ref = p["x_ref"]["value"]
        assert x_ref == pytest.approx(float(np.mean(tip)), abs=0.01)
        elastic = 1 - (1 - GENERAL["elastic"]) * np.exp(GENERAL["grow"] * x_ref)
        assert p["elastic"]["value"] == pytest.approx(elastic, abs=0.1)
        assert p["tail"]["value"] == pytest.approx(GENERAL["tail"], abs=0.1)
        assert p["grow"]["value"] == pytest.approx(GENERAL["grow"], abs=0.2)
        assert doc["channels"]["tip_pos"]["rmse_model"] < 1e-3   # the noise is 0.5 mrad
    else:
        assert "elastic" not in p                              # the plain play is kept


@needs_mrdlab
def test_real_jaw_beats_the_generic_peer():
    # the da Vinci jaw at 10 % reaction torque, where a plain play lost to PySINDy (4.26 vs 2.19 mrad)
    doc = diagnose(read_recording(MRDLAB / "tool4_left_00.TXT", "mrdlab"), sindy=True).as_dict()
    peer = doc["peer"]["tip_pos"]
    assert peer["model_rmse"] <= peer["sindy_rmse"]
    assert "elastic" in next(f for f in doc["findings"] if f["channel"] == "tip_pos")["params"]
