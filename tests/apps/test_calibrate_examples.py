"""examples/calibration holds a recording for every `teleop calibrate` kind (issue 28 item 6): the commands the
docs show (examples/README.md, docs/formats.md) run on a plain clone's layout (the examples directory alone,
from its root) and write what the docs say; the shipped files are what the generator writes (not stale)."""

import re
import shlex
import shutil
from pathlib import Path

import pytest

from teleop.apps.cli import main
from teleop.apps.commands.calibrate import KINDS
from teleop.io import calfile
from teleop.io.calibration_csv import write_examples

ROOT = Path(__file__).resolve().parents[2]


def documented(page: Path, inline: bool = True) -> list:
    """The `teleop calibrate ...` commands a page shows in a bash block and, with `inline`, in backticks
    (whitespace folded)."""
    text = page.read_text(encoding="utf-8")
    spans = re.findall(r"`(teleop calibrate [^`]+)`", re.sub(r"\s+", " ", text)) if inline else []
    lines = [line.split("#")[0].strip() for line in text.splitlines() if line.startswith("teleop calibrate ")]
    return sorted(set(spans) | set(lines))


def test_shipped_recordings_are_what_the_generator_writes(tmp_path):
    for path in write_examples(tmp_path):
        shipped = ROOT / "examples" / "calibration" / path.name
        assert shipped.read_bytes() == path.read_bytes(), f"{shipped}: run python -m teleop.io.calibration_csv " \
                                                          f"examples/calibration"


def test_every_kind_has_an_example_command_in_the_docs():
    readme = documented(ROOT / "examples" / "README.md")
    kinds = {shlex.split(c)[2] for c in readme}
    assert kinds == set(KINDS)
    shown = documented(ROOT / "docs" / "formats.md", inline=False)
    assert len(shown) == len(KINDS) and set(shown) <= set(readme)  # formats.md shows the same commands


@pytest.mark.parametrize("command", documented(ROOT / "examples" / "README.md"))
def test_example_command_runs_on_a_plain_clone_and_writes_what_the_docs_say(tmp_path, monkeypatch, capsys, command):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    argv = shlex.split(command)
    assert argv[0] == "teleop"
    assert main(argv[1:]) == 0
    out = Path(argv[argv.index("--out") + 1])
    printed = capsys.readouterr().out
    assert f"wrote {out}, {out.with_suffix('.png')}" in printed and "+/-" in printed
    kind, _ = calfile.load_calibration(out)
    assert kind == argv[2]
    assert out.with_suffix(".png").stat().st_size > 10_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["examples", "out"]  # nothing else written
