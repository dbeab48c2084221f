"""A simulated single-cable tendon-sheath bench (seed 000 Fig 8-13): a motor hauls one cable through a bent
sheath to a tip that pulls a spring (or carries an external load), with motor and tip force sensors.

This is the project's simulation of the setup that `teleop diagnose` takes as its baseline: the sheath
always has capstan friction over its bend (teleop.core.physics capstan law with stick transitions), the tip
pulls a linear preloaded spring. On top of it any catalogue effects can be switched on (`effects`), or
physics outside the catalogue (`OUTSIDE`: a stiffening spring, a pulley eccentricity, a sensor delay), and
the recording is written as interchange CSV (docs/formats.md) with any subset of the columns, in mm and deg.

It shares with the diagnosis only the physics models (teleop.core.physics); the CSV is written here, not by the
diagnosis' writer, so a recording from this bench is "made elsewhere" as far as the diagnosis knows.

Units: SI inside (m, N, s, rad); the CSV carries mm, deg, N, C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from teleop.core.physics import get_effect
from teleop.core.physics.capstan import tip2motor_transitions

#: catalogue effects this bench can conceal, and the channel each shows on
RIG_EFFECTS = ("backlash", "coulomb_friction", "viscous_friction", "stribeck_friction", "dahl_hysteresis",
               "sensor_hysteresis", "thermal_drift")
#: physics outside the catalogue: a spring that stiffens (cubic), a pulley eccentricity (motor force
#: periodic in motor position), a transport delay of the tip force sensor
OUTSIDE = ("stiffening_spring", "eccentric_pulley", "sensor_delay")
#: the interchange columns the bench can write (t_s always)
COLUMNS = ("motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")
#: the parameters a diagnosis is scored on
PRIMARY = {"backlash": ("width",), "coulomb_friction": ("Fc",), "viscous_friction": ("b",),
           "stribeck_friction": ("Fc", "Fs"), "dahl_hysteresis": ("Fc",), "sensor_hysteresis": ("h",),
           "thermal_drift": ("c",)}


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
        from pathlib import Path
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
    channel it acts on is recorded, and a second channel it can be compared against."""
    cols = set(columns)
    forces = {"motor_force_N", "tip_force_N"} <= cols
    if effect == "backlash":
        return {"motor_pos_mm", "tip_pos_mm"} <= cols or (load == "spring" and {"motor_pos_mm", "tip_force_N"} <= cols)
    if effect in ("coulomb_friction", "viscous_friction", "stribeck_friction", "dahl_hysteresis",
                  "eccentric_pulley"):
        return forces and "motor_pos_mm" in cols
    if effect in ("sensor_hysteresis", "thermal_drift"):
        return forces and "motor_pos_mm" in cols and (effect != "thermal_drift" or "temperature_C" in cols)
    if effect == "stiffening_spring":
        return load == "spring" and "tip_force_N" in cols and bool({"motor_pos_mm", "tip_pos_mm"} & cols)
    if effect == "sensor_delay":
        return "tip_force_N" in cols and (load == "spring" and bool({"motor_pos_mm", "tip_pos_mm"} & cols)
                                          or "motor_force_N" in cols)
    return False


def _apply(name: str, params: dict, **channels) -> np.ndarray:
    from teleop.core.physics import Signals
    return get_effect(name).apply(Signals(**channels), params)


def simulate(seed, effects=("none",), columns=COLUMNS, load: str = "spring", fs_hz: float = 500.0,
             duration_s: float = 20.0, noise: float = 1.0, given: dict | None = None) -> RigRecording:
    """One recording of the bench with `effects` switched on (catalogue names, OUTSIDE names, or 'none')
    at random parameters drawn from `seed` (int or sequence); `columns` of COLUMNS are written.

    `given` fixes what is otherwise drawn (a set experiment, e.g. seed 000 Fig 9-13): "x" motor haul-in
    (n,) [m] with n = duration_s * fs_hz, "theta" bend [rad] (scalar or (n,)), "mu", "k_stick" [N/m],
    "spring_N_per_m" and "preload_N" (load = spring), "tip_force" (n,) [N] (load = external), and
    "ideal_sensors": True for unit gains and zero offsets. The random draws happen all the same, so the
    rest of the recording is the one `seed` gives without `given`."""
    rng = np.random.default_rng(seed)
    given = dict(given or {})
    effects = tuple(e for e in effects if e != "none")
    unknown = [e for e in effects if e not in RIG_EFFECTS + OUTSIDE]
    if unknown:
        raise ValueError(f"cable rig: cannot switch on {unknown} (known: {RIG_EFFECTS + OUTSIDE})")
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
    # position: the tip follows the motor (backlash when on)
    z = x.copy()
    if "backlash" in effects:
        p = {"width": rng.uniform(0.08, 0.25) * 2 * A}
        truth["backlash"] = {"channel": "tip_force" if load == "spring" else "tip_pos", "params": p}
        z = _apply("backlash", p, t=t, x=z)
    # the load at the tip: a preloaded spring on the tip's travel, or an external load of its own
    if load == "spring":
        ks = rng.uniform(200.0, 2000.0)                 # N/m
        pre = ks * A * rng.uniform(1.2, 2.0)            # keeps the cable taut
        ks, pre = float(given.get("spring_N_per_m", ks)), float(given.get("preload_N", pre))
        F_tip = pre + ks * z
        if "stiffening_spring" in effects:
            k3 = rng.uniform(0.25, 0.5) * ks / A ** 2
            truth["stiffening_spring"] = {"channel": "tip_force", "params": {"k3": k3}}
            F_tip = F_tip + k3 * z ** 3
    else:
        L0 = rng.uniform(5.0, 20.0)
        fl = rng.uniform(0.05, 0.4)
        F_tip = L0 * (1 + rng.uniform(0.3, 0.6) * np.sin(2 * np.pi * fl * t + rng.uniform(0, 6.3))
                      + 0.1 * np.sin(2 * np.pi * 1.7 * fl * t))
        if "tip_force" in given:
            F_tip = np.broadcast_to(np.asarray(given["tip_force"], dtype=float), t.shape).copy()
    L0 = float(np.mean(F_tip))
    # the sheath: capstan friction over the bend, stick transitions at reversals
    band = 2 * L0 * math.sinh(mu * float(np.mean(theta)))
    k_stick = band / (rng.uniform(0.02, 0.08) * A)
    k_stick = float(given.get("k_stick", k_stick))
    F_m = tip2motor_transitions(x, F_tip, mu, theta, k_stick)
    Fc = rng.uniform(0.08, 0.2) * L0
    if "coulomb_friction" in effects:
        p = {"Fc": Fc}
        F_m = _apply("coulomb_friction", p, t=t, v=v, load=F_m)
        truth["coulomb_friction"] = {"channel": "motor_force", "params": p}
    if "viscous_friction" in effects:
        p = {"b": Fc / vmax * rng.uniform(1.0, 2.0)}
        F_m = _apply("viscous_friction", p, t=t, v=v, load=F_m)
        truth["viscous_friction"] = {"channel": "motor_force", "params": p}
    if "stribeck_friction" in effects:
        p = {"Fc": Fc, "Fs": Fc * rng.uniform(1.8, 3.0), "vs": v25 * rng.uniform(0.6, 1.2)}
        F_m = _apply("stribeck_friction", p, t=t, v=v, load=F_m)
        truth["stribeck_friction"] = {"channel": "motor_force", "params": p}
    if "dahl_hysteresis" in effects:
        p = {"Fc": Fc, "sigma": Fc / (rng.uniform(0.05, 0.2) * A)}
        F_m = _apply("dahl_hysteresis", p, t=t, x=x, load=F_m)
        truth["dahl_hysteresis"] = {"channel": "motor_force", "params": p}
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
    F = readings[sensor_channel]
    if "sensor_hysteresis" in effects:
        p = {"h": rng.uniform(0.06, 0.12) * float(np.ptp(F)), "delta": rng.uniform(0.02, 0.06) * float(np.ptp(F))}
        readings[sensor_channel] = _apply("sensor_hysteresis", p, t=t, force=F)
        truth["sensor_hysteresis"] = {"channel": sensor_channel, "params": p}
    if "thermal_drift" in effects:
        p = {"c": float(rng.choice([-1, 1])) * rng.uniform(0.1, 0.25) * float(np.ptp(F)) / float(np.ptp(temp)),
             "T0": 25.0}
        readings[sensor_channel] = _apply("thermal_drift", p, t=t, force=F, temperature=temp)
        truth["thermal_drift"] = {"channel": sensor_channel, "params": p}
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
