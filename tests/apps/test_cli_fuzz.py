"""Fuzzing the whole `teleop` command line: random flag values, missing, unreadable, binary and directory
inputs, uncreatable and directory outputs, in every subcommand (found by walking the parser, so a new
subcommand or option is fuzzed without editing this file).

Whatever the arguments: no traceback (any exception out of `teleop.apps.cli.main` fails), exit code 0 or 2 (1 for
`replay`'s "differs"), and on exit 2 exactly one stderr line naming a flag or a file of the command line, and
no output file created. Commands whose work is long (studies, benchmarks, the loop) only have their checks
run: their work functions are replaced by a sentinel, and half of their command lines get an argument that
is surely bad (a directory or uncreatable output, a missing input, letters for a number, an unknown option);
reaching the sentinel with one means it was found only after the work had started, which fails the test.
"""

from __future__ import annotations

import argparse
import importlib
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from teleop.apps import argtypes
from teleop.apps.cli import build_parser, main
from teleop.loop.session import run_session as REAL_RUN_SESSION

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# commands cheap enough to run for real on any arguments (the rest only get their checks fuzzed)
CHEAP = {("geometry",), ("export",), ("replay",)}

# where each long command's work begins: module, attribute
WORK = [("teleop.apps.protocols.palpation", "run_test"), ("teleop.apps.protocols.blind.rig", "SimRig"),
        ("teleop.apps.protocols.blind.rig", "RehearsalStation"), ("teleop.apps.protocols.blind.rig", "BackgroundSession"),
        ("teleop.apps.protocols.blind.rig", "transparency"), ("teleop.apps.protocols.blind.human", "run_human_study"),
        ("teleop.loop.session", "run_session"), ("teleop.diagnosis.diagnose", "diagnose"),
        ("teleop.diagnosis.generator", "case_plan"), ("teleop.apps.bench.tick", "bench_tick"),
        ("teleop.apps.bench.sim", "bench_sim"), ("teleop.apps.bench.effects", "bench_effects"),
        ("devices.arduino.build", "build_firmware"),
        ("teleop.apps.bench.cable", "fig9"), ("teleop.apps.bench.cable", "fig11"), ("teleop.apps.bench.cable", "fig13"),
        ("teleop.apps.bench.cable", "fig10b"), ("teleop.apps.bench.seed", "run_figures"),
        ("teleop.apps.campaign.runner", "run_campaign"),
        ("teleop.apps.bench.session_diagnosis", "bench_session_diagnosis")]
# A new long command: add where its work begins here, or the fuzzer runs that work for real on every valid
# command line it draws (slow, though still checked for tracebacks and one-line errors).


class WorkStarted(BaseException):
    """Raised by the sentinels: not an Exception, so no handler in the code under test swallows it."""


def _sentinel(*args, **kwargs):
    raise WorkStarted("the work started before every argument was checked")


def replace_everywhere(monkeypatch, module: str, name: str, value) -> None:
    """`module.name` replaced by `value`, and so in every module of the project that imported it by name."""
    real = vars(importlib.import_module(module))[name]
    for mod in list(sys.modules.values()):
        if getattr(mod, "__name__", "").split(".")[0] in ("teleop", "devices", "scenes") \
                and getattr(mod, "__dict__", {}).get(name) is real:
            monkeypatch.setattr(mod, name, value)


@pytest.fixture(autouse=True)
def no_work(monkeypatch):
    for module, name in WORK:
        replace_everywhere(monkeypatch, module, name, _sentinel)


def leaf_parsers(parser: argparse.ArgumentParser, path=()) -> dict:
    """{("bench", "tick"): parser, ...}: every subcommand that has no subcommands of its own."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        return {path: parser}
    out = {}
    for name, p in subs[0].choices.items():
        out.update(leaf_parsers(p, path + (name,)))
    return out


PARSERS = leaf_parsers(build_parser())


class Files:
    """The paths the fuzzer hands out, made fresh for each example in a temporary directory."""

    def __init__(self, root: Path):
        self.root = root
        (root / "adir").mkdir()
        (root / "empty.csv").write_bytes(b"")
        (root / "text.toml").write_text("t_s,x\n1,2\nnot,numbers\n[geometry]\nmu = 'x'\n")
        (root / "binary.mcap").write_bytes(bytes(range(256)) * 4)
        (root / "truncated.mcap").write_bytes(b"\x89MCAP0\r\n" + bytes(64))
        unreadable = root / "unreadable.csv"  # garbage too, so that root (who reads it anyway) also gets exit 2
        unreadable.write_text("\x00garbage\n")
        unreadable.chmod(0)
        self.inputs = ["missing.csv", "adir", "empty.csv", "text.toml", "binary.mcap", "truncated.mcap",
                       "unreadable.csv"]
        self.good_inputs = []
        for name in ("session.mcap", "geometry.toml", "column_map.toml", "recording.csv"):
            if (EXAMPLES / name).exists():
                shutil.copy(EXAMPLES / name, root / name)
                self.good_inputs.append(name)
        self.bad_outputs = ["adir", "text.toml/out.json", "adir/../text.toml/x.png", ""]
        self.bad_dirs = ["text.toml", "text.toml/sub", ""]

    def bad_for(self, action) -> list:
        return self.bad_dirs if action.type is argtypes.output_dir else self.bad_outputs

    def fresh_output(self, n: int) -> str:
        return f"out/result{n}.json"


SURELY_BAD_NUMBERS = ["abc", "nan", "1.5.2", "--"]
NUMBERS = ["-1", "0", "1", "3", "0.5", "1e9", "-1e300", "inf", "nan", "abc", "2.5", "99999999999999999999"]
STRINGS = ["", "x", "bogus://", "sim://?script=nope", "serial:///dev/ttyNOPE?baud=1000000", "replay://missing.mcap",
           "mrdlab", "nosuch", "0.1,5", "0.23", "1,,2", "dynamic", "z60", "%", "-3"]


def _kind(action: argparse.Action) -> str:
    t = action.type
    if action.nargs == 0:
        return "flag"
    if action.choices is not None and not isinstance(action, argparse._SubParsersAction):
        return "choice"
    if t in (argtypes.output_file, argtypes.output_dir):
        return "output"
    if t is argtypes.input_file:
        return "input"
    if t in (int, float) or getattr(t, "__module__", "") == "teleop.apps.argtypes" or "fraction" in getattr(t, "__name__", ""):
        return "number"
    return "string"


@st.composite
def command_lines(draw, files: Files):
    """(argv, outputs the command may create, whether a surely-bad argument is in it)."""
    path = draw(st.sampled_from(sorted(PARSERS)))
    parser = PARSERS[path]
    actions = [a for a in parser._actions if not isinstance(a, argparse._HelpAction)]
    argv, outputs, bad = list(path), [], False
    positional = []
    for a in actions:
        kind = _kind(a)
        if a.option_strings and not a.required and not draw(st.booleans()):
            continue
        if kind == "flag":
            argv.append(a.option_strings[0])
            continue
        n = a.nargs if isinstance(a.nargs, int) else (draw(st.integers(1, 2)) if a.nargs == "+" else 1)
        values = []
        for _ in range(n):
            if kind == "choice":
                v = draw(st.sampled_from([str(c) for c in a.choices] + ["bogus"]))
                bad |= v == "bogus"
            elif kind == "output":
                if draw(st.booleans()):
                    v = files.fresh_output(len(outputs))
                    outputs.append(v)
                else:
                    v = draw(st.sampled_from(files.bad_for(a)))
                    bad = True
            elif kind == "input":
                v = draw(st.sampled_from(files.inputs + files.good_inputs))
                bad |= v in ("missing.csv", "adir")
            elif kind == "number":
                v = draw(st.sampled_from(NUMBERS))
                bad |= v in SURELY_BAD_NUMBERS and a.type in (int, float)
            else:
                v = draw(st.sampled_from(STRINGS + files.inputs))
            values.append(v)
        if a.option_strings:
            argv += [a.option_strings[0], *values]
        else:
            positional += values
    argv += positional
    if path not in CHEAP and not bad and draw(st.booleans()):  # one surely bad argument
        out = [a for a in actions if _kind(a) == "output" and a.option_strings]
        how = draw(st.sampled_from(["output", "number", "unknown"] if out else ["number", "unknown"]))
        if how == "output":
            a = draw(st.sampled_from(out))
            argv += [a.option_strings[0], draw(st.sampled_from(files.bad_for(a)))]
        elif how == "number":
            nums = [a for a in actions if a.option_strings and a.type in (int, float)]
            if nums:
                argv[len(path):len(path)] = [draw(st.sampled_from(nums)).option_strings[0], "abc"]
            else:
                argv[len(path):len(path)] = ["--no-such-option"]
        else:
            argv[len(path):len(path)] = ["--no-such-option"]
        bad = True
    return argv, outputs, bad


def _listing(root: Path) -> set:
    return {p.relative_to(root) for p in root.rglob("*")}


@settings(max_examples=int(os.environ.get("CLI_FUZZ_EXAMPLES", 400)), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_cli_fuzz_one_line_exit_2_nothing_written_never_a_traceback(data, capsys):
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        files = Files(root)
        argv, outputs, bad = data.draw(command_lines(files), label="argv")
        before = _listing(root)
        cwd = os.getcwd()
        os.chdir(root)
        try:
            code = main(argv)
        except WorkStarted:  # every check passed and the work began (not run here): fine unless one was bad
            assert not bad, (argv, "a bad argument was found only after the work had started")
            code = None
        finally:
            os.chdir(cwd)
            (root / "unreadable.csv").chmod(0o600)
        err = capsys.readouterr().err
        lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("pybullet build time")]
        if code is None:
            return
        allowed = {0, 1, 2} if argv[0] == "replay" else {0, 2}
        assert code in allowed, (argv, code, err)
        if code == 2:
            assert len(lines) == 1, (argv, err)
            tokens = [t if t else "''" for t in argv if t != "bench"]  # an empty value is shown as ''

            assert any(t in lines[0] for t in tokens) or "required" in lines[0], (argv, lines)
            assert _listing(root) == before, (argv, sorted(map(str, _listing(root) - before)))
        else:
            assert not bad, (argv, code, err)
            for out in outputs:
                assert (root / out).is_file(), (argv, out)


def test_fuzz_reaches_every_subcommand():
    """The walk finds the commands the README lists (a parser refactor must not hide them from the fuzzer)."""
    names = {" ".join(p) for p in PARSERS}
    assert {"geometry", "export", "replay", "diagnose", "palpate", "blind-test", "session", "bench tick",
            "bench loop", "bench link", "bench sim", "bench diagnose", "bench blind-jnd", "bench cable",
            "calibrate", "campaign run"} <= names


@pytest.mark.parametrize("argv, named", [
    (["geometry", "--geometry", "adir"], "adir"),
    (["diagnose", "adir"], "adir"),
    (["diagnose", "empty.csv", "--json", "/nonexistent-root/x.json"], "/nonexistent-root/x.json"),
    (["geometry", "--json", "adir"], "--json"),
    (["export", "missing.mcap", "--csv", "x.csv"], "missing.mcap"),
    (["session", "--robot", "serial:///dev/ttyNOPE?baud=1000000", "--seconds", "0.1"], "/dev/ttyNOPE"),
    (["blind-test", "--jnd", "5"], "--jnd"),
    (["bench", "blind-jnd", "--jnd", "0.2,5"], "--jnd"),
    (["bench", "link", "--build-dir", "file.txt"], "--build-dir"),
])
def test_the_issue_cases(tmp_path, monkeypatch, capsys, argv, named):
    """The cases the newcomer met: one line naming the file or flag, exit 2, nothing written."""
    (tmp_path / "adir").mkdir()
    (tmp_path / "empty.csv").write_text("")
    (tmp_path / "file.txt").write_text("x")
    monkeypatch.chdir(tmp_path)
    if "serial://" in " ".join(argv):  # the real session code up to opening the port
        replace_everywhere(monkeypatch, "teleop.loop.session", "run_session", REAL_RUN_SESSION)
    if argv[-1] == "/nonexistent-root/x.json" and os.access("/", os.W_OK):
        argv = argv[:-1] + ["file.txt/x.json"]
        named = "file.txt/x.json"
    before = _listing(tmp_path)
    assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], lines
    assert _listing(tmp_path) == before


