"""Concealed-effect recordings: a richer simulation of a single-cable rig or a pad poke with exactly one
catalogue effect switched on at random parameters (or none), written as interchange CSV.

The rig: a motor drives a cable through a sheath to the tip; motor and tip encoders, motor and tip force
sensors, the sheath's bend angle and the sensor temperature are recorded. Motion: a sine, a sum of sines
or a triangle whose speed changes segment by segment; the tip load is an external load varying on its own
time scale. The pad: ramp-hold-release pokes of varied depth and speed. The simulation runs the physics
effects sample by sample (their `Step` form, the real-time path) and adds sensor noise and encoder
quantisation; gains and offsets of the ideal links are random. The diagnosis tool sees only the CSV.

Parameters are drawn relative to the signals so each effect is material but not dominant:
`CASE_EFFECTS` lists what is drawn; `PRIMARY` the parameters a diagnosis must recover.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from teleop.diagnosis.links import smooth
from teleop.io.recording_io import interchange_text
from teleop.io.outputs import atomic_write
from teleop.core.physics import get_effect

# the rig always has the sheath's capstan friction (the project's simulation of the setup, the
# diagnosis' default baseline); these are concealed on top of it
RIG_EFFECTS = ("backlash", "cable_compliance", "coulomb_friction", "viscous_friction",
               "stribeck_friction", "dahl_hysteresis", "sensor_hysteresis", "thermal_drift")
PAD_EFFECTS = ("hertz_contact", "viscoelasticity", "contact_damping")
CASE_EFFECTS = RIG_EFFECTS + PAD_EFFECTS
# the parameters a diagnosis is scored on (the others are nuisance or shape parameters)
PRIMARY = {"backlash": ("width",), "cable_compliance": ("k",),
           "coulomb_friction": ("Fc",), "viscous_friction": ("b",), "stribeck_friction": ("Fc", "Fs"),
           "dahl_hysteresis": ("Fc",), "sensor_hysteresis": ("h",), "thermal_drift": ("c",),
           "hertz_contact": ("k",), "viscoelasticity": ("g", "tau"), "contact_damping": ("c",)}
CHANNEL = {"backlash": "tip_pos", "cable_compliance": "tip_pos", "hertz_contact": "force",
           "viscoelasticity": "force", "contact_damping": "force"}


@dataclass(frozen=True)
class GenConfig:
    """Sampling rate [Hz], duration [s] and a factor on every sensor noise level."""

    fs_hz: float = 500.0
    duration_s: float = 20.0
    noise: float = 1.0


@dataclass(frozen=True)
class Case:
    """One generated recording: effect ('none' for effect-free), its channel and true parameters, the
    setup ('rig' or 'pad'), trajectory kind and the interchange CSV text."""

    index: int
    effect: str
    channel: str | None
    params: dict
    setup: str
    trajectory: str
    csv: str = field(repr=False)

    def write(self, path: str | Path) -> Path:
        return atomic_write(path, lambda tmp: tmp.write_text(self.csv, encoding="utf-8"))


def _trajectory(rng: np.random.Generator, t: np.ndarray, cfg: GenConfig) -> tuple[str, np.ndarray]:
    """Motor position [m]: sine, sum of sines, or a triangle of changing speed; amplitude 3-10 mm."""
    kind = ("sine", "sines", "triangle")[int(rng.integers(3))]
    A = rng.uniform(3e-3, 10e-3)
    if kind == "sine":
        f = rng.uniform(0.15, 0.8)
        x = A * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    elif kind == "sines":
        x = np.zeros_like(t)
        for amp, f in zip(rng.dirichlet(np.ones(3)) * A, rng.uniform(0.1, 0.9, 3)):
            x += amp * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    else:
        x = np.zeros_like(t)
        pos, k, direction = 0.0, 0, 1.0
        # stroke speeds cycle through a shuffled log-spaced set, so fit and held-out parts both see
        # slow and fast strokes
        speeds = np.geomspace(0.2, 3.0, 5) * A
        stroke = 0
        while k < t.size:
            if stroke % speeds.size == 0:
                speeds = rng.permutation(speeds)
            speed = speeds[stroke % speeds.size]     # m/s, changes every stroke
            stroke += 1
            # strokes last about a second: slow strokes are short, fast ones span the range
            target = float(np.clip(pos + direction * speed * rng.uniform(0.6, 1.4), -A, A))
            if abs(target - pos) < 0.05 * A:
                target = direction * A
            n = max(2, int(abs(target - pos) / speed * cfg.fs_hz))
            seg = np.linspace(pos, target, n, endpoint=False)
            x[k:k + n] = seg[: t.size - k]
            k += n
            pos, direction = target, -direction
        x = smooth(x, max(1, int(0.01 * cfg.fs_hz)) | 1)  # an actuator cannot turn instantly
    return kind, x


def _run_steps(name: str, params: dict, **channels) -> np.ndarray:
    """Run effect `name` per sample (its Step form) over the channels (n,) arrays."""
    st = get_effect(name).make_step(params)
    n = next(iter(channels.values())).shape[0]
    out = np.empty(n)
    keys = list(channels)
    cols = [channels[k] for k in keys]
    for i in range(n):
        out[i] = st.step(**{k: float(c[i]) for k, c in zip(keys, cols)})
    return out


def _rig(rng: np.random.Generator, effect: str, index: int, cfg: GenConfig) -> Case:
    t = np.arange(int(cfg.duration_s * cfg.fs_hz)) / cfg.fs_hz
    traj, x = _trajectory(rng, t, cfg)
    A = float(np.ptp(x)) / 2
    v = np.gradient(x, t)
    vmax = float(np.percentile(np.abs(v), 99))
    v25 = float(np.percentile(np.abs(v), 25))
    L0 = rng.uniform(5.0, 20.0)
    fl = rng.uniform(0.05, 0.4)
    load = L0 * (1 + rng.uniform(0.3, 0.6) * np.sin(2 * np.pi * fl * t + rng.uniform(0, 2 * np.pi))
                 + 0.1 * np.sin(2 * np.pi * 1.7 * fl * t))
    theta = np.full(t.shape, rng.uniform(1.5, 4.5))       # sheath bend, rad
    temp = 25 + rng.uniform(2, 10) * np.sin(2 * np.pi * t / rng.uniform(15, 40) + rng.uniform(0, 6.3))
    g_p, c_p = rng.uniform(0.8, 1.2), rng.uniform(-2e-3, 2e-3)
    g_f, c_f = rng.uniform(0.9, 1.1), rng.uniform(-1.0, 1.0)
    params: dict = {}
    # position link: tip = effect(g_p x + c_p)
    z = g_p * x + c_p
    Lref = g_f * load
    if effect == "backlash":
        params = {"width": rng.uniform(0.06, 0.2) * 2 * g_p * A}
        tip = _run_steps(effect, params, x=z)
    elif effect == "cable_compliance":
        dl = float(np.ptp(load))
        params = {"k": dl / (rng.uniform(0.04, 0.12) * 2 * g_p * A)}
        tip = _run_steps(effect, params, x=z, load=load)
    else:
        tip = z
    # force link: motor = effect(capstan(load = g_f load_tip)) + c_f, sensor effects on the motor reading
    mu = rng.uniform(0.03, 0.1)
    band = 2 * L0 * math.sinh(mu * theta[0])
    capstan = {"mu": mu, "theta": float(theta[0]), "k": band / (rng.uniform(0.02, 0.08) * A)}
    Lref = _run_steps("capstan_friction", capstan, x=x, load=Lref, theta=theta)
    Fc = rng.uniform(0.06, 0.2) * L0
    if effect == "coulomb_friction":
        params = {"Fc": Fc}
        fm = _run_steps(effect, params, v=v, load=Lref)
    elif effect == "viscous_friction":
        params = {"b": Fc / vmax * rng.uniform(1.0, 2.0)}
        fm = _run_steps(effect, params, v=v, load=Lref)
    elif effect == "stribeck_friction":
        params = {"Fc": Fc, "Fs": Fc * rng.uniform(1.8, 3.0), "vs": v25 * rng.uniform(0.6, 1.2)}
        fm = _run_steps(effect, params, v=v, load=Lref)
    elif effect == "dahl_hysteresis":
        params = {"Fc": Fc, "sigma": Fc / (rng.uniform(0.05, 0.2) * A)}
        fm = _run_steps(effect, params, x=x, load=Lref)
    else:
        fm = Lref
    fm = fm + c_f
    if effect == "sensor_hysteresis":
        params = {"h": rng.uniform(0.05, 0.12) * float(np.ptp(fm)), "delta": rng.uniform(0.02, 0.08) * float(np.ptp(fm))}
        fm = _run_steps(effect, params, force=fm)
    elif effect == "thermal_drift":
        params = {"c": float(rng.choice([-1, 1])) * rng.uniform(0.08, 0.2) * float(np.ptp(fm)) / float(np.ptp(temp)),
                  "T0": 25.0}
        fm = _run_steps(effect, params, force=fm, temperature=temp)
    # sensors: noise, encoder quantisation (1 um), tip force sensor noise
    q = 1e-6
    sp = 0.004 * A * cfg.noise
    sf = 0.005 * L0 * cfg.noise
    chans = {
        "motor_pos": np.round((x + rng.normal(0, sp * 0.1, t.size)) / q) * q,
        "tip_pos": np.round((tip + rng.normal(0, sp, t.size)) / q) * q,
        "motor_force": fm + rng.normal(0, sf, t.size),
        "tip_force": load + rng.normal(0, sf, t.size),
        "bend_angle": theta,
        "temperature": temp + rng.normal(0, 0.02, t.size),
    }
    units = {"motor_pos": "m", "tip_pos": "m", "motor_force": "N", "tip_force": "N", "bend_angle": "rad",
             "temperature": "C"}
    meta = {"source": f"teleop.diagnosis.generator case {index}", "load": "external"}
    channel = CHANNEL.get(effect, "motor_force") if effect != "none" else None
    return Case(index, effect, channel, params, "rig", traj, interchange_text(t, chans, units, meta))


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


def _pad(rng: np.random.Generator, effect: str, index: int, cfg: GenConfig) -> Case:
    t = np.arange(int(cfg.duration_s * cfg.fs_hz)) / cfg.fs_hz
    d = _pokes(rng, t, cfg)
    d_dot = np.gradient(d, t)
    k_lin = rng.uniform(300.0, 3000.0)                  # N/m
    params: dict = {}
    if effect == "hertz_contact":
        params = {"k": k_lin / math.sqrt(rng.uniform(2e-3, 5e-3))}
        F = _run_steps(effect, params, d=d)
    else:
        F = _run_steps("linear_contact", {"k": k_lin}, d=d)
        if effect == "viscoelasticity":
            params = {"g": rng.uniform(0.4, 0.8), "tau": rng.uniform(0.2, 1.5)}
            F = _run_steps(effect, params, t=t, force=F, d=d)
        elif effect == "contact_damping":
            vmax = float(np.percentile(np.abs(d_dot), 99))
            params = {"c": rng.uniform(0.15, 0.4) * k_lin * 5e-3 / vmax}
            F = _run_steps(effect, params, force=F, d=d, d_dot=d_dot)
    Fmax = float(np.max(F))
    chans = {"indentation": np.round((d + rng.normal(0, 5e-6 * cfg.noise, t.size)) / 1e-6) * 1e-6,
             "force": F + rng.uniform(-0.05, 0.05) + rng.normal(0, 0.005 * Fmax * cfg.noise, t.size)}
    meta = {"source": f"teleop.diagnosis.generator case {index}"}
    channel = "force" if effect != "none" else None
    return Case(index, effect, channel, params, "pad", "pokes",
                interchange_text(t, chans, {"indentation": "m", "force": "N"}, meta))


def case_plan(n: int) -> list[tuple[str, str]]:
    """(effect, setup) of cases 0..n-1: every effect in turn, with an effect-free rig and pad case
    after every six (so about a quarter of the cases are effect-free)."""
    cycle = []
    for i, e in enumerate(CASE_EFFECTS):
        cycle.append((e, "pad" if e in PAD_EFFECTS else "rig"))
        if i % 6 == 5:
            cycle += [("none", "rig"), ("none", "pad")]
    return [cycle[i % len(cycle)] for i in range(n)]


def make_case(index: int, effect: str, setup: str, seed: int, cfg: GenConfig = GenConfig()) -> Case:
    """Case `index` of a run seeded with `seed` (independent of the other cases)."""
    rng = np.random.default_rng([seed, index])
    return _pad(rng, effect, index, cfg) if setup == "pad" else _rig(rng, effect, index, cfg)


def generate(n: int, seed: int, cfg: GenConfig = GenConfig()) -> list[Case]:
    """n cases (see case_plan), reproducible from seed."""
    return [make_case(i, e, s, seed, cfg) for i, (e, s) in enumerate(case_plan(n))]
