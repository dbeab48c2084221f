"""Kernels bound to their call sites' argument types (teleop.core.kernels.jit.bind): the loop's path calls them
without numba's dispatch and gets the numbers numba's dispatch gives, bit for bit."""

import importlib
import pickle

import numpy as np
import pytest

from teleop.apps.bench.sim import bench_sim
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.tick import LoopTick
from teleop.core.geometry import default_geometry
from teleop.core.kernels import jit
from teleop.core.kernels.safety import all_finite2
from teleop.core.mapping import MappingParams
from teleop.core.rendering import Renderer
from teleop.loop import safety

# the modules whose call sites bind kernels (each imports jit.bind by name)
BINDING = ("devices.simulated", "scenes.sim_robot", "scenes.pose_follow", "scenes.world",
           "teleop.core.estimation.reading", "teleop.core.mapping", "teleop.core.rendering", "teleop.loop.safety",
           "teleop.apps.bench.sim")


def _unbound(monkeypatch):
    """Every binding call site back on numba's dispatch (bind gives the kernel itself)."""
    for name in BINDING:
        mod = importlib.import_module(name)
        assert mod.bind is jit.bind, name
        monkeypatch.setattr(mod, "bind", lambda kernel, *args: kernel)
    monkeypatch.setattr(safety, "_monitors", [None])


def test_a_bound_kernel_gives_the_kernels_result():
    a, b = np.array([1.0, 2.0]), np.array([3.0, np.nan])
    call = jit.bind(all_finite2, a, a)
    assert call(a, a) is True and call(a, b) is False
    assert call(a, b) == all_finite2(a, b)
    if jit.COMPILED:
        assert call is not all_finite2  # the compiled overload's own entry


@pytest.mark.parametrize("plant", ["matched", "distributed"])
def test_the_simulation_is_the_same_bound_or_dispatched(plant, monkeypatch):
    bound = bench_sim(0.4, seed=3, batch=False, stages=False, plant=plant)
    _unbound(monkeypatch)
    dispatched = bench_sim(0.4, seed=3, batch=False, stages=False, plant=plant)
    assert bound["trajectory"]["final_state"] == "ENABLED"
    assert bound["trajectory"] == dispatched["trajectory"]  # sha256 of lengths, counts, contact force, stylus


def test_a_used_estimator_renderer_and_mapping_still_pickle():
    g = default_geometry()
    lt = LoopTick(g, MappingParams(), ReadingEstimator(g, "dynamic"), Renderer())
    lt.renderer.enable()
    lt.engage(np.zeros(3))
    for k in range(3):
        lt.compute(np.full(3, 1e-4 * k), np.zeros(3), np.full(6, 400 + k), 1e-3)
    copy = pickle.loads(pickle.dumps(lt))
    args = (np.full(3, 2e-4), np.zeros(3), np.full(6, 401), 1e-3)
    for a, b in zip(lt.compute(*args), copy.compute(*args)):
        assert np.array_equal(a, b)


def test_counts_of_another_dtype_rebind():
    est = ReadingEstimator(default_geometry(), "dynamic")
    ref = ReadingEstimator(default_geometry(), "dynamic")
    for counts in (np.full(6, 400, dtype=np.int64), np.full(6, 401.0), np.full(6, 402, dtype=np.int64)):
        t, w = est.update_arrays(counts, np.zeros(6), 1e-3)
        ref.tensions_into(counts.astype(float))
        t_ref, w_ref = ref._t, ref.tick.estimate_into(np.zeros(6), ref._t, 1e-3)[1, :6]
        assert np.array_equal(t, t_ref) and np.array_equal(w, w_ref)


def test_the_estimators_held_arguments_follow_a_reset_and_a_new_dead_band():
    g = default_geometry()
    seq = [np.full(6, 400 + 30 * (k % 5), dtype=np.int64) for k in range(12)]
    used = ReadingEstimator(g, "dynamic")
    for c in seq:
        used.update_arrays(c, np.zeros(6), 1e-3)
    used.reset()  # replaces the FSR and friction states: the held arguments are built again
    used.deadband_counts = 3.0
    fresh = ReadingEstimator(g, "dynamic", deadband_counts=3.0)
    for c in seq:
        t, w = used.update_arrays(c, np.zeros(6), 1e-3)
        t_ref, w_ref = fresh.update_arrays(c, np.zeros(6), 1e-3)
        assert np.array_equal(t, t_ref) and np.array_equal(w, w_ref)
