"""Adding an effect is one module plus its test scenario: a throwaway effect, registered by a module written
to a temporary folder, shows in the catalogue's listing, the generator's draws and the diagnosis' candidates,
and the diagnosis names it on a recording the generator makes with it concealed."""

import importlib
import sys

import numpy as np
import pytest

from scenes.cable_rig import COLUMNS, observable, rig_effects, simulate
from teleop.apps.bench.diagnose_rig import compounds
from teleop.core.physics import REGISTRY, Signals, get_effect, unregister
from teleop.core.physics.catalogue import catalogue_rows, catalogue_table
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import case_effects, case_plan, make_case, primary
from teleop.diagnosis.identify import applicable
from teleop.diagnosis.links import find_links, link_data
from teleop.io.recording_io import read_interchange

NAME = "quadratic_drag"

MODULE = '''
"""A drag growing with the square of the drive speed, on the force link: load + a v |v|."""

import numpy as np

from teleop.core.physics.base import Effect, ParamSpec, Rules, Step, register


def _sim(s, p):
    return s.load + p["a"] * s.v * np.abs(s.v)


def _guess(s, y):
    q = s.v * np.abs(s.v)
    return {"a": float(np.dot(q, y - s.load) / max(float(np.dot(q, q)), 1e-300))}


class QuadraticDragStep(Step):
    effect_name = "quadratic_drag"

    def reset(self):
        pass

    def step(self, v, load):
        return float(load + self.params["a"] * v * abs(v))


QUADRATIC_DRAG = register(Effect(
    name="quadratic_drag", link="force", doc="drag quadratic in speed: load + a v |v|",
    params=(ParamSpec("a", "N s^2/m^2", 1e-3, 1e9, 1.0, "drag coefficient", log=True),),
    inputs=("v", "load"), output="load", simulate=_sim, guess=_guess, step_class=QuadraticDragStep,
    rules=Rules(channel="motor_force", primary=("a",),
                draw=lambda rng, s: {"a": rng.uniform(1.5, 2.5) * s.friction / s.v_fast ** 2})))
'''


@pytest.fixture
def throwaway(tmp_path):
    (tmp_path / "throwaway_effect.py").write_text(MODULE, encoding="utf-8")
    sys.path.insert(0, str(tmp_path))
    try:
        importlib.import_module("throwaway_effect")
        yield get_effect(NAME)
    finally:
        unregister(NAME)
        sys.modules.pop("throwaway_effect", None)
        sys.path.remove(str(tmp_path))
    assert NAME not in REGISTRY


def test_its_step_is_its_array_form(throwaway):
    t = np.linspace(0.0, 2.0, 400)
    sig = Signals(t=t, x=0.01 * np.sin(3 * t), load=5.0 + np.cos(t))
    st = throwaway.make_step({"a": 3.0})
    steps = [st.step(v=float(v), load=float(f)) for v, f in zip(sig.v, sig.load)]
    np.testing.assert_allclose(steps, throwaway.apply(sig, {"a": 3.0}), rtol=1e-12)


def test_a_throwaway_effect_shows_in_the_listing_the_generator_and_the_candidates(throwaway, tmp_path):
    row = [r for r in catalogue_rows() if r["effect"] == NAME]
    assert row and row[0]["link"] == "force" and row[0]["generated"] and f"| {NAME} | force |" in catalogue_table()

    assert NAME in rig_effects() and NAME in case_effects() and primary()[NAME] == ("a",)
    assert any(e == NAME for e, _ in case_plan(len(case_effects()) + 4))
    assert any(NAME in pair for pair in compounds())
    assert observable(NAME, COLUMNS, "spring") and not observable(NAME, ("motor_pos_mm", "tip_pos_mm"), "spring")
    rig = simulate([1, 2], (NAME,), COLUMNS, "external", duration_s=2.0)
    assert rig.effects[NAME]["channel"] == "motor_force" and rig.effects[NAME]["params"]["a"] > 0

    case = make_case(3, NAME, "rig", seed=5)
    assert case.channel == "motor_force" and case.params["a"] > 0
    rec = read_interchange(case.write(tmp_path / "drag.csv"))
    force = [L for L in find_links(rec) if L.kind == "force"]
    assert force and NAME in applicable(link_data(rec, force[0]))
    doc = diagnose(rec).as_dict()
    assert doc["findings"] and doc["findings"][0]["effect"] == NAME, doc["findings"]
    assert doc["findings"][0]["channel"] == "motor_force"
