"""Conformance over every registered effect: round-trip fits within 5 %, Step == apply, specs, errors."""

import json

import numpy as np
import pytest

from teleop.core.errors import InputError
from teleop.core.physics import REGISTRY, Signals, chain, fit, get_effect
from teleop.core.physics.base import ParamSpec

from ._scenarios import scenario
from ._signals import assert_params_close, noisy, step_matches_apply

CATALOGUE = ("backlash", "cable_compliance", "capstan_friction", "coulomb_friction", "viscous_friction",
             "stribeck_friction", "dahl_hysteresis", "sensor_hysteresis", "thermal_drift",
             "hertz_contact", "viscoelasticity", "contact_damping", "linear_contact")
NAMES = sorted(REGISTRY)


def test_catalogue_names_are_registered():
    assert set(CATALOGUE) <= set(REGISTRY)


@pytest.mark.parametrize("name", NAMES)
def test_round_trip_fit_recovers_parameters_within_5_percent(name):
    eff = get_effect(name)
    sc = scenario(name)
    y = noisy(eff.apply(sc.signals, dict(sc.truth, **sc.fixed)), sc.sigma, seed=11)
    res = fit(eff, sc.signals, y, fixed=sc.fixed)
    assert_params_close(res.params, sc.truth, rel=0.05)
    # the residual is the noise, and the reported standard errors cover the actual error
    assert res.rmse == pytest.approx(sc.sigma, rel=0.05)
    for k, v in sc.truth.items():
        assert abs(res.params[k] - v) <= 5 * res.stderr[k] + 1e-12 * abs(v), (k, res.stderr[k])


@pytest.mark.parametrize("name", NAMES)
def test_round_trip_from_a_bad_guess(name):
    eff = get_effect(name)
    sc = scenario(name)
    y = noisy(eff.apply(sc.signals, dict(sc.truth, **sc.fixed)), sc.sigma, seed=12)
    bad = {k: eff.spec(k).clip(v * 8.0) for k, v in sc.truth.items()}
    res = fit(eff, sc.signals, y, fixed=sc.fixed, guess=bad)
    assert_params_close(res.params, sc.truth, rel=0.05)


@pytest.mark.parametrize("name", NAMES)
def test_step_equals_apply_sample_by_sample(name):
    eff = get_effect(name)
    sc = scenario(name)
    sig = sc.signals.window(slice(0, 3000))
    step_matches_apply(eff, sig, dict(sc.truth, **sc.fixed), rtol=1e-9, atol=1e-9)
    st = eff.make_step(dict(sc.truth, **sc.fixed))
    st.reset()  # reset gives the same run again
    names = eff.inputs + tuple(c for c in eff.optional if sig[c] is not None)
    first = [st.step(**{c: float(sig[c][k]) for c in names}) for k in range(50)]
    np.testing.assert_allclose(first, eff.apply(sig, dict(sc.truth, **sc.fixed))[:50], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_specs_are_consistent(name):
    eff = get_effect(name)
    assert eff.name == name and eff.output in eff.inputs + ("x", "load", "force")
    for p in eff.params:
        assert p.lower <= p.default <= p.upper and p.unit and p.doc
        for v in (p.lower, p.default, p.upper):
            assert p.from_unit(p.to_unit(v)) == pytest.approx(v, rel=1e-12, abs=1e-12)
    json.dumps(eff.describe(), allow_nan=False)
    y = eff.apply(scenario(name).signals)  # defaults work
    assert y.shape == scenario(name).signals.t.shape and np.isfinite(y).all()


def test_signed_log_scale_spans_decades_of_either_sign():
    # a stiffness that may be negative (parallel_spring's k and g): asinh(value / tiny) maps [lower, upper]
    # onto [0, 1] monotonically, 0 to the middle, and d value / d u is the mapping's own derivative
    p = ParamSpec("k", "N/m", -1e9, 1e9, 1.0, "test", log=True, tiny=1e-6)
    vals = [-1e9, -3.0, -1e-7, 0.0, 2e-6, 0.02, 150.0, 1e9]
    units = [p.to_unit(v) for v in vals]
    assert units[0] == 0.0 and units[-1] == 1.0 and units[3] == pytest.approx(0.5) and np.all(np.diff(units) > 0)
    for v in vals:
        assert p.from_unit(p.to_unit(v)) == pytest.approx(v, rel=1e-9, abs=1e-15)
        u, h = p.to_unit(v), 1e-7
        if 0 < u - h and u + h < 1:
            slope = (p.from_unit(u + h) - p.from_unit(u - h)) / (2 * h)
            assert p.dvalue_du(v) == pytest.approx(slope, rel=1e-4)
    # the resolution is logarithmic: 0.02 and 150 are as far apart in u as 2e-3 and 15
    assert p.to_unit(150.0) - p.to_unit(0.02) == pytest.approx(p.to_unit(15.0) - p.to_unit(2e-3), rel=1e-6)
    with pytest.raises(ValueError):
        ParamSpec("k", "N/m", 0.0, 1e9, 1.0, "test", log=True, tiny=1e-6)   # a signed scale needs both signs


def test_bad_inputs_give_one_line_input_errors():
    with pytest.raises(InputError, match="unknown effect 'nope'"):
        get_effect("nope")
    t = np.arange(10) * 1e-3
    with pytest.raises(InputError, match="needs signal channel 'load'"):
        get_effect("capstan_friction").apply(Signals(t=t, x=t))
    with pytest.raises(InputError, match="unknown parameter 'w'"):
        get_effect("backlash").apply(Signals(t=t, x=t), {"w": 1.0})
    with pytest.raises(InputError, match="channel 'x' has shape"):
        Signals(t=t, x=np.zeros(3))
    with pytest.raises(InputError, match="NaN"):
        Signals(t=t, x=np.full(10, np.nan))
    with pytest.raises(InputError, match="strictly increasing"):
        Signals(t=t[::-1])
    with pytest.raises(InputError, match="target must be"):
        fit("backlash", Signals(t=t, x=t), np.zeros(3))


def test_mask_fits_on_selected_samples_only():
    eff = get_effect("backlash")
    sc = scenario("backlash")
    y = eff.apply(sc.signals, sc.truth)
    y_bad = y.copy()
    y_bad[: y.size // 2] += 1e-3  # a corrupted first half must not matter when masked out
    res = fit(eff, sc.signals, y_bad, mask=np.arange(y.size) >= y.size // 2)
    assert_params_close(res.params, sc.truth, rel=1e-3)
    assert res.m == y.size - y.size // 2


def test_chain_fits_contact_stack_jointly_and_steps_like_apply():
    sc = scenario("viscoelasticity")
    sls = chain("linear_contact", "viscoelasticity")
    assert sls.inputs == ("d", "t") and sls.param_names == ("linear_contact.k", "viscoelasticity.g",
                                                            "viscoelasticity.tau")
    truth = {"linear_contact.k": 800.0, "viscoelasticity.g": 0.6, "viscoelasticity.tau": 0.7}
    sig = Signals(t=sc.signals.t, d=sc.signals.d)
    y = noisy(sls.apply(sig, truth), 0.01, seed=3)
    res = fit(sls, sig, y, guess={"linear_contact.k": 500.0})
    assert_params_close(res.params, truth)
    step_matches_apply(sls, sig.window(slice(0, 2000)), truth, rtol=1e-9, atol=1e-9)
    # a single-effect chain is that effect
    one = chain("linear_contact")
    np.testing.assert_array_equal(one.apply(sig, {"linear_contact.k": 800.0}),
                                  get_effect("linear_contact").apply(sig, {"k": 800.0}))


def test_package_example_pad_stack_and_fit_plot():
    sc = scenario("contact_damping")
    pad = chain("hertz_contact", "viscoelasticity", "contact_damping")
    assert set(pad.inputs) == {"d", "t", "d_dot"}
    sig = Signals(t=sc.signals.t, d=sc.signals.d)
    F = pad.apply(sig)
    assert np.all(F >= 0) and np.all(F[sig.d <= 0] == 0) and F.max() > 0
    step_matches_apply(pad, sig.window(slice(0, 500)), pad.defaults(), rtol=1e-9, atol=1e-9)
    res = fit("linear_contact", sig, noisy(get_effect("linear_contact").apply(sig, {"k": 900.0}), 0.01))
    ax = res.plot(sig, get_effect("linear_contact").apply(sig, {"k": 900.0}))
    assert len(ax.get_lines()) == 2


def test_parameter_values_outside_physics_are_refused():
    t = np.arange(10) * 1e-3
    with pytest.raises(InputError, match="'width' must be >= 0"):
        get_effect("backlash").apply(Signals(t=t, x=t), {"width": -1e-3})
    with pytest.raises(InputError, match="'tau' must be > 0"):
        get_effect("viscoelasticity").make_step({"tau": 0.0})
    with pytest.raises(InputError, match="'k' must be > 0"):
        get_effect("cable_compliance").apply(Signals(t=t, x=t, load=t), {"k": 0.0})
    # zero play is physical: the tip follows the motor exactly
    np.testing.assert_array_equal(get_effect("backlash").apply(Signals(t=t, x=t), {"width": 0.0}), t)


def test_the_docs_catalogue_table_is_the_registry():
    # docs/diagnosis.md's catalogue table is the registry's listing; regenerate it with
    # `python -m teleop.core.physics.catalogue docs/diagnosis.md`
    from pathlib import Path

    from teleop.core.physics.catalogue import catalogue_rows, with_table

    doc = Path(__file__).resolve().parents[3] / "docs" / "diagnosis.md"
    text = doc.read_text(encoding="utf-8")
    assert with_table(text) == text, "docs/diagnosis.md's catalogue table differs from the registry"
    assert [r["effect"] for r in catalogue_rows()] == list(REGISTRY)
    for name in REGISTRY:
        assert f"\n| {name} | {get_effect(name).link} |" in text
