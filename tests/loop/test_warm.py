"""The first run's kernel compilation is said before it starts (teleop.loop.warm), `teleop warm` does it a group
at a time with a line each, and blind-test compiles before its progress starts (its ETA counts participants)."""

from types import SimpleNamespace

import pytest

from teleop.apps import cli
from teleop.apps.commands import blind_test
from teleop.loop import warm


class FakeKernel:
    """A numba dispatcher as warm.py sees it: name, cache directory, on-disk index, signatures in this process."""

    def __init__(self, name, cache_dir, cached=True):
        self.py_func = SimpleNamespace(__module__="fake", __qualname__=name)
        self.cached = cached
        self._cache = SimpleNamespace(_cache_path=str(cache_dir),
                                      _cache_file=SimpleNamespace(_load_index=lambda: {"sig": 1} if self.cached
                                                                  else {}))
        self.signatures = ["sig"]


def test_cold_until_a_warm_up_recorded_its_kernels_and_cold_again_when_one_is_stale(tmp_path, monkeypatch):
    ks = [FakeKernel("a", tmp_path), FakeKernel("b", tmp_path)]
    monkeypatch.setattr(warm, "kernels", lambda: ks)
    assert warm.cache_is_cold()  # no warm-up completed with this cache
    warm._record_warmed()
    assert not warm.cache_is_cold()
    ks[1].cached = False  # its source changed (or another numba): numba's index no longer matches
    assert warm.cache_is_cold()


@pytest.mark.parametrize("cold", [True, False])
def test_a_cold_cache_is_said_before_anything_compiles(monkeypatch, cold):
    said = []
    monkeypatch.setattr(warm, "_done", [])
    monkeypatch.setattr(warm, "cache_is_cold", lambda: cold)
    monkeypatch.setattr(warm, "_record_warmed", lambda: None)
    monkeypatch.setattr(warm, "GROUPS", (("one", lambda s: said.append("compiled one")),
                                         ("two", lambda s: said.append("compiled two"))))
    groups = []
    warm.warm_up(say=said.append, on_group=lambda name, seconds: groups.append(name))
    assert said == ([warm.COLD_MESSAGE] if cold else []) + ["compiled one", "compiled two"]
    assert groups == ["one", "two"]
    assert warm.warm_up(say=said.append) == 0.0 and len(said) == 2 + cold  # once per process


def test_teleop_warm_says_each_group_and_its_time(monkeypatch, capsys):
    """`teleop warm` in this process, as in a fresh one (no warm-up done yet here)."""
    monkeypatch.setattr(warm, "_done", [])
    assert cli.main(["warm"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] in (warm.COLD_MESSAGE, "loading compiled kernels ...")
    for name, _ in warm.GROUPS:
        assert any(line.startswith(f"  {name}: ") and line.endswith(" s") for line in lines), (name, lines)
    assert lines[-1].startswith("kernels ")


def test_blind_test_compiles_before_its_progress_starts(monkeypatch):
    order = []

    class Stop(Exception):
        pass

    def bar(total, desc):
        order.append("progress")
        raise Stop

    monkeypatch.setattr(blind_test, "warm_up", lambda *a, **k: order.append("warm"))
    monkeypatch.setattr(blind_test, "_progress", bar)
    args = cli.build_parser().parse_args(["blind-test", "--participants", "2"])
    with pytest.raises(Stop):
        args.func(args)
    assert order == ["warm", "progress"]  # the ETA clock starts after the compilation
