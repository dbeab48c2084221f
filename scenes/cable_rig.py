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

`ranges`: None draws the rig's own set-up as it always has (bends 60-360 deg, mu 0.04-0.12, 500 Hz unless
given, noisy encoders, force noise 0.4 % of the mean load); `LITERATURE` (a `RigRanges`) draws it over the
ranges tendon-sheath rigs are reported at (each range's source on the field), the cable's axial stiffness
setting the sheath's stick stiffness through Kaneko's dead zone.

Units: SI inside (m, N, s, rad); the CSV carries mm, deg, N, C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pathlib import Path

from scenes.tendon_sheath import dead_zone_uniform
from teleop.core.physics import REGISTRY, Signals, get_effect
from teleop.core.physics.base import Scale
from teleop.core.physics.capstan import tip2motor_transitions

#: the links whose effects the rig can conceal (a contact effect needs a pad: teleop.diagnosis.generator)
RIG_LINKS = ("position", "force", "sensor")
#: the interchange column that records each physics channel the rig's effects may read beside their own
CHANNEL_COLUMNS = {"temperature": "temperature_C", "theta": "bend_angle_deg"}
#: physics the rig writes itself: a spring that stiffens (cubic) and a pulley eccentricity (motor force
#: periodic in motor position), both outside the catalogue, and a late tip force sensor, a pure delay the
#: catalogue knows under its own name (Rules.also_known_as)
OUTSIDE = ("stiffening_spring", "eccentric_pulley", "sensor_delay")
#: the interchange columns the bench can write (t_s always)
COLUMNS = ("motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")


#: the optional sensors of a literature-range recording (the motor encoder, the drive, is always recorded)
OPTIONAL_COLUMNS = COLUMNS[1:]


@dataclass(frozen=True)
class RigRanges:
    """What a rig's set-up is drawn over (SI unless the name says otherwise), with each range's source.

    mu: sheath friction coefficient [-], uniform: issue 26 item 6's literature range 0.05-0.25; its low end is
        the seed's own sheath (seed 000 Fig 9, the project's mu 0.056), the high end a polymer cable in a
        polymer liner (Do, Tjahjowidodo, Lau, Phee, Mech Syst Signal Process 2015, report coefficients of
        that order for their endoscopic sheaths).
    bend_deg: total bend of the sheath [deg], uniform: up to seed 000 Fig 8's route (A-B 360 deg) plus its
        scaffold (B-C 140 deg) plus a kinematic bend, 540 deg; from 30 deg, a nearly straight sheath.
    max_capstan_ratio: exp(mu Theta) at most (issue 26: capstan ratios 1.0-5.0); pairs beyond it are redrawn.
    cables: {material: ((EA_min, EA_max) [N], (L_min, L_max) [m])}, the material drawn uniformly, then EA
        and L uniform. Steel: a 0.3-0.45 mm 7x7 rope, E = 200 GPa at a rope modulus of about half the full
        section (scenes.tendon_sheath's EA source: 7 kN and 16 kN), from 5 kN. Polymer: a 0.3-0.5 mm UHMWPE
        braid (Dyneema SK75 datasheet: fibre modulus about 110 GPa; a braid about a third of it on a 0.6
        fill): 1.5-4 kN. Lengths: seed 000's sheath (about 1 m) to a 1.5 m endoscope, from 0.5 m.
    load_N: mean tip load [N], uniform (seed 000 Fig 9-11: 0.49-4.9 N weights to 20 N pretensions).
    noise_fs: every analog sensor's noise as a fraction of its full scale, log-uniform: 0.2-3 %, from a
        strain-gauge cell through an amplifier (seed 000 Table 4's [17]: 0.03 N on 5 N, 0.6 %) to an FSR
        (seed 000's quintic FSR calibration leaves several % of its range).
    drive_hz: the drive's frequencies [Hz], log-uniform: 0.05-5 Hz, from a quasi-static haul to the hand's
        voluntary band (MRDLab's da Vinci runs: 0.1-0.5 Hz sines; shared/data/README.md).
    max_speed: the drive's peak speed [m/s] (a frequency beyond it is lowered): a NEMA17 stepper (seed 000's
        actuator) at 600 rpm on a 10 mm drum, about 0.3 m/s.
    fs_hz: sampling rate [Hz], log-uniform: 200 Hz (seed 000's Arduino Mega loop) to 2 kHz (a DAQ; MRDLab
        logs at 1 kHz).
    exact_encoder: the probability that an encoder is exact (a commanded or optical-encoder position:
        quantised at 1 um, no noise); else it is an analog position sensor with the analog noise.
    sensor_present: the probability that each optional sensor (OPTIONAL_COLUMNS) is recorded."""

    mu: tuple = (0.05, 0.25)
    bend_deg: tuple = (30.0, 540.0)
    max_capstan_ratio: float = 5.0
    cables: tuple = (("steel", (5.0e3, 16.0e3), (0.5, 1.5)), ("polymer", (1.5e3, 4.0e3), (0.5, 1.5)))
    load_N: tuple = (3.0, 20.0)
    noise_fs: tuple = (0.002, 0.03)
    drive_hz: tuple = (0.05, 5.0)
    max_speed: float = 0.3
    fs_hz: tuple = (200.0, 2000.0)
    exact_encoder: float = 0.5
    sensor_present: float = 0.6


LITERATURE = RigRanges()


def _loguniform(rng: np.random.Generator, lo_hi) -> float:
    return float(math.exp(rng.uniform(math.log(lo_hi[0]), math.log(lo_hi[1]))))


def draw_setup(rng: np.random.Generator, ranges: RigRanges) -> dict:
    """A literature-range set-up: {"fs_hz", "mu", "bend_rad", "capstan_ratio", "cable", "EA_N", "length_m",
    "load_N", "dead_zone_m" (Kaneko's, at the mean load), "noise_fs", "motor_encoder", "tip_encoder"
    ("exact" or "noisy")}."""
    fs = _loguniform(rng, ranges.fs_hz)
    while True:
        mu = float(rng.uniform(*ranges.mu))
        bend = math.radians(float(rng.uniform(*ranges.bend_deg)))
        if math.exp(mu * bend) <= ranges.max_capstan_ratio:
            break
    cable, ea, length = ranges.cables[int(rng.integers(len(ranges.cables)))]
    EA, L = float(rng.uniform(*ea)), float(rng.uniform(*length))
    load = float(rng.uniform(*ranges.load_N))
    enc = ["exact" if rng.random() < ranges.exact_encoder else "noisy" for _ in range(2)]
    return {"fs_hz": fs, "mu": mu, "bend_rad": bend, "capstan_ratio": math.exp(mu * bend), "cable": cable,
            "EA_N": EA, "length_m": L, "load_N": load, "dead_zone_m": dead_zone_uniform(load, EA, L, mu * bend),
            "noise_fs": _loguniform(rng, ranges.noise_fs), "motor_encoder": enc[0], "tip_encoder": enc[1]}


def draw_columns(rng: np.random.Generator, ranges: RigRanges, effects=("none",), load: str = "spring") -> tuple:
    """The columns of a literature-range recording: the motor encoder and each optional sensor present with
    probability `ranges.sensor_present`, redrawn until every catalogue effect of `effects` is `observable`
    (an effect-free recording: until some rig effect would be, i.e. it has a link); ValueError when no
    columns could show them under `load`."""
    want = [e for e in effects if e in REGISTRY]
    hidden = [e for e in want if not observable(e, COLUMNS, load)]
    if hidden:
        raise ValueError(f"cable rig: {hidden} cannot show in any recording with a {load} load")
    while True:
        cols = ("motor_pos_mm",) + tuple(c for c in OPTIONAL_COLUMNS if rng.random() < ranges.sensor_present)
        if want and all(observable(e, cols, load) for e in want):
            return cols
        if not want and any(observable(e, cols, load) for e in rig_effects()):
            return cols


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
    #: {effect: {"channel", "clean" (n,), "change" (n,)}}: what each effect switched on changed on its channel
    #: (noise-free, before the sensor's gain and zero) and that channel without it, in SI
    contributions: dict = field(default_factory=dict, repr=False)

    def write(self, path) -> None:
        Path(path).write_text(self.csv, encoding="utf-8")


def trajectory(rng: np.random.Generator, t: np.ndarray, fs: float, ranges: RigRanges | None = None,
               travel: float = 0.0) -> tuple[str, np.ndarray]:
    """Motor haul-in [m] about its mean: sine, sum of sines, or strokes of changing speed (a variable-speed
    triangle), 3-10 mm. ranges: frequencies from ranges.drive_hz (log-uniform), each lowered to keep the
    peak speed within ranges.max_speed; travel: a least amplitude [m] (a drive that reaches past the dead
    zone)."""
    kind = ("sine", "sines", "strokes")[int(rng.integers(3))]
    A = max(rng.uniform(3e-3, 10e-3), travel)

    def hz(lo, hi, size=None):
        if ranges is None:
            return rng.uniform(lo, hi, size)
        f = np.exp(rng.uniform(math.log(ranges.drive_hz[0]), math.log(ranges.drive_hz[1]), size))
        return np.minimum(f, ranges.max_speed / (2 * np.pi * A))
    if kind == "sine":
        x = A * np.sin(2 * np.pi * hz(0.15, 0.7) * t + rng.uniform(0, 2 * np.pi))
    elif kind == "sines":
        x = np.zeros_like(t)
        for amp, f in zip(rng.dirichlet(np.ones(3)) * A, hz(0.1, 0.8, 3)):
            x += amp * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    else:
        x = np.empty_like(t)
        pos, k, direction = 0.0, 0, 1.0
        # stroke speeds: a triangle of amplitude A at frequency f moves at 4 A f
        speeds = np.geomspace(0.25, 3.0, 5) * A if ranges is None else np.sort(4 * A * hz(0, 0, 5))
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


def simulate(seed, effects=("none",), columns=COLUMNS, load: str = "spring", fs_hz: float | None = 500.0,
             duration_s: float = 20.0, noise: float = 1.0, given: dict | None = None,
             ranges: RigRanges | None = None) -> RigRecording:
    """One recording of the bench with `effects` switched on (catalogue names of `rig_effects()`, OUTSIDE
    names, or 'none') at random parameters drawn from `seed` (int or sequence), each catalogue effect's by
    its own draw (Rules.draw); `columns` of COLUMNS are written. Effects act link by link: the position
    link's on the tip's travel (those reading the load once it is known), the force link's on the motor
    force, the sensor effects on the reading of one force sensor.

    `given` fixes what is otherwise drawn (a set experiment, e.g. seed 000 Fig 9-13): "x" motor haul-in
    (n,) [m] with n = duration_s * fs_hz, "theta" bend [rad] (scalar or (n,)), "mu", "k_stick" [N/m],
    "spring_N_per_m" and "preload_N" (load = spring), "tip_force" (n,) [N] (load = external),
    "ideal_sensors": True for unit gains and zero offsets, and "sensor_channel" ("motor_force" or
    "tip_force") the force sensor a sensor effect sits on. The random draws happen all the same, so the
    rest of the recording is the one `seed` gives without `given`.

    `ranges` (a RigRanges, e.g. LITERATURE): the set-up is drawn over them (`draw_setup`; its record in
    `setup`), fs_hz None taking the drawn sampling rate; the sheath's stick stiffness is the one whose
    transition spans Kaneko's dead zone at the mean load (scenes.tendon_sheath.dead_zone_uniform), every
    analog sensor's noise the drawn fraction of its full scale times `noise`."""
    rng = np.random.default_rng(seed)
    lit = draw_setup(rng, ranges) if ranges is not None else None
    if fs_hz is None:
        if lit is None:
            raise ValueError("cable rig: fs_hz None needs ranges to draw it from")
        fs_hz = lit["fs_hz"]
    given = dict(given or {})
    effects = tuple(e for e in effects if e != "none")
    unknown = [e for e in effects if e not in rig_effects() + OUTSIDE]
    if unknown:
        raise ValueError(f"cable rig: cannot switch on {unknown} (known: {rig_effects() + OUTSIDE})")
    t = np.arange(int(duration_s * fs_hz)) / fs_hz
    travel = 0.0 if lit is None else 1.2 * lit["dead_zone_m"]
    traj, x = trajectory(rng, t, fs_hz, ranges, travel)
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
    contrib: dict = {}

    def changed(name, channel, before, after):   # an effect's own change of its channel (noise-free)
        contrib[name] = {"channel": channel, "clean": np.array(before, dtype=float),
                         "change": np.asarray(after, dtype=float) - before}
    # sheath bend: constant, or stepped between a few angles as in the seed's bend-angle experiments
    if rng.random() < 0.5 or "bend_angle_deg" not in columns:   # a bend nobody records is fixed
        theta = np.full(t.shape, rng.uniform(math.pi / 2, 2 * math.pi))
    else:
        levels = rng.uniform(math.pi / 3, 2 * math.pi, 4)
        theta = levels[np.minimum((t / duration_s * 4).astype(int), 3)]
    mu = rng.uniform(0.04, 0.12)
    if lit is not None:   # the drawn total bend, constant or stepped down to half of it
        theta = np.full(t.shape, lit["bend_rad"])
        if "bend_angle_deg" in columns and rng.random() < 0.5:
            theta = (lit["bend_rad"] * rng.uniform(0.5, 1.0, 4))[np.minimum((t / duration_s * 4).astype(int), 3)]
        mu = lit["mu"]
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
        z_before, z = z, _apply(name, p, t=t, x=z)
        changed(name, truth[name]["channel"], z_before, z)
    # the load at the tip: a preloaded spring on the tip's travel, or an external load of its own
    if load == "spring":
        ks = rng.uniform(200.0, 2000.0)                 # N/m
        pre = ks * A * rng.uniform(1.2, 2.0)            # keeps the cable taut
        if lit is not None:                             # the drawn mean load, the spring keeping it taut
            pre = lit["load_N"]
            ks = min(ks, pre / (1.5 * A))
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
        L0 = L0 if lit is None else lit["load_N"]
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
        z0 = z
        if load == "spring":
            for _ in range(20):
                z = _apply(name, p, t=t, x=z0, load=F_tip)
                F_tip = spring(z)
        else:
            z = _apply(name, p, t=t, x=z, load=F_tip)
        changed(name, truth[name]["channel"], z0, z)
    L0 = float(np.mean(F_tip))
    if load == "spring":   # a position effect shows on the tip force through the spring
        for c in contrib.values():
            c["clean"], c["change"] = spring(c["clean"]), spring(c["clean"] + c["change"]) - spring(c["clean"])
    # the sheath: capstan friction over the bend, stick transitions at reversals
    band = 2 * L0 * math.sinh(mu * float(np.mean(theta)))
    k_stick = band / (rng.uniform(0.02, 0.08) * A)
    if lit is not None:   # the transition spans the cable's dead zone (Kaneko) at the mean load
        k_stick = band / dead_zone_uniform(L0, lit["EA_N"], lit["length_m"], mu * float(np.mean(theta)))
    k_stick = float(given.get("k_stick", k_stick))
    F_m = tip2motor_transitions(x, F_tip, mu, theta, k_stick)
    Fc = rng.uniform(0.08, 0.2) * L0           # the rig's friction level, drawn whatever is switched on
    for name in _switched_on(effects, "force"):
        p = get_effect(name).rules.draw(rng, Scale(travel=A, load=L0, load_span=float(np.ptp(F_tip)), friction=Fc,
                                                   v_fast=vmax, v_slow=v25))
        F_before, F_m = F_m, _apply(name, p, t=t, x=x, v=v, load=F_m, theta=theta, temperature=temp)
        truth[name] = {"channel": get_effect(name).rules.channel, "params": p}
        changed(name, truth[name]["channel"], F_before, F_m)
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
    sensor_channel = given.get("sensor_channel", sensor_channel)
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
        changed(name, sensor_channel, F, readings[sensor_channel])
    if "sensor_delay" in effects:
        tau = rng.uniform(0.05, 0.15)
        # a pure delay of the tip force, which the catalogue knows (an effect's Rules.also_known_as)
        truth["sensor_delay"] = {"channel": "tip_force", "params": {"delay": tau}}
        changed("sensor_delay", "tip_force", readings["tip_force"], np.interp(t - tau, t, readings["tip_force"]))
        readings["tip_force"] = readings["tip_force"] + contrib["sensor_delay"]["change"]
    sf = {"motor_force": 0.004 * L0 * noise, "tip_force": 0.004 * L0 * noise}
    sx = {"motor": 2e-6 * noise, "tip": 5e-6 * noise}
    if lit is not None:   # a fraction of each sensor's full scale (its peak reading, the travel's span)
        sf = {c: lit["noise_fs"] * noise * float(np.max(np.abs(readings[c]))) for c in sf}
        sx = {e: 0.0 if lit[f"{e}_encoder"] == "exact" else lit["noise_fs"] * noise * float(np.ptp(x))
              for e in sx}
    cols = {
        "motor_pos_mm": 1e3 * (np.round((x + rng.normal(0, sx["motor"], t.size)) / 1e-6) * 1e-6),
        "tip_pos_mm": 1e3 * (np.round((z + rng.normal(0, sx["tip"], t.size)) / 1e-6) * 1e-6),
        "motor_force_N": readings["motor_force"] + rng.normal(0, sf["motor_force"], t.size),
        "tip_force_N": readings["tip_force"] + rng.normal(0, sf["tip_force"], t.size),
        "bend_angle_deg": np.rad2deg(theta),
        "temperature_C": temp + rng.normal(0, 0.02, t.size),
    }
    names = ["t_s"] + [c for c in COLUMNS if c in columns]
    data = np.column_stack([t] + [cols[c] for c in names[1:]])
    lines = [f"# load = {load}", "# source = scenes.cable_rig (simulated single-cable bench)",
             ",".join(names)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in data]
    setup = {"mu": mu, "k_stick": k_stick, "theta_mean": float(np.mean(theta)),
             "spring_N_per_m": ks if load == "spring" else None, "fs_hz": fs_hz,
             "capstan_ratio": math.exp(mu * float(np.mean(theta))),
             "noise_N": {c: float(v) for c, v in sf.items()}, "noise_m": {e: float(v) for e, v in sx.items()}}
    if lit is not None:
        setup.update({k: lit[k] for k in ("cable", "EA_N", "length_m", "noise_fs", "motor_encoder", "tip_encoder")})
    return RigRecording(truth, "\n".join(lines) + "\n", tuple(names[1:]), traj, load, setup, contrib)
