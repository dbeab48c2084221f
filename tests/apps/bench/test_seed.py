"""teleop bench seed: the verdict rules, the flags, the tension read at B (what the figures' numbers rest on)
and the robot-level Fig 13's turn statistics. The seed's numbers are printed beside ours, not asserted."""

import math

import numpy as np
import pytest

from scenes.tendon_sheath import TendonSheathParams, tension_at_b
from teleop.apps.bench import cable, seed
from teleop.apps.cli import main
from teleop.apps.protocols.palpation import no_load_errors
from teleop.core.errors import InputError


def test_goal_rules_take_a_factor_either_way_and_a_spread():
    assert seed.within_factor(0.2, 0.173) and seed.within_factor(0.173 / 1.49, 0.173)
    assert not seed.within_factor(0.173 / 1.6, 0.173)        # far below the hardware's error is a miss too
    assert not seed.within_factor(0.3, 0.173) and not seed.within_factor(0.0, 0.173)
    assert seed.within_spread(9.0, 9.4, 0.7) and not seed.within_spread(8.0, 9.4, 0.7)


def test_only_names_known_figures():
    assert seed.parse_only(None) == seed.FIGURES
    assert seed.parse_only("fig9, table3,fig9") == ("fig9", "table3")
    with pytest.raises(InputError, match="--only: unknown figure.*fig99"):
        seed.parse_only("fig9,fig99")


@pytest.mark.parametrize("argv,words", [
    (["bench", "seed", "--only", "fig12"], ["--only", "fig12", "fig9"]),
    (["bench", "seed", "--plant", "matched", "--cable-params", "pyproject.toml"], ["--cable-params", "distributed"]),
])
def test_bad_flags_are_one_line_exit_2(capsys, argv, words):
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    for w in words:
        assert w in err


def test_tension_at_b_meets_the_capstan_law_over_the_whole_bend():
    """In steady sliding under a hanging weight W the tension at B swings between W exp(+-mu (theta0 + theta)):
    read at B itself, not in the scaffold's first element (which misses half of that element's bend)."""
    p = TendonSheathParams()
    res = cable.fig10b(seed=0, cable=p, weights_N=[2.94, 4.9], theta_deg=30.0)
    mt = p.mu_c * (p.theta0 + math.radians(30.0))
    for c in res["cases"].values():
        assert c["tension_B_change_N"] == pytest.approx(2 * c["weight_N"] * math.sinh(mt), rel=0.02)
    # element j alone: 5/6 of theta0 at N = 20, a swing ~14 % short
    T = np.array([[1.0] * 16 + [0.5] * 4])
    assert tension_at_b(T, p)[0] == pytest.approx(0.5 * 2.0 ** (1 - 22.5 / (22.5 + 140 / 3)), rel=1e-9)


def test_no_load_errors_count_turns_and_find_the_jump_after_one():
    dt = 0.01
    x = np.r_[np.linspace(0, 1e-2, 200), np.linspace(1e-2, 0, 200)[1:], np.linspace(0, 1e-2, 200)[1:]]
    poses = np.zeros((x.size, 6))
    poses[:, 2] = x
    flat = np.zeros((x.size, 6))
    jumpy = np.zeros((x.size, 6))
    jumpy[205:215, 2] = 1.0          # just after the first turn (sample 199)
    jumpy[50, 2] = 0.1               # away from the turns
    out = no_load_errors({"a": flat, "b": jumpy}, poses, 0, x.size, 2, turn_window_s=0.5, dt=dt)
    assert out["turns"] == 2
    assert out["b"]["max_abs_near_turns_N"] == 1.0 and out["b"]["peak_to_peak_N"] == 1.0
    assert out["b"]["rmse_off_turns_N"] == pytest.approx(0.1 / math.sqrt(x.size - 100), rel=1e-3)
    assert out["a"]["rmse_N"] == 0.0


def test_table3_builds_the_blind_rig_with_the_cable_params(monkeypatch, tmp_path):
    toml = tmp_path / "cable.toml"
    toml.write_text("[tendon_sheath]\nmu_c = 0.05\n")
    seen = {}

    class Built(Exception):
        pass

    def rig(options):
        seen["options"] = options
        raise Built

    monkeypatch.setattr(seed, "SimRig", rig)
    with pytest.raises(Built):
        seed.run_figures(("table3",), 1, "distributed", cable_params=str(toml))
    assert seen["options"].plant == "distributed" and seen["options"].cable_params == str(toml)
    assert "--cable-params" in seed.command("table3", 1, "distributed", str(toml))
