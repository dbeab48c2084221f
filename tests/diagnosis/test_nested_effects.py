"""An effect that extends a simpler one (Rules.extends: Stribeck's Coulomb) is also fitted from the simpler
one's fit, and named where its extra parameters pay on held-out data."""

import numpy as np
import pytest

from scenes.cable_rig import LITERATURE, simulate
from teleop.core.physics import REGISTRY, Signals, get_effect
from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange

EXTENDING = [n for n, e in REGISTRY.items() if e.rules.extends]


def test_some_effect_extends_another():
    assert EXTENDING


@pytest.mark.parametrize("name", EXTENDING)
def test_extends_a_registered_effect_whose_parameters_it_has(name):
    eff = get_effect(name)
    simple = get_effect(eff.rules.extends)
    assert simple.link == eff.link and set(simple.param_names) <= set(eff.param_names)
    assert eff.rules.nested_starts is not None


@pytest.mark.parametrize("name", EXTENDING)
def test_nested_starts_lie_within_the_bounds(name):
    eff = get_effect(name)
    t = np.linspace(0.0, 10.0, 2001)
    x = 5e-3 * np.sin(2 * np.pi * 0.3 * t)
    sig = Signals(t=t, x=x, load=np.full(t.shape, 5.0))
    starts = eff.rules.nested_starts(get_effect(eff.rules.extends).defaults(), sig)
    assert starts
    for p in starts:
        full = eff.check(p)   # names and signs are the effect's own
        for spec in eff.params:
            assert spec.lower <= full[spec.name] <= spec.upper


def test_stribeck_found_from_the_coulomb_fit_where_its_own_guess_fails(tmp_path):
    """A literature-range spring rig whose Stribeck peak its own data-driven start misses (the fit ended at
    the Coulomb limit, three times worse on held-out data than the Coulomb friction, and Coulomb was named):
    fitted from the Coulomb fit it is named, its parameters within 20 %."""
    cols = ("motor_pos_mm", "motor_force_N", "tip_force_N", "temperature_C")
    rig = simulate([1, 7, 7], ("stribeck_friction",), cols, "spring", None, 10.0, 1.0, ranges=LITERATURE)
    path = tmp_path / "rig.csv"
    rig.write(path)
    doc = diagnose(read_interchange(path)).as_dict()
    first = doc["findings"][0]
    assert first["effect"] == "stribeck_friction", [f["effect"] for f in doc["findings"]]
    true = rig.effects["stribeck_friction"]["params"]
    for p in get_effect("stribeck_friction").rules.primary:
        assert abs(first["params"][p]["value"] - true[p]) <= 0.2 * true[p]
    assert first["improvement"] >= 2.0
