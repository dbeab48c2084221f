"""links.predict memoises each effect's output per link data (links._stage): the same numbers as a fresh
computation, the caller's own array, and the stages before a changed parameter's effect not run again."""

import math

import numpy as np

import teleop.core.physics.links as links
from teleop.core.physics.links import Link, LinkData, LinkModel, predict


def _data(kind: str) -> LinkData:
    t = np.arange(3000) * 1e-3
    x = 2e-3 * np.sin(2 * math.pi * 0.7 * t) + 1e-3 * np.sin(2 * math.pi * 1.9 * t)
    load = 5.0 + 600.0 * x
    if kind == "force":
        link = Link("force", "motor_force", "tip_force", "motor_pos")
        return LinkData(link, t, load, 1.3 * load, x, None, None, np.full(t.size, 2.5))
    link = Link("position", "tip_pos", "motor_pos", "motor_pos", "tip_force")
    return LinkData(link, t, x, 0.98 * x, x, load, None, None)


def _model(kind: str, last: float) -> LinkModel:
    if kind == "force":
        chain = (("capstan_friction", {"mu": 0.12, "theta": 2.5, "k": 2e4, "n": 0.5}),
                 ("coulomb_friction", {"Fc": 0.2}), ("viscous_friction", {"b": last}))
        return LinkModel(Link("force", "motor_force", "tip_force", "motor_pos"), 1.1, 0.3, 1.0, 1.0, chain, 1)
    chain = (("backlash", {"width": 1e-4}), ("cable_compliance", {"k": 1e4 * last}))
    return LinkModel(Link("position", "tip_pos", "motor_pos", "motor_pos", "tip_force"), 0.97, 1e-5, 1.0, 1.0,
                     chain)


def test_memoised_predictions_are_the_fresh_ones_bit_for_bit_and_the_callers_own():
    for kind in ("force", "position"):
        d = _data(kind)
        seen = [predict(d, _model(kind, v)) for v in (0.5, 0.7, 0.5, 0.9)]   # the third from the memo
        for v, y in zip((0.5, 0.7, 0.5, 0.9), seen):
            fresh = predict(_data(kind), _model(kind, v))
            assert np.array_equal(y, fresh), kind
        assert not np.array_equal(seen[0], seen[1])   # the parameter matters
        y = predict(d, _model(kind, 0.5))
        assert y.flags.writeable
        y[:] = 0.0   # the caller may change its array: the memo's is not that one
        assert np.array_equal(predict(d, _model(kind, 0.5)), seen[0])


def test_only_the_stages_from_the_changed_parameters_effect_on_run_again(monkeypatch):
    calls = []
    run = links._apply

    def counted(name, sig, p):
        calls.append(name)
        return run(name, sig, p)
    monkeypatch.setattr(links, "_apply", counted)
    d = _data("force")
    predict(d, _model("force", 0.5))
    assert calls == ["capstan_friction", "coulomb_friction", "viscous_friction"]
    calls.clear()
    predict(d, _model("force", 0.6))   # the last effect's parameter: the capstan and Coulomb stages are kept
    assert calls == ["viscous_friction"]
    calls.clear()
    m = _model("force", 0.6)
    predict(d, LinkModel(m.link, m.gain, 0.9, m.direction, m.load_sign, m.effects, m.base))   # the offset: none
    assert calls == []
    predict(d, LinkModel(m.link, 1.2, m.offset, m.direction, m.load_sign, m.effects, m.base))   # the gain: all
    assert calls == ["capstan_friction", "coulomb_friction", "viscous_friction"]
