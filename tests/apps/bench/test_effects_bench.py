"""teleop bench effects: every registered effect of the catalogue is timed, in both of its forms, and the
command writes what it prints (the times themselves are this machine's, not asserted)."""

import json

from teleop.apps.bench.effects import bench_effects
from teleop.apps.cli import main
from teleop.core.physics.base import REGISTRY


def test_every_registered_effect_is_timed():
    out = bench_effects(samples=200, repeat=1, step_samples=20)
    assert out["samples"] == 200
    assert set(out["apply_ms"]) == set(REGISTRY) == set(out["step_us"])
    assert all(v["min"] >= 0 and v["p50"] >= v["min"] for v in out["apply_ms"].values())


def test_the_command_writes_its_json(tmp_path, capsys):
    path = tmp_path / "effects.json"
    assert main(["bench", "effects", "--samples", "200", "--repeat", "1", "--json", str(path)]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert json.loads(path.read_text()) == printed and set(printed["apply_ms"]) == set(REGISTRY)
