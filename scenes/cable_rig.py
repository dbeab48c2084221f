"""A simulated single-cable tendon-sheath bench (seed 000 Fig 8-13): a motor hauls one cable through a bent
sheath to a tip that pulls a spring (or carries an external load), with motor and tip force sensors.

This is the project's simulation of the setup that `teleop diagnose` takes as its baseline: the sheath
always has capstan friction over its bend (teleop.core.physics capstan law with stick transitions), the tip
pulls a linear preloaded spring. On top of it any catalogue effect with a generator draw (physics Rules.draw)
on the position, force or sensor link can be switched on (`effects`, `rig_effects()`), at parameters its
own draw gives against the recording's scale, or physics outside the catalogue (`OUTSIDE`: a stiffening
spring, a pulley eccentricity, a sensor delay), and the recording is written as interchange CSV
(docs/formats.md) with any subset of the columns, in mm and deg. This is the one rig generator: the
diagnosis' concealed-effect cases (teleop.diagnosis.generator) are recordings of it with an external load.

It shares with the diagnosis only the physics models (teleop.core.physics); the CSV is written here, not by the
diagnosis' writer, so a recording from this bench is "made elsewhere" as far as the diagnosis knows.

Units: SI inside (m, N, s, rad); the CSV carries mm, deg, N, C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pathlib import Path

from teleop.core.physics import REGISTRY, Signals, get_effect
from teleop.core.physics.base import Scale
from teleop.core.physics.capstan import tip2motor_transitions

#: the links whose effects the rig can conceal (a contact effect needs a pad: teleop.diagnosis.generator)
RIG_LINKS = ("position", "force", "sensor")
#: the interchange column that records each physics channel the rig's effects may read beside their own
CHANNEL_COLUMNS = {"temperature": "temperature_C", "theta": "bend_angle_deg"}
#: physics outside the catalogue: a spring that stiffens (cubic), a pulley eccentricity (motor force
#: periodic in motor position), a transport delay of the tip force sensor
OUTSIDE = ("stiffening_spring", "eccentric_pulley", "sensor_delay")
#: the interchange columns the bench can write (t_s always)
COLUMNS = ("motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")


def rig_effects() -> tuple[str, ...]:
    """The registered effects this bench can conceal, in registry order: those with a generator draw on the
    position, force or sensor link."""
    return tuple(n for n, e in REGISTRY.items() if e.rules.draw is not None and e.link in RIG_LINKS)


@dataclass(frozen=True)
class RigRecording:
    """One bench recording: the effects switched on with their true parameters and the channel each is
    on ({effect: {"channel", "params"}}), the CSV text and the columns written."""

    effects: dict
    csv: str = field(repr=False)
    columns: tuple
    trajectory: str
    load: str
    setup: dict = field(default_factory=dict)   # the simulation's own parameters (mu, k_stick, spring)

    def write(self, path) -> None:
        Path(path).write_text(self.csv, encoding="utf-8")


def _trajectory(rng: np.random.Generator, t: np.ndarray, fs: float) -> tuple[str, np.ndarray]:
    """Motor haul-in [m] about its mean: sine, sum of sines, or strokes of changing speed (3-10 mm)."""
    kind = ("sine", "sines", "strokes")[int(rng.integers(3))]
    A = rng.uniform(3e-3, 10e-3)
    if kind == "sine":
        x = A * np.sin(2 * np.pi * rng.uniform(0.15, 0.7) * t + rng.uniform(0, 2 * np.pi))
    elif kind == "sines":
        x = np.zeros_like(t)
        for amp, f in zip(rng.dirichlet(np.ones(3)) * A, rng.uniform(0.1, 0.8, 3)):
            x += amp * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    else:
        x = np.empty_like(t)
        pos, k, direction = 0.0, 0, 1.0
        speeds = np.geomspace(0.25, 3.0, 5) * A
        while k < t.size:
            speed = speeds[int(rng.integers(speeds.size))]
            target = float(np.clip(pos + direction * speed * rng.uniform(0.6, 1.5), -A, A))
            if abs(target - pos) < 0.1 * A:
                target = direction * A
            n = max(2, int(abs(target - pos) / speed * fs))
            seg = np.linspace(pos, target, n, endpoint=False)
            x[k:k + n] = seg[: t.size - k]
            k += n
            hold = int(rng.uniform(0.0, 0.3) * fs)          # the motor may pause before turning
            x[k:k + hold] = target
            k += hold
            pos, direction = target, -direction
        w = max(1, int(0.015 * fs)) | 1                      # an actuator does not turn instantly
        x = np.convolve(np.pad(x, w // 2, mode="edge"), np.ones(w) / w, mode="valid")
    return kind, x


def observable(effect: str, columns, load: str) -> bool:
    """True when `effect` switched on in the bench shows in a recording with `columns` and `load`: the
    channel it acts on is recorded, and a second channel it can be compared against. A catalogue effect's
    rule follows from its link and inputs: on the position link the tip against the motor (a stretch under
    the load only with an external load: under a linear spring it is a gain), on the force link both
    forces and the motor's motion, a sensor effect as a force-link effect and the channels it reads."""
    cols = set(columns)
    forces = {"motor_force_N", "tip_force_N"} <= cols
    if effect in REGISTRY and effect not in OUTSIDE:
        eff = get_effect(effect)
        if eff.link == "position" and "load" in eff.inputs:
            return load == "external" and {"motor_pos_mm", "tip_pos_mm"} <= cols and bool(
                {"motor_force_N", "tip_force_N"} & cols)
        if eff.link == "position":
            return {"motor_pos_mm", "tip_pos_mm"} <= cols or (load == "spring" and {"motor_pos_mm", "tip_force_N"} <= cols)
        needs = {CHANNEL_COLUMNS[c] for c in eff.inputs if c in CHANNEL_COLUMNS}
        return eff.link in ("force", "sensor") and forces and "motor_pos_mm" in cols and needs <= cols
    if effect == "eccentric_pulley":
        return forces and "motor_pos_mm" in cols
    if effect == "stiffening_spring":
        return load == "spring" and "tip_force_N" in cols and bool({"motor_pos_mm", "tip_pos_mm"} & cols)
    if effect == "sensor_delay":
        return "tip_force_N" in cols and (load == "spring" and bool({"motor_pos_mm", "tip_pos_mm"} & cols)
                                          or "motor_force_N" in cols)
    return False


def _apply(name: str, params: dict, **channels) -> np.ndarray:
    """Effect `name`'s array form over the channels it reads (inputs and optional ones) of `channels`."""
    eff = get_effect(name)
    use = {c: a for c, a in channels.items() if c == "t" or c in eff.inputs + eff.optional}
    return eff.apply(Signals(**use), params)


def _switched_on(effects, link: str, with_load: bool | None = None) -> list[str]:
    """The catalogue effects of `effects` on `link`, in registry order (with_load: only those that do, or
    do not, read the load)."""
    return [n for n in rig_effects() if n in effects and get_effect(n).link == link
            and (with_load is None or ("load" in get_effect(n).inputs) == with_load)]


def simulate(seed, effects=("none",), columns=COLUMNS, load: str = "spring", fs_hz: float = 500.0,
             duration_s: float = 20.0, noise: float = 1.0, given: dict | None = None) -> RigRecording:
    """One recording of the bench with `effects` switched on (catalogue names of `rig_effects()`, OUTSIDE
    names, or 'none') at random parameters drawn from `seed` (int or sequence), each catalogue effect's by
    its own draw (Rules.draw); `columns` of COLUMNS are written. Effects act link by link: the position
    link's on the tip's travel (those reading the load once it is known), the force link's on the motor
    force, the sensor effects on the reading of one force sensor.

    `given` fixes what is otherwise drawn (a set experiment, e.g. seed 000 Fig 9-13): "x" motor haul-in
    (n,) [m] with n = duration_s * fs_hz, "theta" bend [rad] (scalar or (n,)), "mu", "k_stick" [N/m],
    "spring_N_per_m" and "preload_N" (load = spring), "tip_force" (n,) [N] (load = external), and
    "ideal_sensors": True for unit gains and zero offsets. The random draws happen all the same, so the
    rest of the recording is the one `seed` gives without `given`."""
    rng = np.random.default_rng(seed)
    given = dict(given or {})
    effects = tuple(e for e in effects if e != "none")
    unknown = [e for e in effects if e not in rig_effects() + OUTSIDE]
    if unknown:
        raise ValueError(f"cable rig: cannot switch on {unknown} (known: {rig_effects() + OUTSIDE})")
    t = np.arange(int(duration_s * fs_hz)) / fs_hz
    traj, x = _trajectory(rng, t, fs_hz)
    if "x" in given:
        traj, x = "given", np.asarray(given["x"], dtype=float)
        if x.shape != t.shape:
            raise ValueError(f"cable rig: given x has shape {x.shape}, expected {t.shape}")
    A = float(np.ptp(x)) / 2
    v = np.gradient(x, t)
    v[np.abs(v) < 1e-9] = 0.0          # at rest (round-off of the smoothing is not motion)
    vmax = float(np.percentile(np.abs(v), 99))
    v25 = float(np.percentile(np.abs(v[v != 0]), 25))      # a slow stroke's speed (moving samples)
    truth: dict = {}
    # sheath bend: constant, or stepped between a few angles as in the seed's bend-angle experiments
    if rng.random() < 0.5 or "bend_angle_deg" not in columns:   # a bend nobody records is fixed
        theta = np.full(t.shape, rng.uniform(math.pi / 2, 2 * math.pi))
    else:
        levels = rng.uniform(math.pi / 3, 2 * math.pi, 4)
        theta = levels[np.minimum((t / duration_s * 4).astype(int), 3)]
    mu = rng.uniform(0.04, 0.12)
    if "theta" in given:
        theta = np.broadcast_to(np.asarray(given["theta"], dtype=float), t.shape).copy()
    mu = float(given.get("mu", mu))
    temp = 24 + rng.uniform(2, 10) * np.sin(2 * np.pi * t / rng.uniform(15, 40) + rng.uniform(0, 6.3))
    # position: the tip follows the motor (a play when on); seen through the spring on the tip force
    z = x.copy()
    on_tip = "tip_force" if load == "spring" else None
    for name in _switched_on(effects, "position", with_load=False):
        p = get_effect(name).rules.draw(rng, Scale(travel=A, v_fast=vmax, v_slow=v25))
        truth[name] = {"channel": on_tip or get_effect(name).rules.channel, "params": p}
        z = _apply(name, p, t=t, x=z)
    # the load at the tip: a preloaded spring on the tip's travel, or an external load of its own
    if load == "spring":
        ks = rng.uniform(200.0, 2000.0)                 # N/m
        pre = ks * A * rng.uniform(1.2, 2.0)            # keeps the cable taut
        ks, pre = float(given.get("spring_N_per_m", ks)), float(given.get("preload_N", pre))
        k3 = 0.0
        if "stiffening_spring" in effects:
            k3 = rng.uniform(0.25, 0.5) * ks / A ** 2
            truth["stiffening_spring"] = {"channel": "tip_force", "params": {"k3": k3}}

        def spring(z):
            F = pre + ks * z
            return F + k3 * z ** 3 if k3 else F
        F_tip = spring(z)
    else:
        L0 = rng.uniform(5.0, 20.0)
        fl = rng.uniform(0.05, 0.4)
        F_tip = L0 * (1 + rng.uniform(0.3, 0.6) * np.sin(2 * np.pi * fl * t + rng.uniform(0, 6.3))
                      + 0.1 * np.sin(2 * np.pi * 1.7 * fl * t))
        if "tip_force" in given:
            F_tip = np.broadcast_to(np.asarray(given["tip_force"], dtype=float), t.shape).copy()
    # position effects under the load (a stretch): with a spring the load is the tip's own travel, solved
    # by fixed-point iteration (the stretch is a small part of the travel)
    for name in _switched_on(effects, "position", with_load=True):
        p = get_effect(name).rules.draw(rng, Scale(travel=A, load=float(np.mean(F_tip)),
                                                   load_span=float(np.ptp(F_tip)), v_fast=vmax, v_slow=v25))
        truth[name] = {"channel": on_tip or get_effect(name).rules.channel, "params": p}
        if load == "spring":
            z0 = z
            for _ in range(20):
                z = _apply(name, p, t=t, x=z0, load=F_tip)
                F_tip = spring(z)
        else:
            z = _apply(name, p, t=t, x=z, load=F_tip)
    L0 = float(np.mean(F_tip))
    # the sheath: capstan friction over the bend, stick transitions at reversals
    band = 2 * L0 * math.sinh(mu * float(np.mean(theta)))
    k_stick = band / (rng.uniform(0.02, 0.08) * A)
    k_stick = float(given.get("k_stick", k_stick))
    F_m = tip2motor_transitions(x, F_tip, mu, theta, k_stick)
    Fc = rng.uniform(0.08, 0.2) * L0           # the rig's friction level, drawn whatever is switched on
    for name in _switched_on(effects, "force"):
        p = get_effect(name).rules.draw(rng, Scale(travel=A, load=L0, load_span=float(np.ptp(F_tip)), friction=Fc,
                                                   v_fast=vmax, v_slow=v25))
        F_m = _apply(name, p, t=t, x=x, v=v, load=F_m, theta=theta, temperature=temp)
        truth[name] = {"channel": get_effect(name).rules.channel, "params": p}
    if "eccentric_pulley" in effects:
        lam = rng.uniform(0.5, 1.0) * 2 * A
        amp = rng.uniform(0.1, 0.2) * float(np.ptp(F_m))
        truth["eccentric_pulley"] = {"channel": "motor_force", "params": {"amplitude": amp, "period": lam}}
        F_m = F_m + amp * np.sin(2 * np.pi * x / lam)
    # sensors: gains and zeros, then the sensor effect on one of the two force sensors
    readings = {"motor_force": rng.uniform(0.9, 1.1) * F_m + rng.uniform(-0.5, 0.5),
                "tip_force": rng.uniform(0.95, 1.05) * F_tip + rng.uniform(-0.3, 0.3)}
    if given.get("ideal_sensors"):
        readings = {"motor_force": F_m.copy(), "tip_force": F_tip.copy()}
    sensor_channel = "motor_force" if rng.random() < 0.5 else "tip_force"
    if "motor_force_N" not in columns:
        sensor_channel = "tip_force"
    if "tip_force_N" not in columns or load != "spring":   # a tip sensor's own effect needs the spring law
        sensor_channel = "motor_force"
    for name in _switched_on(effects, "sensor"):
        F = readings[sensor_channel]
        p = get_effect(name).rules.draw(rng, Scale(travel=A, load=L0, force_span=float(np.ptp(F)),
                                                   temp_span=float(np.ptp(temp)), v_fast=vmax, v_slow=v25))
        readings[sensor_channel] = _apply(name, p, t=t, x=x, force=F, temperature=temp, theta=theta)
        truth[name] = {"channel": sensor_channel, "params": p}
    if "sensor_delay" in effects:
        tau = rng.uniform(0.05, 0.15)
        truth["sensor_delay"] = {"channel": "tip_force", "params": {"tau": tau}}
        readings["tip_force"] = np.interp(t - tau, t, readings["tip_force"])
    sf = 0.004 * L0 * noise
    cols = {
        "motor_pos_mm": 1e3 * (np.round((x + rng.normal(0, 2e-6 * noise, t.size)) / 1e-6) * 1e-6),
        "tip_pos_mm": 1e3 * (np.round((z + rng.normal(0, 5e-6 * noise, t.size)) / 1e-6) * 1e-6),
        "motor_force_N": readings["motor_force"] + rng.normal(0, sf, t.size),
        "tip_force_N": readings["tip_force"] + rng.normal(0, sf, t.size),
        "bend_angle_deg": np.rad2deg(theta),
        "temperature_C": temp + rng.normal(0, 0.02, t.size),
    }
    names = ["t_s"] + [c for c in COLUMNS if c in columns]
    data = np.column_stack([t] + [cols[c] for c in names[1:]])
    lines = [f"# load = {load}", "# source = scenes.cable_rig (simulated single-cable bench)",
             ",".join(names)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in data]
    setup = {"mu": mu, "k_stick": k_stick, "theta_mean": float(np.mean(theta)),
             "spring_N_per_m": ks if load == "spring" else None}
    return RigRecording(truth, "\n".join(lines) + "\n", tuple(names[1:]), traj, load, setup)
