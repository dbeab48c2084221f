"""Concealed-effect recordings: a single-cable rig or a pad poke with exactly one catalogue effect switched on
at random parameters (or none), written as interchange CSV.

The rig is the simulated single-cable bench (scenes.cable_rig, the one rig generator) with all its columns
and an external load: a motor drives a cable through a sheath to the tip; motor and tip encoders, motor and
tip force sensors, the sheath's bend angle and the sensor temperature are recorded. The pad: ramp-hold-release
pokes of varied depth and speed on a linear pad, run sample by sample (the effects' `Step` form, the
real-time path), with sensor noise and encoder quantisation. The diagnosis tool sees only the CSV.

What is drawn is read from the physics registry: every effect with a generator draw (Rules.draw), drawn
relative to the signals so each effect is material but not dominant (`case_effects()`), and scored on its
primary parameters (`primary()`, Rules.primary).

Two set-ups of the rig (GenConfig.ranges): "project", the rig's own draws (every column, an external load,
the rate and duration given); "literature", the set-up drawn over the ranges tendon-sheath rigs are reported
at (scenes.cable_rig.LITERATURE, each range's source there: mu 0.05-0.25, total bend up to 540 deg at a
capstan ratio up to 5, steel and polymer cables, noise 0.2-3 % of full scale, drives 0.05-5 Hz, 200 Hz-2 kHz
sampling unless the rate is given, exact and noisy encoders), each optional sensor present or absent
(redrawn until the effect shows: scenes.cable_rig.observable) and a spring or external load.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from scenes.cable_rig import COLUMNS, LITERATURE, draw_columns, observable, rig_effects, simulate
from teleop.io.recording_io import interchange_text
from teleop.io.outputs import atomic_write
from teleop.core.physics import REGISTRY, get_effect, linear_force
from teleop.core.physics.base import Scale


def pad_effects() -> tuple[str, ...]:
    """Registered contact effects with a generator draw, in registry order (concealed on the pad)."""
    return tuple(n for n, e in REGISTRY.items() if e.rules.draw is not None and e.link == "contact")


def case_effects() -> tuple[str, ...]:
    """Every effect the generator conceals: the rig's (scenes.cable_rig.rig_effects), then the pad's."""
    return rig_effects() + pad_effects()


def primary() -> dict:
    """{effect: the parameters a diagnosis is scored on} for every concealed effect (Rules.primary)."""
    return {n: get_effect(n).rules.primary for n in case_effects()}


#: the rig set-ups a generator may draw (GenConfig.ranges -> scenes.cable_rig ranges; None: the rig's own)
RANGES = {"project": None, "literature": LITERATURE}


@dataclass(frozen=True)
class GenConfig:
    """Sampling rate [Hz] (None: drawn, literature ranges only), duration [s], a factor on every sensor
    noise level, and the rig's set-up ranges (a key of RANGES)."""

    fs_hz: float | None = 500.0
    duration_s: float = 20.0
    noise: float = 1.0
    ranges: str = "project"


@dataclass(frozen=True)
class Case:
    """One generated recording: effect ('none' for effect-free), its channel and true parameters, the
    setup ('rig' or 'pad'), trajectory kind and the interchange CSV text; a rig case also its columns,
    load, the simulation's own set-up (scenes.cable_rig RigRecording.setup: mu, capstan ratio, noise...) and
    what its effect changed on its channel (RigRecording.contributions)."""

    index: int
    effect: str
    channel: str | None
    params: dict
    setup: str
    trajectory: str
    csv: str = field(repr=False)
    columns: tuple = ()
    load: str = ""
    rig: dict = field(default_factory=dict, repr=False)
    contributions: dict = field(default_factory=dict, repr=False)   # RigRecording.contributions

    def write(self, path: str | Path) -> Path:
        return atomic_write(path, lambda tmp: tmp.write_text(self.csv, encoding="utf-8"))


def _run_steps(name: str, params: dict, **channels) -> np.ndarray:
    """Run effect `name` per sample (its Step form) over the channels (n,) arrays it reads."""
    eff = get_effect(name)
    st = eff.make_step(params)
    keys = [k for k in channels if k in eff.inputs + eff.optional]
    n = next(iter(channels.values())).shape[0]
    out = np.empty(n)
    cols = [channels[k] for k in keys]
    for i in range(n):
        out[i] = st.step(**{k: float(c[i]) for k, c in zip(keys, cols)})
    return out


def _rig(effect: str, index: int, seed: int, cfg: GenConfig) -> Case:
    """The cable rig with `effect` switched on (or 'none'): every column and an external load ("project"),
    or columns and load drawn ("literature": from the stream [seed, index, 1])."""
    ranges = RANGES[cfg.ranges]
    cols, load = COLUMNS, "external"
    if ranges is not None:
        rng = np.random.default_rng([seed, index, 1])
        load = ("spring", "external")[int(rng.integers(2))]
        if effect in REGISTRY and not observable(effect, COLUMNS, load):   # e.g. a stretch under a spring
            load = "external" if load == "spring" else "spring"
        cols = draw_columns(rng, ranges, (effect,), load)
    rig = simulate([seed, index], (effect,), cols, load, cfg.fs_hz, cfg.duration_s, cfg.noise, ranges=ranges)
    truth = rig.effects.get(effect, {"channel": None, "params": {}})
    return Case(index, effect, truth["channel"], dict(truth["params"]), "rig", rig.trajectory, rig.csv,
                rig.columns, load, dict(rig.setup), dict(rig.contributions))


def _pokes(rng: np.random.Generator, t: np.ndarray, cfg: GenConfig) -> np.ndarray:
    """Indentation [m]: ramp-hold-release pokes of varied depth, speed and hold; d < 0 is off the pad."""
    d = np.full(t.shape, -1e-3)
    k = int(rng.uniform(0.3, 1.0) * cfg.fs_hz)
    while k < t.size:
        depth = rng.uniform(2e-3, 6e-3)
        ramp = int(rng.uniform(0.2, 1.5) * cfg.fs_hz)
        hold = int(rng.uniform(0.5, 3.0) * cfg.fs_hz)
        rel = int(rng.uniform(0.2, 1.5) * cfg.fs_hz)
        shape = np.concatenate([np.linspace(-1e-3, depth, ramp), np.full(hold, depth),
                                np.linspace(depth, -1e-3, rel)])
        n = min(shape.size, t.size - k)
        d[k:k + n] = shape[:n]
        k += n + int(rng.uniform(0.3, 1.0) * cfg.fs_hz)
    return d


def _pad(rng: np.random.Generator, effect: str, index: int, seed: int, cfg: GenConfig) -> Case:
    """Pokes on a linear pad with the contact effect `effect` (or 'none') at its own draw's parameters (a
    rate to draw: log-uniform over the ranges' fs_hz, from the stream [seed, index, 2])."""
    if cfg.fs_hz is None:
        lo, hi = RANGES[cfg.ranges].fs_hz
        fs = float(np.exp(np.random.default_rng([seed, index, 2]).uniform(np.log(lo), np.log(hi))))
        cfg = GenConfig(fs, cfg.duration_s, cfg.noise, cfg.ranges)
    t = np.arange(int(cfg.duration_s * cfg.fs_hz)) / cfg.fs_hz
    d = _pokes(rng, t, cfg)
    d_dot = np.gradient(d, t)
    k_lin = rng.uniform(300.0, 3000.0)                  # N/m
    params: dict = {}
    # a contact law (it reads the indentation alone) replaces the linear pad; any other effect acts on its force
    law = effect != "none" and get_effect(effect).inputs == ("d",)
    if not law:
        F = linear_force(d, k_lin)
    if effect != "none":
        scale = Scale(travel=5e-3, stiffness=k_lin, v_fast=float(np.percentile(np.abs(d_dot), 99)))
        params = get_effect(effect).rules.draw(rng, scale)
        F = _run_steps(effect, params, d=d) if law else _run_steps(effect, params, t=t, force=F, d=d, d_dot=d_dot)
    Fmax = float(np.max(F))
    chans = {"indentation": np.round((d + rng.normal(0, 5e-6 * cfg.noise, t.size)) / 1e-6) * 1e-6,
             "force": F + rng.uniform(-0.05, 0.05) + rng.normal(0, 0.005 * Fmax * cfg.noise, t.size)}
    meta = {"source": f"teleop.diagnosis.generator case {index}"}
    channel = get_effect(effect).rules.channel if effect != "none" else None
    return Case(index, effect, channel, params, "pad", "pokes",
                interchange_text(t, chans, {"indentation": "m", "force": "N"}, meta), ("indentation", "force"))


def case_plan(n: int) -> list[tuple[str, str]]:
    """(effect, setup) of cases 0..n-1: every effect in turn, with an effect-free rig and pad case
    after every six (so about a quarter of the cases are effect-free)."""
    cycle = []
    pads = pad_effects()
    for i, e in enumerate(case_effects()):
        cycle.append((e, "pad" if e in pads else "rig"))
        if i % 6 == 5:
            cycle += [("none", "rig"), ("none", "pad")]
    return [cycle[i % len(cycle)] for i in range(n)]


def make_case(index: int, effect: str, setup: str, seed: int, cfg: GenConfig = GenConfig()) -> Case:
    """Case `index` of a run seeded with `seed` (independent of the other cases)."""
    if setup == "pad":
        return _pad(np.random.default_rng([seed, index]), effect, index, seed, cfg)
    return _rig(effect, index, seed, cfg)


def generate(n: int, seed: int, cfg: GenConfig = GenConfig()) -> list[Case]:
    """n cases (see case_plan), reproducible from seed."""
    return [make_case(i, e, s, seed, cfg) for i, (e, s) in enumerate(case_plan(n))]
