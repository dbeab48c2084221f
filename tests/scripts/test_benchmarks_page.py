"""scripts/benchmarks.py render: docs/benchmarks.md's table for a bench's wrapped JSON (a fixture, no bench
run, no timing)."""

import importlib.util
import shutil
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
SCRIPT = HERE.parents[1] / "scripts" / "benchmarks.py"


@pytest.fixture(scope="module")
def benchmarks():
    spec = importlib.util.spec_from_file_location("benchmarks_script", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_render_writes_the_fixture_table(benchmarks, tmp_path):
    data = tmp_path / "benchmarks"
    data.mkdir()
    shutil.copy(HERE / "fixtures" / "feedforward.json", data / "feedforward.json")
    page = tmp_path / "benchmarks.md"
    text = benchmarks.render(data, page)
    assert page.read_text() == text
    section = text.split("## feedforward\n", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ")]
    assert rows == [
        "| figure | value |",
        "| play width | 0.5 mm |",
        "| feed-forward width | 0.5 mm |",
        "| tip error, plain: RMS / p95 / max | 0.396 / 0.467 / 0.514 mm |",
        "| tip error, compensated: RMS / p95 / max | 0.105 / 0.229 / 0.361 mm |",
        "| tip error, no play: RMS / p95 / max | 0.0188 / 0.0266 / 0.0316 mm |",
        "| RMS ratio (plain / compensated) | 3.78 x |",
        "| pass | yes |",
    ]
    assert ("Command: `teleop bench feedforward --seconds 10 --seed 0 --json F`; machine: 2 cores, Test CPU 3000, "
            "Python 3.11.7; date: 2026-01-02 03:04 UTC.") in section
    # every other bench is listed as not run, with its command
    not_run = text.split("## Not yet run\n", 1)[1]
    for bench in benchmarks.BENCHES:
        assert (f"- {bench.name}:" in not_run) == (bench.name != "feedforward")


def test_a_key_the_result_lacks_is_left_out(benchmarks):
    rows = dict(benchmarks.feedforward_rows({"ratio_rms": 2.0, "sessions": {"plain": {"tip_error_mm": {}}}}))
    assert rows == {"RMS ratio (plain / compensated)": "2 x"}
