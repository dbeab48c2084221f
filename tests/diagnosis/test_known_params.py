"""Parameters the user's simulation already has (`# EFFECT.PARAM = VALUE` in the recording's metadata) are
held at that value in the baseline: the sheath's friction coefficient of a simulated robot is not refitted to
swallow a friction the simulation left out, and the JSON says which values were given."""

import pytest

from scenes.cable_rig import simulate
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.links import find_links, known_params, link_data
from teleop.io.recording_io import read_interchange
from teleop.core.errors import InputError

COLUMNS = ("motor_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg")


def _with_metadata(text: str, lines) -> str:
    head, rest = text.split("\n", 1)
    return "\n".join([head, *(f"# {k} = {v}" for k, v in lines), rest])


def test_known_mu_is_held_and_reported(tmp_path):
    rig = simulate([5, 11], ("coulomb_friction",), COLUMNS, "external")
    path = tmp_path / "rig.csv"
    path.write_text(_with_metadata(rig.csv, [("capstan_friction.mu", repr(rig.setup["mu"]))]), encoding="utf-8")
    known = diagnose(read_interchange(path)).as_dict()
    mu = known["baseline"]["params"]["motor_force"]["capstan_friction"]["mu"]
    assert mu["value"] == rig.setup["mu"] and mu["known"] is True and mu["stderr"] is None
    assert [f["effect"] for f in known["findings"]] == ["coulomb_friction"]
    fc = known["findings"][0]["params"]["Fc"]["value"]
    assert abs(fc - rig.effects["coulomb_friction"]["params"]["Fc"]) < 0.1 * rig.effects["coulomb_friction"]["params"]["Fc"]

    # without it the baseline's mu is fitted, takes part of the Coulomb band, and the finding pays less
    plain_path = tmp_path / "plain.csv"
    rig.write(plain_path)
    plain = diagnose(read_interchange(plain_path)).as_dict()
    mu_fit = plain["baseline"]["params"]["motor_force"]["capstan_friction"]["mu"]
    assert "known" not in mu_fit and mu_fit["value"] > rig.setup["mu"]
    assert known["findings"][0]["improvement"] > plain["findings"][0]["improvement"]


def test_known_params_reach_every_link(tmp_path):
    rig = simulate([2, 11], ("none",), COLUMNS, "external")
    path = tmp_path / "rig.csv"
    path.write_text(_with_metadata(rig.csv, [("capstan_friction.mu", "0.05"), ("capstan_friction.k", "2e4"),
                                             ("note.text", "other metadata with a dot")]), encoding="utf-8")
    rec = read_interchange(path)
    assert known_params(rec) == {"capstan_friction": {"mu": 0.05, "k": 2e4}}
    for link in find_links(rec):
        assert link_data(rec, link).known == {"capstan_friction": {"mu": 0.05, "k": 2e4}}


@pytest.mark.parametrize("key, value, match", [("capstan_friction.nu", "0.05", "has no parameter 'nu'"),
                                               ("capstan_friction.mu", "high", "expected a number"),
                                               ("coulomb_friction.Fc", "nan", "finite")])
def test_bad_known_params_name_the_key(tmp_path, key, value, match):
    rig = simulate([2, 11], ("none",), COLUMNS, "external")
    path = tmp_path / "rig.csv"
    path.write_text(_with_metadata(rig.csv, [(key, value)]), encoding="utf-8")
    with pytest.raises(InputError, match=match) as err:
        diagnose(read_interchange(path))
    assert key in str(err.value) and str(path) in str(err.value)
