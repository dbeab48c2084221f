"""Recordings the diagnosis did not make: a test-side generator that shares none of the catalogue's kernels.

One cable runs through a sheath and pulls a spring (load = spring). The motor hauls the cable in by x [m]
(x increasing: pulling); the spring's tension at the tip is T_tip = T0 + k_s x. The motor (proximal) tension
follows the capstan law written out here on its own:

- `instant`: T_m = T_tip exp(+mu Theta) while the motor pulls (v > 0), T_tip exp(-mu Theta) while it pays out
  (v < 0), switched on the sign of the drive's true velocity at the sample (held through v = 0);
- pre-sliding (`stick_k` [N/m]): after a reversal the cable sticks and T_m travels across the band
  [T_tip e^-mu Theta, T_tip e^+mu Theta] at stick_k newtons per metre of motor travel, integrated on a grid
  SUB times finer than the recording and sampled.

The drive is analytic (a sine, a sum of sines, or a triangle of varying speed with rounded turns), the motor
encoder exact or noisy (Gaussian, rounded to counts), each force sensor carries Gaussian noise of a known
fraction of its own full scale. Columns: t_s, motor_pos_mm, motor_force_N, bend_angle_deg, and tip_force_N
with the tip sensor (without it the diagnosis takes the load from the spring law). The interchange CSV (docs/formats.md) is
written here too, line by line.

`plant_case` gives the same columns from the distributed tendon-sheath plant (scenes.tendon_sheath), a second
source whose physics (LuGre friction per node, an elastic cable) is not the catalogue's either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scenes.tendon_sheath import SheathLoad, TendonSheath, TendonSheathParams   # a yardstick: tests only

SUB = 20          # fine steps per recorded sample for the pre-sliding integration


@dataclass(frozen=True)
class Case:
    """One recording's setup (SI). ratio: the capstan ratio exp(mu Theta); theta_deg: the total bend Theta;
    drive: 'sine' | 'sines' | 'triangle'; stick_k [N/m] or None (instant switch); enc_noise [m] (0: exact
    encoder; else Gaussian noise rounded to counts of enc_noise / 2); noise_frac: force noise as a fraction of
    the motor force's full scale; tip: the tip force sensor recorded."""

    ratio: float = 2.0
    theta_deg: float = 300.0
    drive: str = "sine"
    stick_k: float | None = None
    enc_noise: float = 0.0
    noise_frac: float = 0.005
    tip: bool = True
    seconds: float = 20.0
    rate: float = 1000.0
    amplitude: float = 5e-3
    freq: float = 0.5
    T0: float = 6.0
    k_spring: float = 600.0
    seed: int = 0

    @property
    def mu(self) -> float:
        return math.log(self.ratio) / math.radians(self.theta_deg)


def drive(case: Case, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(x [m], v [m/s]) of the case's drive at times t."""
    A, w = case.amplitude, 2 * math.pi * case.freq
    if case.drive == "sine":
        return A * np.sin(w * t), A * w * np.cos(w * t)
    if case.drive == "sines":
        amps, freqs = (0.6, 0.3, 0.15), (1.0, 2.3, 4.1)
        x = sum(a * A * np.sin(2 * math.pi * f * case.freq * t + k) for k, (a, f) in enumerate(zip(amps, freqs)))
        v = sum(a * A * 2 * math.pi * f * case.freq * np.cos(2 * math.pi * f * case.freq * t + k)
                for k, (a, f) in enumerate(zip(amps, freqs)))
        return x, v
    if case.drive == "triangle":
        # legs between +-A of varying duration, the speed profile a raised cosine over each leg (rounded turns)
        rng = np.random.default_rng(case.seed + 7)
        legs = rng.uniform(0.4, 1.6, int(case.seconds * case.freq * 4) + 8) / (2 * case.freq)
        edges = np.concatenate(([0.0], np.cumsum(legs)))
        k = np.searchsorted(edges, t, side="right") - 1
        T = legs[k]
        s = (t - edges[k]) / T
        direction = np.where(k % 2 == 0, 1.0, -1.0)
        x = direction * A * (2 * (s - np.sin(2 * math.pi * s) / (2 * math.pi)) - 1.0)
        v = direction * A * 2 * (1 - np.cos(2 * math.pi * s)) / T
        return x, v
    raise ValueError(f"unknown drive {case.drive!r}")


def motor_tension(case: Case, x: np.ndarray, v: np.ndarray, T_tip: np.ndarray) -> np.ndarray:
    """Motor tension [N] on samples (x, v, T_tip) of a fine enough grid (see module docstring)."""
    e = case.ratio
    lo, hi = T_tip / e, T_tip * e
    out = np.empty_like(x)
    if case.stick_k is None:
        s = np.sign(np.where(np.abs(v) > 1e-9 * float(np.max(np.abs(v))), v, 0.0))   # a turn on a sample: v = 0
        last = 1.0 if s[0] >= 0 else -1.0
        for i in range(s.size):   # held through v = 0
            if s[i] != 0:
                last = s[i]
            out[i] = hi[i] if last > 0 else lo[i]
        return out
    T = T_tip[0]
    for i in range(x.size):
        if i:
            T = T + case.stick_k * (x[i] - x[i - 1])
        T = min(max(T, lo[i]), hi[i])
        out[i] = T
    return out


@dataclass(frozen=True)
class Made:
    """A generated recording: t (n,) [s], channels {name: (n,) SI}, units {name: unit}, metadata, and the true
    noise standard deviation of motor_force [N] (noise_N)."""

    t: np.ndarray
    channels: dict
    units: dict
    metadata: dict
    noise_N: float
    truth: dict


def make(case: Case) -> Made:
    """The recording of `case` (seeded by case.seed)."""
    rng = np.random.default_rng(case.seed)
    n = int(round(case.seconds * case.rate))
    t = np.arange(n) / case.rate
    sub = SUB if case.stick_k is not None else 1
    tf = np.arange(n * sub) / (case.rate * sub)
    xf, vf = drive(case, tf)
    T_tip_f = case.T0 + case.k_spring * xf
    Tm = motor_tension(case, xf, vf, T_tip_f)[::sub]
    x, T_tip = xf[::sub], T_tip_f[::sub]
    full = float(np.max(np.abs(Tm)))
    sigma = case.noise_frac * full
    if case.enc_noise > 0:
        q = case.enc_noise / 2
        x_rec = np.round((x + rng.normal(0.0, case.enc_noise, n)) / q) * q
    else:
        x_rec = x.copy()
    channels = {"motor_pos": x_rec, "motor_force": Tm + rng.normal(0.0, sigma, n),
                "bend_angle": np.full(n, math.radians(case.theta_deg))}
    units = {"motor_pos": "m", "motor_force": "N", "bend_angle": "rad"}
    if case.tip:   # each sensor's noise a fraction of its own full scale
        channels["tip_force"] = T_tip + rng.normal(0.0, case.noise_frac * float(np.max(np.abs(T_tip))), n)
        units["tip_force"] = "N"
    meta = {"load": "spring", "source": f"tests.diagnosis._independent {case}"}
    return Made(t, channels, units, meta, sigma, {"motor_force": Tm, "tip_force": T_tip, "x": x})


def plant_case(ratio: float = 2.0, seconds: float = 12.0, noise_frac: float = 0.005, tip: bool = True,
               freq: float = 0.5, amplitude: float = 4e-3, seed: int = 0) -> Made:
    """The distributed tendon-sheath plant (scenes.tendon_sheath) pulling a spring, its Coulomb friction set
    so that the capstan ratio over its bends is `ratio`; sine drive, exact encoder, Gaussian force noise."""
    theta = math.radians(140.0 + 360.0)
    mu = math.log(ratio) / theta
    params = TendonSheathParams(mu_c=mu, mu_s=1.2 * mu)
    plant = TendonSheath(params, SheathLoad("spring", stiffness=600.0), pretension=6.0)
    rng = np.random.default_rng(seed)
    n = int(round(seconds * 1000.0))
    t = np.arange(n) / 1000.0
    x = amplitude * np.sin(2 * math.pi * freq * t)
    run = plant.run(x)
    Tm, T_tip = run.f_motor[:, 0], run.f_tip[:, 0]
    sigma = noise_frac * float(np.max(np.abs(Tm)))
    channels = {"motor_pos": x, "motor_force": Tm + rng.normal(0.0, sigma, n), "bend_angle": np.full(n, theta)}
    units = {"motor_pos": "m", "motor_force": "N", "bend_angle": "rad"}
    if tip:
        channels["tip_force"] = T_tip + rng.normal(0.0, noise_frac * float(np.max(np.abs(T_tip))), n)
        units["tip_force"] = "N"
    meta = {"load": "spring", "source": f"tests.diagnosis._independent plant ratio {ratio}"}
    return Made(t, channels, units, meta, sigma, {"motor_force": Tm, "tip_force": T_tip, "x": x})


_COLUMN = {"motor_pos": ("motor_pos_mm", 1e3), "tip_pos": ("tip_pos_mm", 1e3), "motor_force": ("motor_force_N", 1.0),
           "tip_force": ("tip_force_N", 1.0), "bend_angle": ("bend_angle_deg", 180.0 / math.pi)}


def write_csv(made: Made, path: Path) -> Path:
    """The interchange CSV of `made` at path (docs/formats.md: metadata lines, a header, one row a sample)."""
    names = [c for c in ("motor_pos", "tip_pos", "motor_force", "tip_force", "bend_angle") if c in made.channels]
    cols = [made.t] + [made.channels[c] * _COLUMN[c][1] for c in names]
    lines = [f"# {k} = {v}" for k, v in made.metadata.items()]
    lines.append(",".join(["t_s"] + [_COLUMN[c][0] for c in names]))
    lines.extend(",".join(repr(float(v)) for v in row) for row in np.column_stack(cols))
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)
