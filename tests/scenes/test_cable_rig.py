"""Recordings of the simulated single-cable bench (scenes.cable_rig, made apart from the diagnosis: they
share only the physics models), in the column subsets a lab records: the sheath's capstan friction is the
baseline, not a finding; each effect is named on the channel it shows on; physics outside the catalogue
is `unexplained`; effects the columns cannot show give `none`."""

import pytest

from scenes.cable_rig import observable, simulate
from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange

SPRING_NO_TIP = ("motor_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")
ALL = ("motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")


def _diagnose(tmp_path, seed, effects, columns, load="spring", full=False, **kw):
    rig = simulate(seed, effects, columns, load)
    path = tmp_path / "rig.csv"
    rig.write(path)
    diag = diagnose(read_interchange(path), **kw)
    return (rig, diag.as_dict(), diag) if full else (rig, diag.as_dict())


@pytest.mark.parametrize("effect, seed", [("none", 1), ("backlash", 2), ("coulomb_friction", 3),
                                          ("dahl_hysteresis", 4), ("sensor_hysteresis", 5),
                                          ("thermal_drift", 6), ("viscous_friction", 7)])
def test_spring_rig_without_tip_position(tmp_path, effect, seed):
    rig, doc, diag = _diagnose(tmp_path, [seed, 11], (effect,), SPRING_NO_TIP, full=True)
    assert doc["baseline"]["effects"]["motor_force"] == ["capstan_friction"]
    # the final model's capstan recovers the sheath's friction coefficient (the bend is recorded)
    force = [res for res in diag.links if res.data.link.output == "motor_force"][0]
    mu = dict(force.final.model.effects)["capstan_friction"]["mu"]
    assert abs(mu - rig.setup["mu"]) < 0.2 * rig.setup["mu"]
    named = [f["effect"] for f in doc["findings"]]
    if effect == "none":
        assert named == [] and doc["unexplained"] == []
        return
    assert named[0] == effect, doc["findings"]
    first = doc["findings"][0]
    assert first["channel"] == rig.effects[effect]["channel"]
    assert first["improvement"] >= 2.0


def test_lossless_baseline_names_the_sheath_friction(tmp_path):
    _, doc = _diagnose(tmp_path, [8, 11], ("none",), SPRING_NO_TIP, baseline=())
    assert doc["findings"][0]["effect"] == "capstan_friction"
    assert doc["baseline"]["model"].startswith("ideal rigid lossless link")


# the rig's late tip-force sensor ("sensor_delay") is a transport_delay to the diagnosis: tests/diagnosis/test_lag_named.py
@pytest.mark.parametrize("effect, seed", [("stiffening_spring", 9), ("eccentric_pulley", 10)])
def test_physics_outside_the_catalogue_is_unexplained(tmp_path, effect, seed):
    _, doc = _diagnose(tmp_path, [seed, 11], (effect,), SPRING_NO_TIP)
    assert doc["findings"] == []
    assert doc["unexplained"], doc


def test_two_effects_named_both(tmp_path):
    rig, doc = _diagnose(tmp_path, [13, 11], ("backlash", "dahl_hysteresis"), ALL)
    named = [f["effect"] for f in doc["findings"]]
    assert set(named[:2]) == {"backlash", "dahl_hysteresis"}
    play = [f for f in doc["findings"] if f["effect"] == "backlash"][0]
    assert play["channel"] == "tip_pos"


def test_an_effect_the_columns_cannot_show_is_none(tmp_path):
    cols = ("motor_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")
    assert not observable("backlash", cols, "external")
    _, doc = _diagnose(tmp_path, [14, 11], ("backlash",), cols, load="external")
    assert doc["findings"] == []
