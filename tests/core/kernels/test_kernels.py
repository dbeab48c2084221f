"""The compiled kernels: warmed before the loop, cached or not, and the same source without numba."""

import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from teleop.core.kernels import jit

ROOT = Path(__file__).resolve().parents[3]


def _run(code: str, **env) -> subprocess.CompletedProcess:
    e = dict(os.environ, **env)
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=e, capture_output=True, text=True,
                          timeout=600)


TICKS = """
import json, numpy as np
from teleop.apps.bench.tick import make_ticks, _trajectory
out = {}
for name in ("single", "double", "dynamic"):
    fast, _ = make_ticks(name)
    p, v, c = _trajectory(300, 1e-3, 1)
    out[name] = [[np.asarray(a).tolist() for a in fast.compute(p[k], v[k], c[k], 1e-3)] for k in range(300)]
print(json.dumps(out))
"""


def test_without_numba_the_same_source_gives_the_same_ticks():
    compiled = _run(TICKS)
    plain = _run(TICKS, TELEOP_NO_JIT="1")
    assert compiled.returncode == 0 and plain.returncode == 0, compiled.stderr + plain.stderr
    assert json.loads(compiled.stdout) == json.loads(plain.stdout)


def test_the_loop_and_the_sim_robot_compile_nothing_after_the_warm_up():
    code = """
import json
from teleop.loop.warm import kernels, warm_up
from teleop.apps.bench.sim import bench_sim
warm_up()
before = {k.__name__: len(k.signatures) for k in kernels()}
bench_sim(seconds=0.3, batch=False, stages=False)
after = {k.__name__: len(k.signatures) for k in kernels()}
print(json.dumps({k: after[k] - before[k] for k in after if after[k] != before[k]}))
"""
    r = _run(code)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1]) == {}


def test_no_writable_cache_anywhere_compiles_in_memory_with_one_warning(tmp_path):
    """A read-only package directory, an unwritable NUMBA_CACHE_DIR and home: numba refuses cache=True at
    import; the kernels then compile in memory (numba's in-tree locator is switched off to stand for the
    read-only package: the tests run as whoever owns the checkout)."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    code = """
import numba.core.caching as C
C.InTreeCacheLocator.from_function = classmethod(lambda cls, f, p: None)
import numpy as np
from teleop.core.estimation.tick import TickComputer
from teleop.core.geometry import default_geometry
print(TickComputer(default_geometry(), "dynamic").estimate(np.zeros(6), np.full(6, 2.0), 1e-3)[1][2])
"""
    r = _run(code, NUMBA_CACHE_DIR=str(blocker / "c"), HOME=str(blocker), XDG_CACHE_HOME=str(blocker / "x"))
    assert r.returncode == 0, r.stderr
    assert abs(float(r.stdout.strip())) < 1e-9
    assert r.stderr.count("numba cache unavailable") == 1


def test_a_writable_numba_cache_dir_keeps_the_compiled_kernels(tmp_path):
    code = "from teleop.core.kernels.friction import dahl_step; print(dahl_step(0.0, 1e-3, 1e4, 0.1))"
    first = _run(code, NUMBA_CACHE_DIR=str(tmp_path))
    assert first.returncode == 0, first.stderr
    assert any(p.suffix == ".nbi" for p in tmp_path.rglob("*")), "no cache index written"
    second = _run(code, NUMBA_CACHE_DIR=str(tmp_path))
    assert second.stdout == first.stdout


@pytest.mark.parametrize("mod, fn", [("friction", "dahl_step"), ("sheath", "capstan_play_step"),
                                     ("friction", "direction_step")])
def test_py_func_is_the_kernel_source(mod, fn):
    k = getattr(importlib.import_module(f"teleop.core.kernels.{mod}"), fn)
    assert k.py_func.__code__.co_filename.endswith(f"{mod}.py")


@pytest.mark.skipif(not jit.COMPILED, reason="numba not installed (or TELEOP_NO_JIT)")
def test_kernel_caches_are_stamped_with_every_kernel_source(tmp_path):
    """A kernel's cached code holds its callees compiled in: its cache must go stale when any kernel source
    changes, not only its own file (numba's default, which kept old linalg code under the forward kinematics)."""
    from teleop.core.kernels import geometry, linalg

    for k in (geometry.forward_kinematics, linalg.solve_into):
        assert k._cache._cache_file._source_stamp == jit._kernels_stamp()
    src = tmp_path / "kernels"
    src.mkdir()
    for name in ("a.py", "b.py"):
        (src / name).write_text("x = 1\n")
    old = jit._KERNEL_DIR
    try:
        jit._KERNEL_DIR = str(src)
        before = jit._kernels_stamp()
        (src / "b.py").write_text("x = 2\n")  # a callee's module changes
        assert jit._kernels_stamp() != before
    finally:
        jit._KERNEL_DIR = old


def _ratio(a, b):
    return a / b


def _ratio_ieee(a, b):  # a function of its own: numba's disk cache keys a kernel by its source, not its options
    return a / b


@pytest.mark.skipif(not jit.COMPILED, reason="numba not installed (or TELEOP_NO_JIT)")
def test_ieee_division_gives_inf_where_the_default_raises():
    """njit(ieee_division=True) (the distributed cable's kernels): a division by zero gives inf or nan, as
    numpy does; the default kernel raises as Python does; a nonzero divisor gives the same number."""
    ieee, plain = jit.njit(ieee_division=True)(_ratio_ieee), jit.njit(_ratio)
    assert ieee(1.0, 0.0) == float("inf") and ieee(0.0, 0.0) != ieee(0.0, 0.0)
    with pytest.raises(ZeroDivisionError):
        plain(1.0, 0.0)
    assert ieee(1.0, 3.0) == plain(1.0, 3.0) == 1.0 / 3.0
