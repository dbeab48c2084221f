"""`teleop bench effects [--samples N] [--repeat R] [--json PATH]`: how fast the effect catalogue runs
(teleop.core.physics): each registered effect's apply() on a 1 kHz signal of N samples, and its Step per sample.

Prints one JSON object {"samples", "apply_ms": {effect: {"p50", "min"}}, "step_us": {effect: best of R}}.
Timings are measurements of this machine, never asserted by the tests.
"""

from __future__ import annotations

import json
import time

import numpy as np

from teleop.apps.argtypes import positive_int
from teleop.core.physics.base import REGISTRY, Signals
from teleop.io.outputs import write_json


def bench_signals(n: int, seed: int = 0) -> Signals:
    """A 1 kHz signal of n samples with every channel present (reversing motion, load, contact cycles)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    x = 8e-3 * np.sin(2 * np.pi * 0.5 * t) + 1e-3 * np.sin(2 * np.pi * 2.3 * t) + rng.normal(0, 1e-6, n)
    d = 1e-3 + 3e-3 * np.sin(2 * np.pi * 0.8 * t)
    return Signals(t=t, x=x, load=3 + np.sin(0.8 * t), force=500 * np.maximum(d, 0), temperature=25 + 0.1 * t,
                   theta=2.4 + 0.2 * np.sin(0.3 * t), d=d)


def register(subparsers) -> None:
    p = subparsers.add_parser("effects", help="speed of the effect catalogue: apply() per signal, Step per sample")
    p.add_argument("--samples", type=positive_int, default=40_000, help="samples of the signal (default 40000)")
    p.add_argument("--repeat", type=positive_int, default=7, help="timed runs per effect, best kept (default 7)")
    p.add_argument("--json", metavar="PATH", help="also write the result to this file")
    p.set_defaults(func=run)


def bench_effects(samples: int = 40_000, repeat: int = 7, step_samples: int = 2000) -> dict:
    """{"samples", "apply_ms", "step_us"} (module docstring) of every registered effect; the Step is timed over
    the first `step_samples` samples (at most all of them)."""
    step_samples = min(step_samples, samples)
    sig = bench_signals(samples)
    apply_ms, step_us = {}, {}
    for name, eff in sorted(REGISTRY.items()):
        p = eff.defaults()
        ts = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            eff.apply(sig, p)
            ts.append((time.perf_counter() - t0) * 1e3)
        apply_ms[name] = {"p50": round(float(np.median(ts)), 3), "min": round(float(np.min(ts)), 3)}
        st = eff.make_step(p)
        names = eff.inputs + tuple(c for c in eff.optional if sig[c] is not None)
        rows = [{c: float(sig[c][k]) for c in names} for k in range(step_samples)]
        best = np.inf
        for _ in range(repeat):
            st.reset()
            t0 = time.perf_counter()
            for u in rows:
                st.step(**u)
            best = min(best, time.perf_counter() - t0)
        step_us[name] = round(best / step_samples * 1e6, 2)
    return {"samples": samples, "apply_ms": apply_ms, "step_us": step_us}


def run(args) -> int:
    res = bench_effects(args.samples, args.repeat)
    print(json.dumps(res, indent=2))
    if args.json:
        write_json(args.json, res)
    return 0
