"""`teleop bench diagnose`: the rig suite's plan is reproducible and covers subsets, loads and compounds; the
summary's rates are those of its rows, whichever source they come from."""

import json

from teleop.apps.bench.diagnose_rig import SUBSETS, compounds, rates, rig_plan
from teleop.apps.cli import main


def test_rig_plan_is_reproducible_and_varied():
    a, b = rig_plan(30, 4), rig_plan(30, 4)
    assert a == b
    assert {c["subset"] for c in a} == set(SUBSETS)
    assert {c["load"] for c in a} == {"spring", "external"}
    assert any(tuple(c["effects"]) in compounds() for c in a)


def test_rates_count_both_sources():
    rows = [{"truth": "none", "correct": True},
            {"truth": ["none"], "correct": False},
            {"truth": "backlash", "correct": True, "params_ok": True, "improved_2x": True, "improvement": 3.0},
            {"truth": ["coulomb_friction"], "correct": False, "params_ok": False, "improved_2x": True,
             "improvement": 2.5}]
    r = rates(rows)
    assert (r["effect_cases"], r["clean_cases"]) == (2, 2)
    assert r["named_first_rate"] == 0.5 and r["none_rate"] == 0.5
    assert r["params_within_20pct_rate"] == 0.5 and r["improvement_min"] == 2.5


def test_summary_matches_rows(tmp_path, capsys):
    out = tmp_path / "b.json"
    assert main(["bench", "diagnose", "--cases", "3", "--suite", "rig", "--seed", "2", "--seconds", "8",
                 "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert len(doc["rig_rows"]) == 3
    assert doc["summary"] == rates(doc["rig_rows"])
