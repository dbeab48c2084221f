"""Calibration recordings made from the sensor physics models, with known parameters (tests, examples).

Each generator runs the physics a real protocol would meet and gives the CSV text the calibration reads
(teleop.io.calibration_csv.write_examples writes them to files); it
imports only the physics models (teleop.core.sensors, teleop.core.physics), never the fits (teleop.core.calibration.fsr,
fbg, one_sensor), so a test that recovers the parameters checks the fits against the physics.

- `fsr_step_protocol`: seed 000 Fig 7 (0-650 g up in 50 g steps, 600-0 g down, repeated): the FSR reads
  through its branch lag (teleop.core.sensors.FsrBranchLag: the unloading branch is the loading one at the
  tension plus the friction gap) plus conductance noise.
- `fbg_load_steps`: seed 001 sec. 2.1.3-2.1.4: 0-20 N up and down in steps at several temperatures; FBG2
  carries a hysteresis, both gratings the temperature shift and noise (teleop.core.sensors.synthesize_fbg).
  The hysteresis is a loop that closes at both ends as in seed 001 Fig 4a (loop="closing", the default):
  +-h sin(pi F / top) by the direction of the last load step (the gap 2h at mid-span, zero at 0 and top,
  the loop's centre line S F untilted), or the catalogue's sensor hysteresis switch (loop="switch",
  teleop.core.physics.hysteresis_offset: a gap 2h over the whole loop, jumping at the turns);
  `fbg_loop_gap` gives a loop's true gaps.
- `one_cable_cycles`: one tendon-sheath cable hauling a spring back and forth (teleop.core.physics capstan law
  with stick transitions): Kp = exp(-mu Theta), Kr = exp(+mu Theta).
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.physics import hysteresis_offset
from teleop.core.physics.capstan import tip2motor_transitions
from teleop.core.sensors import G, LOADING, UNLOADING, FbgParams, FsrBranchLag, FsrCalibration, synthesize_fbg


def fsr_step_protocol(cal: FsrCalibration, seed: int = 0, repeats: int = 3, noise_uS: float = 0.3,
                      step_g: float = 50.0, top_g: float = 650.0) -> str:
    """CSV text (tension_N, conductance_uS, branch) of the seed's step protocol read by an FSR with
    calibration `cal` (its loading branch and the branch lag), `repeats` passes, noise [uS] RMS."""
    rng = np.random.default_rng(seed)
    up = np.arange(0.0, top_g + 0.5 * step_g, step_g)
    down = up[-2::-1]
    lag = FsrBranchLag(cal, n=1)
    lines = ["# source = teleop.core.calibration.generate.fsr_step_protocol (synthetic)",
             f"# truth = FsrCalibration loading {list(cal.loading)} unloading {list(cal.unloading)}",
             "tension_N,conductance_uS,branch"]
    for _ in range(repeats):
        for weights, branch in ((up, LOADING), (down, UNLOADING)):
            for w in weights:
                t = w * 1e-3 * G
                g = float(lag.conductance(lag.step(np.array([t])))[0]) * 1e6 + rng.normal(0.0, noise_uS)
                lines.append(f"{t:.6f},{max(g, 0.0):.6f},{'loading' if branch == LOADING else 'unloading'}")
    return "\n".join(lines) + "\n"


def _load_levels(top_N: float, step_N: float) -> np.ndarray:
    """One loop's force levels [N]: 0 -> top in steps, then back to 0."""
    return np.r_[np.arange(0.0, top_N + 1e-9, step_N), np.arange(top_N - step_N, -1e-9, -step_N)]


def _direction(F: np.ndarray) -> np.ndarray:
    """(n,) +1 after the force last rose, -1 after it last fell (+1 before it first moved)."""
    d = np.sign(np.r_[0.0, np.diff(F)])
    for k in range(1, d.size):
        if d[k] == 0:
            d[k] = d[k - 1]
    d[d == 0] = 1.0
    return d


def _hysteresis(F: np.ndarray, h: float, step_N: float, loop: str, top_N: float) -> np.ndarray:
    """(n,) the sensed force's hysteresis offset [N] along the stepped reference force F (n,) [N] (module
    docstring)."""
    if loop == "switch":
        return hysteresis_offset(F, h, 0.05 * step_N)
    if loop == "closing":
        return _direction(F) * h * np.sin(np.pi * np.clip(F / top_N, 0.0, 1.0))
    raise ValueError(f"loop must be 'switch' or 'closing', got {loop!r}")


def fbg_loop_gap(hysteresis_N: float, loop: str = "closing", top_N: float = 20.0,
                 step_N: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """(levels, gap) [N]: the true loading - unloading gap of `fbg_load_steps`' hysteresis at each force level
    strictly inside the loop (0 < F < top), after a first loop has settled it."""
    levels = _load_levels(top_N, step_N)
    F = np.r_[levels, levels]
    off = _hysteresis(F, hysteresis_N, step_N, loop, top_N)[levels.size:]
    n_up = int(np.argmax(levels)) + 1
    inside = levels[1:n_up - 1]
    up = off[1:n_up - 1]
    down = off[n_up:][::-1][1:]  # unloading, from the lowest level above 0 upwards
    return inside, up - down[:inside.size]


def fbg_load_steps(p: FbgParams = FbgParams(), hysteresis_N: float = 0.48, temperatures_C=(25.0, 45.0, 65.0),
                   seed: int = 0, top_N: float = 20.0, step_N: float = 2.0, hold: int = 20,
                   force_noise_N: float = 0.01, with_branch: bool = False, loop: str = "closing") -> str:
    """CSV text (t_s, force_N, temperature_C, dl1_pm, dl2_pm[, branch]) of load steps 0 -> top -> 0 at each
    temperature. `loop` "closing" (default, seed 001 Fig 4a's shape): the loading - unloading gap is 2h at
    mid-span and zero at the loop's ends (`fbg_loop_gap`; seed 001's largest gap, 4.798 % of 20 N, is
    h = 0.48 N); "switch": `hysteresis_N` is the catalogue hysteresis h, a gap 2h everywhere, switching at
    the turns. The reference force carries `force_noise_N` RMS noise."""
    rng = np.random.default_rng(seed)
    levels = _load_levels(top_N, step_N)
    F, T = [], []
    for temp in temperatures_C:
        for f in levels:
            F += [f] * hold
            T += list(temp + rng.normal(0.0, 0.05, hold))
    F, T = np.array(F), np.array(T)
    F_sensed = F + _hysteresis(F, hysteresis_N, step_N, loop, top_N)
    dl1, dl2 = synthesize_fbg(F_sensed, T - temperatures_C[0], p, rng)
    F_ref = F + rng.normal(0.0, force_noise_N, F.shape)
    branch = _direction(F)
    head = "t_s,force_N,temperature_C,dl1_pm,dl2_pm" + (",branch" if with_branch else "")
    lines = ["# source = teleop.core.calibration.generate.fbg_load_steps (synthetic)",
             f"# truth = S {p.S_pm_N} pm/N, kT1 {p.kT1_pm_C}, kT2 {p.kT2_pm_C} pm/degC, h {hysteresis_N} N"
             + ("" if loop == "switch" else f", {loop} loop (gap 2h at mid-span, 0 at the ends)"), head]
    for k in range(F.size):
        row = f"{k * 0.1:.1f},{F_ref[k]:.5f},{T[k]:.4f},{dl1[k]:.4f},{dl2[k]:.4f}"
        if with_branch:
            row += "," + ("unloading" if branch[k] < 0 else "loading")
        lines.append(row)
    return "\n".join(lines) + "\n"


def one_cable_cycles(mu: float = 0.08, theta: float = 2 * math.pi, seed: int = 0, cycles: int = 3,
                     fs_hz: float = 200.0, period_s: float = 4.0, amplitude_m: float = 5e-3,
                     spring_N_per_m: float = 800.0, preload_N: float = 6.0, noise_N: float = 0.02) -> tuple[str, dict]:
    """(CSV text, truth) of one cable pulling a spring through a sheath bent by theta [rad]: interchange
    columns t_s, motor_pos_mm, motor_force_N, tip_force_N. Truth: Kp = exp(-mu theta), Kr = exp(mu theta)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(cycles * period_s * fs_hz)) / fs_hz
    x = amplitude_m * np.sin(2 * np.pi * t / period_s)
    F_tip = preload_N + spring_N_per_m * x
    band = 2 * preload_N * math.sinh(mu * theta)
    k_stick = band / (0.01 * amplitude_m)            # the transition takes 1 % of the stroke
    F_m = tip2motor_transitions(x, F_tip, mu, theta, k_stick)
    cols = np.column_stack([t, x * 1e3, F_m + rng.normal(0, noise_N, t.size), F_tip + rng.normal(0, noise_N, t.size)])
    lines = ["# load = spring", "# source = teleop.core.calibration.generate.one_cable_cycles (synthetic)",
             "t_s,motor_pos_mm,motor_force_N,tip_force_N"]
    lines += [",".join(f"{v:.9g}" for v in row) for row in cols]
    return "\n".join(lines) + "\n", {"Kp": math.exp(-mu * theta), "Kr": math.exp(mu * theta), "bp": 0.0, "br": 0.0}
