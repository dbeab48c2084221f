"""The distributed suite of `teleop bench diagnose` on the position link: a recording of the distributed
tendon-sheath plant (scenes.tendon_sheath, LuGre friction per node: no catalogue kernel) pulling a spring
names a play whose dead zone grows with the tension, within 20 % of Kaneko's closed form over the bent length
at the 5th and 95th percentile tension, and fits the tip to its noise floor."""

from types import SimpleNamespace

import numpy as np
import pytest

from teleop.apps.bench.diagnose_distributed import distributed_plan, play_against_kaneko, run_distributed_case


def test_spring_case_names_the_tension_play_at_kanekos_dead_zone():
    case = distributed_plan(1)[0]
    assert case["load"] == "spring" and case["effect"] == "none"
    row = run_distributed_case(case, seed=1, duration_s=8.0)
    assert row["named"]["tip_pos"] == ["backlash"]
    assert row["play_tension_per_m"] > 0                      # the dead zone grows with the tension
    lo, hi = row["play_over_dead_zone_range"]                 # at the 5th and 95th percentile tension
    assert 0.8 < lo < 1.2 and 0.8 < hi < 1.2
    tip = next(p for p in row["peer"] if p["channel"] == "tip_pos")
    assert tip["model_over_noise"] < 1.2


def test_play_against_kaneko_reads_the_width_in_motor_travel():
    finding = {"effect": "backlash", "params": {"width": {"value": 2e-3}, "width_input": {"value": 1e-3}}}
    out = play_against_kaneko(finding, None, {"dead_zone_mean_m": 5e-4}, "force")
    assert out["play_width_m"] == 1e-3 and out["play_over_dead_zone"] == pytest.approx(2.0)
    assert "play_over_dead_zone_range" not in out            # no tension growth reported without it
    assert "play_take_up_m" not in out                       # nor a take-up length at a sharp take-up
    finding["params"]["take_up"] = {"value": 0.2}
    rounded = play_against_kaneko(finding, None, {"dead_zone_mean_m": 5e-4}, "force")
    assert rounded["play_take_up_m"] == pytest.approx(0.2 * 1e-3 / 2)   # in motor travel, over the half-width


def test_play_against_kaneko_reads_the_width_growing_with_the_recorded_force():
    # under an external force the width grows with the tip force itself: w (1 + c (|T| - T_ref) / T_ref) at the
    # force's 5th and 95th percentile, against Kaneko's there
    force = np.linspace(2.0, 10.0, 1001)
    rec = SimpleNamespace(channels={"tip_force": force})
    finding = {"effect": "backlash", "params": {"width": {"value": 1e-3}, "load_tension": {"value": 1.0},
                                                "load": {"value": 6.0}}}
    q = np.percentile(force, [5, 95])
    kaneko = list(1e-3 * q / 6.0)                             # proportional to the tension, 1 mm at 6 N
    out = play_against_kaneko(finding, rec, {"dead_zone_mean_m": 1e-3, "dead_zone_range_m": kaneko}, "force")
    assert out["play_load_tension"] == 1.0
    assert out["play_width_range_m"] == pytest.approx(kaneko, rel=1e-12)
    assert out["play_over_dead_zone_range"] == pytest.approx([1.0, 1.0], rel=1e-12)
