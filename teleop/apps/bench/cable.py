"""`teleop bench cable --experiment fig9|fig10b|fig11|fig13 [--seed S] [--json F] [--plot F]`: seed 000's
single-cable experiments on the simulated single-cable bench (scenes.cable_rig), each beside the seed's
numbers.

The cable (seed 000 Fig 8): motor -> A-B (Bowden sheath, theta1 = 360 deg) -> FSR at B (the distal sensor)
-> B-C (scaffold, theta0 = 140 deg) -> C-D (theta, the robot's bend) -> load. The bench runs the sheath
segments as the rig's capstan law with stick transitions: B-D with the project's mu = 0.056
(teleop.core.geometry, fitted to Fig 9's distal swings), A-B with MU_AB, fitted here to Fig 9a's proximal
swing (2.48/1.50 N at theta = 0); Fig 9b (theta = 30 deg) is then a prediction. The FSR reads the tension
at B through its own physics (teleop.core.sensors: branch lag, conductance, 10-bit ADC with 1 count RMS noise)
and the loop's converter (FsrConverter, branch by reading direction).

- fig9: proximal (strain gauge at the motor, Fig 8b) vs distal (FSR at B, Fig 8a) force while the motor
  moves back and forth under a hanging weight, at theta = 0, 30, 60, 90 deg; the seed's pretensions
  1.96 N (0 deg) and 2.94 N (30, 60, 90 deg).
- fig10b: the FSR's swing over a back-and-forth (three times) under each hanging weight 0.49-4.9 N (50-500 g)
  at theta = 60 deg, before and after the capstan compensation (seed eq 3 over theta0 + theta, the
  direction from the motor's motion).
- fig11: the FSR-modelled tip tension (capstan compensation over theta0 + theta, seed eq 3/7: the direction
  from the motor's motion) against the F/T ground truth of a spring, the motor at variable speed:
  (b) a sine, (c) a sum of two sines; A-B bent 360 and 180 deg. Also the project's flat-transition
  compensator (teleop.core.physics.motor2tip_transitions), which needs no direction.
- fig13: no load (the pretension weight only), the cable moved 20 mm back and forth twice at 0.5 mm/s:
  the sensed force (estimate minus pretension; the truth is 0) without compensation, with the single
  (capstan) compensation and with the double one (the seed's turn polynomials, teleop.core.estimation.turn,
  fitted on one run and applied to a second run with other noise).
In the simulation the FSR at B sees only the B-D sheath, so the A-B bend cannot change what it reads
(the seed's Fig 11 finding holds here by construction; the proximal force does change and is shown).

`--plant distributed`: the one cable is the distributed tendon-sheath cable (scenes.tendon_sheath, its
parameters from `--cable-params` TOML or its defaults: route bend A-B, FSR at B, scaffold bend B-C, the
bend theta at the tip) in place of the two capstan segments; the proximal gauge reads the tension at the
sheath's entrance, the FSR the tension at B (`tension_at_b`), the load is the hanging weight (a force) or
the spring. Nothing is fitted: mu_AB and mu_BD are the cable's one mu_c. The FSR there is the sensor alone
(scenes.fsr_sensor.FsrSensor: the Interlink datasheet's 10 % hysteresis as a Preisach operator, not the
calibration's branch gap, which also holds the calibration rig's friction), read through the same converter.
"""

from __future__ import annotations

import math
from dataclasses import asdict

import numpy as np

from scenes.cable_rig import simulate
from scenes.fsr_lab import LAB_SEED, lab_fit
from scenes.fsr_sensor import FsrSensor, FsrSensorParams
from scenes.tendon_sheath import SheathLoad, TendonSheath, TendonSheathParams, tension_at_b
from teleop.apps.argtypes import input_file
from teleop.core.errors import InputError
from teleop.core.estimation.turn import TurnCompensation, TurnCompensator, fit_turn_compensation
from teleop.core.geometry import Geometry
from teleop.core.physics import motor2tip, motor2tip_transitions
from teleop.core.sensors import FsrBranchLag, FsrCalibration, FsrConverter, default_fsr_calibration
from teleop.io.figures import legend_outside
from teleop.io.outputs import check_output, save_figure, write_json

EXPERIMENTS = ("fig9", "fig10b", "fig11", "fig13")
THETA0 = math.radians(140.0)
THETA1 = math.radians(360.0)
FS_HZ = 100.0
G_N_PER_KG = 9.80665  # standard gravity: the seed's weights in newtons

#: the seed's figures in numbers (seed 000 sec. 3.2 text; Fig 11 and 13 are reported in words only)
SEED = {
    "fig9": {"0": {"pretension_N": 1.96, "distal_N": [2.25, 1.71], "proximal_N": [2.48, 1.50]},
             "30": {"pretension_N": 2.94, "distal_N": [3.32, 2.39], "proximal_N": [4.43, 1.74]}},
    "fig10b": ["for a constant weight the change in the modelled force is smaller after the capstan compensation "
               "(0.49-4.9 N, theta = 60 deg, three back-and-forths each)"],
    "fig11": ["the force measured by the FSR aligns well with the ground truth",
              "a sudden shift, quickly returning to normal, when the motor's direction or speed changes rapidly",
              "the results for 360 and 180 deg of A-B are almost identical"],
    "fig13": ["without compensation the readings are unstable during no-load motion",
              "single compensation: stable except a sudden change at each turn (segments EF, GH)",
              "double compensation: the change at the turns diminished, stable throughout"],
}


def mu_bd() -> float:
    """Sheath friction coefficient of B-D: the project's geometry default (fitted to Fig 9's distal swings)."""
    return float(Geometry.__dataclass_fields__["mu"].default)


def mu_ab() -> float:
    """A-B's friction coefficient from Fig 9a's proximal swing: 2.48 / 1.50 = exp(2 (mu (theta0) + mu_ab theta1))."""
    s = SEED["fig9"]["0"]["proximal_N"]
    return (0.5 * math.log(s[0] / s[1]) - mu_bd() * THETA0) / THETA1


def register(subparsers) -> None:
    p = subparsers.add_parser("cable", help="seed 000 single-cable experiments (Fig 9, 11, 13) on the simulated bench")
    p.add_argument("--experiment", choices=EXPERIMENTS, required=True, help="which figure to reproduce")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    p.add_argument("--plant", default="matched", choices=("matched", "distributed"),
                   help="the cable: matched (the rig's capstan segments, default) or distributed (the distributed "
                        "tendon-sheath cable, scenes/tendon_sheath.py)")
    p.add_argument("--cable-params", type=input_file, default=None, metavar="TOML",
                   help="with --plant distributed: the cable's [tendon_sheath] table (docs/formats.md)")
    p.add_argument("--fsr-calibration", default="builtin", choices=("builtin", "platform"),
                   help="the FSR's calibration the converter reads with: builtin (default) or, with --plant "
                        "distributed, platform (the one fitted on that cable's simulated calibration platform, "
                        "scenes.fsr_lab, as the distributed robot's estimators)")
    p.add_argument("--json", metavar="F", help="write the numbers as JSON")
    p.add_argument("--plot", metavar="F", help="write the figure (PNG)")
    p.set_defaults(func=run)


# ---- the bench -------------------------------------------------------------------------------------------

def _columns(rec) -> dict:
    lines = [ln for ln in rec.csv.splitlines() if not ln.startswith("#")]
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    return dict(zip(lines[0].split(","), data.T))


def sheath(seed: int, x: np.ndarray, theta, mu: float, load: dict, noise: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(motor-side force, load-side force) [N] of one sheath segment on the rig: motor haul-in x (n,) [m] at
    FS_HZ, bend theta [rad], friction mu, load {"tip_force": (n,)} (external) or {"spring_N_per_m",
    "preload_N"}; ideal sensors, force noise `noise` x 0.4 % of the mean load. Stick transitions over 2 %
    of the stroke."""
    spring = "spring_N_per_m" in load
    F_mean = float(np.mean(load["tip_force"])) if not spring else load["preload_N"]
    A = 0.5 * float(np.ptp(x)) or 1e-3
    k_stick = 2 * F_mean * math.sinh(mu * float(np.mean(theta))) / (0.02 * A)
    given = {"x": x - float(np.mean(x)) if spring else x, "theta": theta, "mu": mu, "k_stick": max(k_stick, 1.0),
             "ideal_sensors": True, **load}
    rec = simulate(seed, load="spring" if spring else "external", fs_hz=FS_HZ, duration_s=x.size / FS_HZ,
                   noise=noise, given=given, columns=("motor_pos_mm", "motor_force_N", "tip_force_N"))
    c = _columns(rec)
    return c["motor_force_N"], c["tip_force_N"]


def distributed(seed: int, x: np.ndarray, theta: float, load: dict, cable: TendonSheathParams, theta1=None,
                noise: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(proximal force at the sheath's entrance, tension at B, tip load force) [N] of the one cable as the
    distributed tendon-sheath cable: motor haul-in x (n,) [m] at FS_HZ (from its first sample), the bend
    theta of C-D [rad], load {"tip_force": (n,)} (a force) or {"spring_N_per_m", "preload_N"}, the route bend
    A-B theta1 [rad] (None: the cable's). The proximal gauge's noise: `noise` x 0.4 % of the mean load."""
    if "tip_force" in load:
        tip = np.asarray(load["tip_force"], dtype=float)
        sheath = TendonSheath(cable, SheathLoad("force"), pretension=float(tip[0]), tick=1.0 / FS_HZ, theta1=theta1)
        F_mean = float(np.mean(tip))
    else:
        sheath = TendonSheath(cable, SheathLoad("spring", stiffness=load["spring_N_per_m"]),
                              pretension=load["preload_N"], tick=1.0 / FS_HZ, theta1=theta1)
        tip, F_mean = np.zeros(x.size), load["preload_N"]
    run = sheath.run(x - x[0], tip, theta, keep_tensions=True)
    proximal = run.f_motor[:, 0] + np.random.default_rng(seed).normal(0.0, 0.004 * F_mean * noise, x.size)
    return proximal, tension_at_b(run.tensions[:, 0, :], cable, theta1), run.f_tip[:, 0]


def fsr_reading(T: np.ndarray, seed: int, noise_counts: float = 1.0, alone: bool = False,
                converter: FsrCalibration | None = None) -> np.ndarray:
    """(n,) tension [N] the distal FSR reports for true tension T (n,) [N], through the loop's converter
    (FsrConverter: the calibration's branch by the reading's direction) with the calibration `converter`
    (None: the built-in one). The sensor: `alone` False, the matched robot's (teleop.core.sensors.FsrBranchLag:
    the calibration's whole branch gap as its play, conductance, ADC); True, the FSR alone
    (scenes.fsr_sensor.FsrSensor: the datasheet's own hysteresis on the built-in loading branch, used with the
    distributed cable)."""
    cal = default_fsr_calibration()
    if alone:
        counts = FsrSensor(1, seed, FsrSensorParams(noise_counts=noise_counts), cal).run(np.asarray(T, dtype=float))
    else:
        lag = FsrBranchLag(cal, n=1)
        u = lag.run(np.asarray(T, dtype=float)[:, None])[:, 0]
        rng = np.random.default_rng(seed)
        counts = np.clip(np.rint(cal.conductance2counts(lag.conductance(u)) + rng.normal(0, noise_counts, u.size)),
                         0, cal.adc_max)
    conv = FsrConverter(cal if converter is None else converter, n=1)
    return np.array([conv.update(c[None])[0] for c in counts])


def single_compensation(F: np.ndarray, x: np.ndarray, mu: float, theta: float) -> np.ndarray:
    """Seed eq 7: tip tension from the distal reading F (n,) [N], pulling/releasing by the motor's motion."""
    v = np.gradient(x)
    pulling = np.where(v != 0, v > 0, True)
    held = np.maximum.accumulate(np.where(v != 0, np.arange(v.size), 0))     # at rest: the last direction
    return motor2tip(F, mu, theta, pulling[held])


def _strokes(x: np.ndarray) -> list[tuple[int, int, int]]:
    """(start, end, direction) of each stroke of a back-and-forth x."""
    d = np.sign(np.diff(x))
    moving = np.nonzero(d)[0]
    if moving.size == 0:
        return []
    # a rest continues the stroke before it (the first rest belongs to the first stroke)
    d = d[np.maximum.accumulate(np.where(d != 0, np.arange(d.size), moving[0]))]
    cuts = np.r_[0, np.nonzero(np.diff(d))[0] + 1, d.size]
    return [(int(a), int(b), int(d[a])) for a, b in zip(cuts[:-1], cuts[1:]) if b > a]


def _levels(F: np.ndarray, x: np.ndarray, skip: float = 0.4) -> tuple[float, float]:
    """(pulling level, releasing level) [N]: medians of F over the strokes, the first `skip` of each left out
    (the transition), the first stroke too (it starts from rest)."""
    up, down = [], []
    for a, b, d in _strokes(x)[1:]:
        seg = F[a + int(skip * (b - a)):b]
        (up if d > 0 else down).append(seg)
    return float(np.median(np.concatenate(up))), float(np.median(np.concatenate(down)))


def triangle(amplitude: float, speed: float, strokes: int, rest_s: float = 1.0) -> np.ndarray:
    """Motor haul-in [m] at FS_HZ: rest, then `strokes` strokes of 2 amplitude at `speed` [m/s] from
    -amplitude, alternating, then rest."""
    n = int(round(2 * amplitude / speed * FS_HZ))
    ramp = np.linspace(-amplitude, amplitude, n, endpoint=False)
    parts = [np.full(int(rest_s * FS_HZ), -amplitude)]
    for k in range(strokes):
        parts.append(ramp if k % 2 == 0 else ramp[::-1] + (ramp[1] - ramp[0]))
    parts.append(np.full(int(rest_s * FS_HZ), parts[-1][-1]))
    return np.concatenate(parts)


# ---- experiments -----------------------------------------------------------------------------------------

def _cable_keys(cable: TendonSheathParams | None) -> dict:
    """The JSON's plant keys: none for the rig's capstan segments, the distributed cable's parameters."""
    return {} if cable is None else {"plant": "distributed", "cable": asdict(cable)}


def fig9(seed: int = 0, cable: TendonSheathParams | None = None, converter: FsrCalibration | None = None) -> dict:
    """Proximal vs distal force under a hanging weight at theta = 0, 30, 60, 90 deg (module docstring);
    `cable`: the distributed cable in place of the rig's capstan segments; `converter`: the FSR's calibration
    (None: the built-in one; fsr_reading)."""
    x = triangle(5e-3, 2e-3, 6)
    out = {"mu_BD": mu_bd(), "mu_AB": mu_ab(), "theta0_deg": 140.0, "theta1_deg": 360.0, "cases": {}, "series": {}}
    if cable is not None:
        out.update(mu_BD=cable.mu_c, mu_AB=cable.mu_c, theta0_deg=math.degrees(cable.theta0),
                   theta1_deg=math.degrees(cable.theta1), **_cable_keys(cable))
    for k, deg in enumerate((0, 30, 60, 90)):
        W = 1.96 if deg == 0 else 2.94
        if cable is None:
            T_B, _ = sheath(seed + k, x, THETA0 + math.radians(deg), mu_bd(), {"tip_force": np.full(x.size, W)})
            proximal, _ = sheath(seed + 200 + k, x, THETA1, mu_ab(), {"tip_force": T_B}, noise=1.0)
        else:
            proximal, T_B, _ = distributed(seed + 200 + k, x, math.radians(deg), {"tip_force": np.full(x.size, W)},
                                           cable, noise=1.0)
        distal = fsr_reading(T_B, seed + 100 + k, alone=cable is not None, converter=converter)
        d, p, b = _levels(distal, x), _levels(proximal, x), _levels(T_B, x)
        case = {"pretension_N": W, "distal_N": list(d), "proximal_N": list(p), "distal_change_N": d[0] - d[1],
                "proximal_change_N": p[0] - p[1], "tension_B_N": list(b), "tension_B_change_N": b[0] - b[1]}
        s = SEED["fig9"].get(str(deg))
        if s:
            case["seed"] = {**s, "distal_change_N": s["distal_N"][0] - s["distal_N"][1],
                            "proximal_change_N": s["proximal_N"][0] - s["proximal_N"][1]}
        out["cases"][str(deg)] = case
        out["series"][str(deg)] = {"t": np.arange(x.size) / FS_HZ, "x": x, "distal": distal, "proximal": proximal,
                                   "tension_B": T_B}
    return out


def fig10b(seed: int = 0, cable: TendonSheathParams | None = None, weights_N=None, theta_deg: float = 60.0,
           converter: FsrCalibration | None = None) -> dict:
    """The FSR's swing before and after the capstan compensation under each hanging weight (module docstring);
    `cable`: the distributed cable in place of the rig's capstan segments; weights_N: default 0.49-4.9 N;
    `converter`: the FSR's calibration (None: the built-in one)."""
    x = triangle(5e-3, 2e-3, 6)
    theta = math.radians(theta_deg)
    weights = np.arange(50, 501, 50) * 1e-3 * G_N_PER_KG if weights_N is None else weights_N  # 50-500 g
    out = {"theta_CD_deg": theta_deg, "mu_compensation": mu_bd(), "cases": {}, **_cable_keys(cable)}
    for k, W in enumerate(weights):
        W = float(W)
        if cable is None:
            T_B, _ = sheath(seed + k, x, THETA0 + theta, mu_bd(), {"tip_force": np.full(x.size, W)})
        else:
            _, T_B, _ = distributed(seed + k, x, theta, {"tip_force": np.full(x.size, W)}, cable)
        F = fsr_reading(T_B, seed + 100 + k, alone=cable is not None, converter=converter)
        comp = single_compensation(F, x, mu_bd(), THETA0 + theta)
        (f_hi, f_lo), (c_hi, c_lo), (b_hi, b_lo) = _levels(F, x), _levels(comp, x), _levels(T_B, x)
        out["cases"][f"{W:g}"] = {"weight_N": W, "fsr_change_N": f_hi - f_lo, "compensated_change_N": c_hi - c_lo,
                                  "tension_B_change_N": b_hi - b_lo,
                                  "compensated_error_N": 0.5 * (c_hi + c_lo) - W}
    ch = [c["fsr_change_N"] for c in out["cases"].values()]
    cc = [c["compensated_change_N"] for c in out["cases"].values()]
    out["smaller_after_compensation"] = int(sum(abs(b) < abs(a) for a, b in zip(ch, cc)))
    out["seed"] = SEED["fig10b"]
    return out


def _errors(est: np.ndarray, truth: np.ndarray, x: np.ndarray, window_s: float = 1.0) -> dict:
    e = est - truth
    near = np.zeros(e.size, dtype=bool)
    for a, _, _ in _strokes(x)[1:]:
        near[a:a + int(window_s * FS_HZ)] = True
    return {"rmse_N": float(np.sqrt(np.mean(e ** 2))), "max_abs_N": float(np.max(np.abs(e))),
            "rmse_away_from_turns_N": float(np.sqrt(np.mean(e[~near] ** 2))),
            "max_abs_near_turns_N": float(np.max(np.abs(e[near]))) if near.any() else 0.0}


def fig11(seed: int = 0, theta_deg: float = 0.0, cable: TendonSheathParams | None = None,
          converter: FsrCalibration | None = None) -> dict:
    """FSR-modelled tension against the F/T truth of a spring at variable motor speed (module docstring);
    `cable`: the distributed cable in place of the rig's capstan segments."""
    t = np.arange(int(20 * FS_HZ)) / FS_HZ
    motions = {"b": 4e-3 * np.sin(2 * np.pi * 0.15 * t),
               "c": 2.5e-3 * np.sin(2 * np.pi * 0.12 * t) + 1.5e-3 * np.sin(2 * np.pi * 0.41 * t + 1.0)}
    theta = THETA0 + math.radians(theta_deg)
    load = {"spring_N_per_m": 400.0, "preload_N": 3.0}
    out = {"theta_CD_deg": theta_deg, "spring": load, "cases": {}, "series": {}, **_cable_keys(cable)}
    for k, (name, x) in enumerate(motions.items()):
        if cable is None:
            T_B, truth = sheath(seed + k, x, theta, mu_bd(), load, noise=1.0)
        for ab in (360, 180):
            if cable is None:  # the proximal (motor) force over A-B: the FSR does not see it
                proximal, _ = sheath(seed + 10 + k, x, math.radians(ab), mu_ab(), {"tip_force": T_B})
            else:  # one cable: A-B's bend may change what reaches B
                proximal, T_B, truth = distributed(seed + 10 + k, x, math.radians(theta_deg), load, cable,
                                                   theta1=math.radians(ab))
            # the FSR at B: the same tension whatever A-B does
            F = fsr_reading(T_B, seed + 100 + k, alone=cable is not None, converter=converter)
            single = single_compensation(F, x, mu_bd(), theta)
            flat = motor2tip_transitions(F, mu_bd(), theta)
            key = f"{name}_{ab}"
            out["cases"][key] = {"motion": name, "AB_deg": ab, "fsr_raw": _errors(F, truth, x),
                                 "single": _errors(single, truth, x), "flat_transitions": _errors(flat, truth, x),
                                 "proximal_range_N": [float(proximal.min()), float(proximal.max())]}
            out["series"][key] = {"t": t, "truth": truth, "fsr": F, "single": single, "flat": flat, "proximal": proximal}
    out["seed"] = SEED["fig11"]
    return out


def fig13(seed: int = 0, pretensions_N=(1.96, 4.9), speed_mm_s: float = 0.5,
          cable: TendonSheathParams | None = None, converter: FsrCalibration | None = None) -> dict:
    """No-load back and forth, 20 mm twice at 0.5 mm/s: sensed force without, single and double compensation,
    at each pretension (the weight that keeps the cable taut; the truth is 0); `cable`: the distributed cable
    in place of the rig's capstan segments."""
    x = triangle(10e-3, speed_mm_s * 1e-3, 4, rest_s=5.0)
    t = np.arange(x.size) / FS_HZ
    out = {"stroke_mm": 20.0, "speed_mm_s": speed_mm_s, "strokes": 4, "pretensions": {}, "series": {"t": t, "x": x},
           **_cable_keys(cable)}
    for k, W in enumerate(pretensions_N):
        res, sensed = _no_load(seed + 10 * k, x, float(W), cable, converter)
        out["pretensions"][f"{W:g}"] = res
        out["series"][f"{W:g}"] = sensed
    out["seed"] = SEED["fig13"]
    return out


def _no_load(seed: int, x: np.ndarray, W: float, cable: TendonSheathParams | None = None,
             converter: FsrCalibration | None = None) -> tuple[dict, dict]:
    t = np.arange(x.size) / FS_HZ
    runs = []
    for r in range(2):                       # run 0 fits the turn polynomials, run 1 is measured
        if cable is None:
            T_B, _ = sheath(seed + r, x, THETA0, mu_bd(), {"tip_force": np.full(x.size, W)})
        else:  # the same cable twice: the runs differ in the FSR's noise
            _, T_B, _ = distributed(seed + r, x, 0.0, {"tip_force": np.full(x.size, W)}, cable)
        F = fsr_reading(T_B, seed + 100 + r, alone=cable is not None, converter=converter)
        runs.append((F, single_compensation(F, x, mu_bd(), THETA0), T_B))
    poses = np.zeros((x.size, 6))
    poses[:, 2] = x
    wrench = np.zeros((x.size, 6))
    wrench[:, 2] = runs[0][1] - W
    F, single, T_B = runs[1]
    try:
        fit = fit_turn_compensation(t, poses, wrench, axis=2)
        comp = TurnCompensator(TurnCompensation(axes=(fit,)))
        corr = np.array([comp.update((0.0, 0.0, xk), 1.0 / FS_HZ)[2] for xk in x])
        duration = fit.duration
    except InputError:
        corr, duration = np.zeros(x.size), float("nan")
    double = single - corr
    flat = motor2tip_transitions(F, mu_bd(), THETA0)
    sensed = {"non_compensated": F - W, "single": single - W, "double": double - W, "flat_transitions": flat - W}
    moving = np.abs(np.gradient(x)) > 0
    seen = float(np.ptp(F[moving]))
    res = {"pretension_N": W, "turn_fit_duration_s": duration, "fsr_range_moving_N": seen,
           "tension_B_range_moving_N": float(np.ptp(T_B[moving])), "cases": {}}
    window = duration if np.isfinite(duration) and duration < 10 else 1.0
    for name, v in sensed.items():
        e = _errors(v, np.zeros(x.size), x, window_s=window)
        e["peak_to_peak_moving_N"] = float(np.ptp(v[moving]))
        res["cases"][name] = e
    return res, sensed


# ---- output ----------------------------------------------------------------------------------------------

def table(name: str, res: dict) -> str:
    """The numbers beside the seed's, as text."""
    lines = []
    if name == "fig9":
        how = "the distributed cable's mu_c" if res.get("plant") == "distributed" else \
            "fitted to Fig 9a's proximal swing"
        lines.append(f"seed 000 Fig 9 on the simulated bench: mu(B-D) = {res['mu_BD']:.4f}, mu(A-B) = {res['mu_AB']:.4f} "
                     f"({how}), theta0 {res['theta0_deg']:g} deg, theta1 {res['theta1_deg']:g} deg")
        lines.append("distal = what the FSR at B reports; tension at B = the cable's true tension there (no sensor)")
        lines.append(f"{'theta':>6} {'W [N]':>6}  {'distal hi/lo (change) [N]':>28}  {'proximal hi/lo (change) [N]':>30}"
                     f"  {'tension at B hi/lo (change)':>28}")
        for deg, c in res["cases"].items():
            lines.append(f"{deg:>6} {c['pretension_N']:6.2f}  ours {c['distal_N'][0]:5.2f}/{c['distal_N'][1]:5.2f} "
                         f"({c['distal_change_N']:4.2f})       ours {c['proximal_N'][0]:5.2f}/{c['proximal_N'][1]:5.2f} "
                         f"({c['proximal_change_N']:4.2f})       {c['tension_B_N'][0]:5.2f}/{c['tension_B_N'][1]:5.2f} "
                         f"({c['tension_B_change_N']:4.2f})")
            if "seed" in c:
                s = c["seed"]
                lines.append(f"{'':>6} {'':>6}  seed {s['distal_N'][0]:5.2f}/{s['distal_N'][1]:5.2f} "
                             f"({s['distal_change_N']:4.2f})       seed {s['proximal_N'][0]:5.2f}/{s['proximal_N'][1]:5.2f} "
                             f"({s['proximal_change_N']:4.2f})")
    elif name == "fig10b":
        lines.append(f"seed 000 Fig 10b on the simulated bench: theta {res['theta_CD_deg']:g} deg, swing of the FSR "
                     f"over three back-and-forths before and after the capstan compensation (mu "
                     f"{res['mu_compensation']:.3f}) [N]")
        lines.append(f"{'weight':>7} {'FSR':>7} {'compensated':>12} {'tension at B':>13} {'comp. level - W':>16}")
        for c in res["cases"].values():
            lines.append(f"{c['weight_N']:7.2f} {c['fsr_change_N']:7.3f} {c['compensated_change_N']:12.3f} "
                         f"{c['tension_B_change_N']:13.3f} {c['compensated_error_N']:16.3f}")
        lines.append(f"smaller after compensation at {res['smaller_after_compensation']} of {len(res['cases'])} weights")
        lines += ["seed (in words): " + s for s in res["seed"]]
    elif name == "fig11":
        lines.append(f"seed 000 Fig 11 on the simulated bench (spring {res['spring']['spring_N_per_m']:g} N/m, "
                     f"preload {res['spring']['preload_N']:g} N, theta_CD {res['theta_CD_deg']:g} deg): "
                     f"modelled tension minus F/T truth [N]")
        lines.append(f"{'case':>8} {'estimate':>17} {'RMSE':>6} {'max':>6} {'RMSE off turns':>15} {'max near turns':>15}")
        for key, c in res["cases"].items():
            for est in ("fsr_raw", "single", "flat_transitions"):
                e = c[est]
                lines.append(f"{key:>8} {est:>17} {e['rmse_N']:6.3f} {e['max_abs_N']:6.3f} "
                             f"{e['rmse_away_from_turns_N']:15.3f} {e['max_abs_near_turns_N']:15.3f}")
            lines.append(f"{'':>8} proximal force range {c['proximal_range_N'][0]:.2f}-{c['proximal_range_N'][1]:.2f} N "
                         f"(A-B {c['AB_deg']} deg)")
        lines += ["seed (in words): " + s for s in res["seed"]]
    else:
        lines.append(f"seed 000 Fig 13 on the simulated bench: no load, {res['strokes']} strokes of "
                     f"{res['stroke_mm']:g} mm at {res['speed_mm_s']:g} mm/s; sensed force (truth 0) [N]")
        for W, r in res["pretensions"].items():
            lines.append(f"pretension {W} N: tension at B swings {r['tension_B_range_moving_N']:.3f} N, the FSR reports "
                         f"a {r['fsr_range_moving_N']:.3f} N range; turn polynomials over "
                         f"{r['turn_fit_duration_s']:.2f} s after a turn")
            lines.append(f"{'estimate':>17} {'RMSE':>6} {'max':>6} {'p-p moving':>10} {'RMSE off turns':>15} "
                         f"{'max near turns':>15}")
            for est, e in r["cases"].items():
                lines.append(f"{est:>17} {e['rmse_N']:6.3f} {e['max_abs_N']:6.3f} {e['peak_to_peak_moving_N']:10.3f} "
                             f"{e['rmse_away_from_turns_N']:15.3f} {e['max_abs_near_turns_N']:15.3f}")
        lines += ["seed (in words): " + s for s in res["seed"]]
    return "\n".join(lines)


FIGURE_TITLES = {"fig9": "seed 000 Fig 9: proximal (strain gauge) vs distal (FSR at B) force, hanging weight",
                 "fig10b": "seed 000 Fig 10b: FSR swing before and after capstan compensation",
                 "fig11": "seed 000 Fig 11: FSR-modelled tip tension vs F/T ground truth (spring load)",
                 "fig13": "seed 000 Fig 13: no-load back and forth, tip tension estimate minus pretension"}


def figure_title(name: str, res: dict, noise_seed: int | None = None) -> str:
    """What the figure is: the experiment, the bench, the plant (the cable's model) and the sensor."""
    plant = res.get("plant", "matched")
    cable = "distributed tendon-sheath cable" if plant == "distributed" else "capstan segments"
    return (f"{FIGURE_TITLES[name]}\nsimulated single-cable bench, plant {plant} ({cable}), sensor FSR at B"
            + ("" if noise_seed is None else f", noise seed {noise_seed}"))


def figure(name: str, res: dict, noise_seed: int | None = None):
    """The figure laid out like the seed's, titled by `figure_title`."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    if name == "fig9":
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
        for ax, deg, tag in ((axes[0], "0", "a"), (axes[1], "30", "b")):
            s, c = res["series"][deg], res["cases"][deg]
            ax.plot(s["t"], s["proximal"], color="tab:orange", lw=0.8, label="proximal (strain gauge at the motor)")
            ax.plot(s["t"], s["tension_B"], color="tab:cyan", lw=2.0, alpha=0.6, label="true tension at B")
            ax.plot(s["t"], s["distal"], color="tab:blue", lw=0.8, label="distal (FSR at B)")
            seed = c["seed"]
            for v in seed["proximal_N"]:
                ax.axhline(v, color="tab:orange", ls="--", lw=0.8)
            for v in seed["distal_N"]:
                ax.axhline(v, color="tab:blue", ls="--", lw=0.8)
            ax.plot([], [], "k--", lw=0.8, label="seed's levels")
            ax.set_title(f"({tag}) theta = {deg} deg, pretension {c['pretension_N']} N", fontsize=9)
            ax.set_xlabel("time [s]")
            ax.set_ylabel("cable tension [N]")
        ax = axes[2]
        degs = [int(d) for d in res["cases"]]
        ax.plot(degs, [res["cases"][str(d)]["proximal_change_N"] for d in degs], "o-", color="tab:orange",
                label="proximal, ours")
        ax.plot(degs, [res["cases"][str(d)]["distal_change_N"] for d in degs], "o-", color="tab:blue", label="distal, ours")
        seeded = [d for d in degs if "seed" in res["cases"][str(d)]]
        ax.plot(seeded, [res["cases"][str(d)]["seed"]["proximal_change_N"] for d in seeded], "s", mfc="none",
                color="tab:orange", ms=9, label="proximal, seed")
        ax.plot(seeded, [res["cases"][str(d)]["seed"]["distal_change_N"] for d in seeded], "s", mfc="none",
                color="tab:blue", ms=9, label="distal, seed")
        ax.set_xlabel("bend angle theta of C-D [deg]")
        ax.set_ylabel("force change over a back-and-forth [N]")
        ax.set_title("(c) change vs bend (1.96 N at 0 deg, 2.94 N otherwise)", fontsize=9)
        legend_outside(axes[0], "below", ncol=2)
        legend_outside(ax, "below", ncol=2)
    elif name == "fig10b":
        fig, ax = plt.subplots(figsize=(7, 4.5))
        cs = list(res["cases"].values())
        w = [c["weight_N"] for c in cs]
        ax.plot(w, [c["fsr_change_N"] for c in cs], "o-", label="FSR reading, no compensation")
        ax.plot(w, [c["compensated_change_N"] for c in cs], "s-", label="after capstan compensation")
        ax.plot(w, [c["tension_B_change_N"] for c in cs], ":", color="grey", label="true tension at B")
        ax.set_xlabel("hanging weight [N]")
        ax.set_ylabel("swing over a back-and-forth [N]")
        ax.set_title(f"theta = {res['theta_CD_deg']:g} deg, 3 back-and-forths per weight", fontsize=9)
        legend_outside(ax, "right")
    elif name == "fig11":
        fig, axes = plt.subplots(1, 2, figsize=(14, 4.5))
        for ax, m, tag in ((axes[0], "b", "sine"), (axes[1], "c", "sum of two sines")):
            s, s180 = res["series"][f"{m}_360"], res["series"][f"{m}_180"]
            ax.plot(s["t"], s["truth"], "k", lw=1.2, label="ground truth (F/T at the spring)")
            ax.plot(s["t"], s["fsr"], color="0.6", lw=0.7, label="FSR reading at B (uncompensated)")
            ax.plot(s["t"], s["single"], color="tab:red", lw=0.8, label="modelled, capstan (seed eq 7), A-B 360 deg")
            ax.plot(s180["t"], s180["single"], color="tab:green", lw=0.8, ls="--", label="modelled, capstan, A-B 180 deg")
            ax.plot(s["t"], s["flat"], color="tab:blue", lw=0.8, label="modelled, flat transitions (project)")
            ax.set_title(f"({m}) motor moves as a {tag}", fontsize=9)
            ax.set_xlabel("time [s]")
            ax.set_ylabel("tension [N]")
        legend_outside(axes[0], "below", ncol=2)
        legend_outside(axes[1], "below", ncol=2)
    else:
        Ws = list(res["pretensions"])
        fig, axes = plt.subplots(len(Ws) + 1, 1, figsize=(11, 3 * len(Ws) + 2), sharex=True,
                                 gridspec_kw={"height_ratios": [3] * len(Ws) + [1]})
        s = res["series"]
        for ax, W in zip(axes, Ws):
            # single drawn wide and pale under double: where the turn polynomials change nothing both show
            for key, color, lw, alpha, label in (
                    ("non_compensated", "tab:blue", 0.8, 1.0, "without compensation"),
                    ("single", "tab:red", 2.4, 0.45, "single compensation (capstan)"),
                    ("double", "tab:green", 0.8, 1.0, "double compensation (capstan + turn polynomials)"),
                    ("flat_transitions", "tab:purple", 0.8, 1.0, "flat transitions (project)")):
                ax.plot(s["t"], s[W][key], color=color, lw=lw, alpha=alpha, label=label)
            ax.axhline(0, color="k", lw=0.5)
            ax.set_ylabel("tip tension estimate\n- pretension [N]")
            ax.set_title(f"pretension {W} N; the truth is 0 (no load)", fontsize=9)
            legend_outside(ax, "right")
        axx = axes[-1]
        axx.plot(s["t"], np.asarray(s["x"]) * 1e3, "k", lw=0.8)
        axx.set_xlabel("time [s]")
        axx.set_ylabel("cable haul-in [mm]")
    fig.suptitle(figure_title(name, res, noise_seed), fontsize=10)
    fig.tight_layout()
    return fig


def _jsonable(res: dict) -> dict:
    return {k: v for k, v in res.items() if k != "series"}


def run(args) -> int:
    for flag, path in (("--json", args.json), ("--plot", args.plot)):
        if path:
            check_output(path, flag)
    if args.cable_params is not None and args.plant != "distributed":
        raise InputError("--cable-params: the cable's parameters belong to --plant distributed")
    if args.fsr_calibration == "platform" and args.plant != "distributed":
        raise InputError("--fsr-calibration platform: the platform calibration is fitted on --plant distributed")
    cable = None
    if args.plant == "distributed":
        cable = TendonSheathParams() if args.cable_params is None else TendonSheathParams.from_toml(args.cable_params)
    converter = lab_fit(cable, FsrSensorParams(), LAB_SEED).cal if args.fsr_calibration == "platform" else None
    res = {"fig9": fig9, "fig10b": fig10b, "fig11": fig11, "fig13": fig13}[args.experiment](
        args.seed, cable=cable, converter=converter)
    print(table(args.experiment, res))
    if converter is not None:
        print("FSR converted with the platform calibration (scenes.fsr_lab, as the distributed robot's estimators)")
    if args.json:
        write_json(args.json, {"experiment": args.experiment, "seed": args.seed,
                               "fsr_calibration": args.fsr_calibration, **_jsonable(res)})
    if args.plot:
        save_figure(figure(args.experiment, res, args.seed), args.plot)
    return 0
