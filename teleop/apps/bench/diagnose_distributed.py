"""Distributed cases of `teleop bench diagnose --suite distributed`: recordings of the distributed
tendon-sheath plant (scenes.tendon_sheath: the cable as N elastic elements with LuGre friction per node, a
physics no catalogue effect is), diagnosed from their CSV alone.

Each case draws a literature-range set-up (scenes.cable_rig.draw_setup: mu, total bend at a capstan ratio
up to 5, a steel or polymer cable's EA and length, the mean tip load, the noise fraction, exact or noisy
encoders, the sampling rate) and the drive (scenes.cable_rig.trajectory, reaching past the cable's dead
zone); the plant's sheath is that cable over that bend (the route bend spread over the first BENT = 80 % of
its length, mu_s = 1.2 mu, 10 um of pre-sliding travel), its tip on a preloaded spring or an external force of
its own. The motor and tip sides of the cable are recorded (motor and tip position, motor force at the
sheath's entrance, tip force, the bend, the sensors' temperature), every third case with a catalogue sensor effect on the motor force
sensor (its own draw, Rules.draw). A distributed plant has no single catalogue effect: the case reports what
the diagnosis names, the sheath's friction coefficient its baseline capstan fits against the plant's, the
play it fits on the position link against the dead zone of Kaneko's closed form at the mean tip tension
(`dead_zone_uniform` over the bent length BENT L, where the friction is: the straight rest carries the tip's
tension on either branch and adds no dead zone; it grows with the tension) and, where the play's general form grows with the tension
(backlash's `tension`: under a spring the tip position is the tension; its `load_tension`: under an
external force the recorded tip force), its width at the 5th and 95th percentile of the tip tension against
Kaneko's there, its take-up length where it rounds the take-up (backlash's `take_up`: the plant's pre-sliding
along the sheath), and per channel the held-out RMSE over the noise the case added (the noise floor).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from scenes.cable_rig import LITERATURE, draw_setup, trajectory
from scenes.tendon_sheath import SheathLoad, TendonSheath, TendonSheathParams, dead_zone_uniform
from teleop.core.physics import REGISTRY, Signals, get_effect
from teleop.core.physics.base import Scale
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.links import smooth_width
from teleop.diagnosis.scoring import QUANTUM_M, peer_rows
from teleop.io.recording_io import interchange_text, read_interchange

#: pre-sliding travel of the plant's LuGre bristles [m] (scenes.tendon_sheath's default: mu_c / sigma0)
PRESLIDING_M = 1.0e-5
#: the fraction of the cable's length (from the motor) the route bend is spread over; the rest is straight
BENT = 0.8
#: expected of the diagnosis on a distributed plant: the capstan on the force link (in the project's
#: baseline), a play whose dead zone grows with the tension on the position link
EXPECTED = {"motor_force": "capstan_friction", "tip_pos": "backlash"}


def sensor_effects() -> tuple[str, ...]:
    """Registered sensor-link effects with a generator draw (registry order), put on the motor force sensor."""
    return tuple(n for n, e in REGISTRY.items() if e.rules.draw is not None and e.link == "sensor")


def distributed_plan(n: int) -> list[dict]:
    """n cases: the load alternating spring / external force, every third case with the next sensor effect."""
    sensors = sensor_effects()
    plan = []
    for i in range(n):
        effect = sensors[(i // 3) % len(sensors)] if (i % 3 == 2 and sensors) else "none"
        plan.append({"index": i, "load": ("spring", "force")[i % 2], "effect": effect})
    return plan


def simulate_case(case: dict, seed: int, duration_s: float = 20.0, noise: float = 1.0,
                  fs_hz: float | None = None) -> dict:
    """One recording of the distributed plant: {"csv", "setup", "truth" ({effect: params} on motor_force),
    "noise" ({channel: the added noise [SI]}), "trajectory"}; reproducible from (seed, case index)."""
    rng = np.random.default_rng([seed, case["index"], 31])
    s = draw_setup(rng, LITERATURE)
    fs = float(fs_hz or s["fs_hz"])
    t = np.arange(int(duration_s * fs)) / fs
    kind, x = trajectory(rng, t, fs, LITERATURE, 1.2 * s["dead_zone_m"])
    A = float(np.ptp(x)) / 2
    L = s["length_m"]
    params = TendonSheathParams(length=L, EA=s["EA_N"], mu_c=s["mu"], mu_s=1.2 * s["mu"],
                                sigma0=s["mu"] / PRESLIDING_M, theta0=0.0, theta1=s["bend_rad"],
                                route_span=(0.0, BENT * L), scaffold_span=(BENT * L, 0.95 * L),
                                kinematic_span=(0.95 * L, L))
    L0 = s["load_N"]
    if case["load"] == "spring":
        ks = min(float(rng.uniform(200.0, 2000.0)), L0 / (1.5 * A))
        plant = TendonSheath(params, SheathLoad("spring", stiffness=ks), pretension=L0, tick=1.0 / fs)
        tip_in = np.zeros_like(t)
    else:
        ks = None
        fl = float(rng.uniform(0.05, 0.4))
        tip_in = L0 * (1 + rng.uniform(0.3, 0.6) * np.sin(2 * np.pi * fl * t + rng.uniform(0, 6.3))
                       + 0.1 * np.sin(2 * np.pi * 1.7 * fl * t))
        plant = TendonSheath(params, SheathLoad("force"), pretension=float(tip_in[0]), tick=1.0 / fs)
    run = plant.run(x - x[0], tip_in)      # the motor starts at 0, where the plant's state is at rest
    xm, fm, ft, xt = run.x_motor[:, 0], run.f_motor[:, 0], run.f_tip[:, 0], run.x_tip[:, 0]
    truth = {}
    reading = fm.copy()
    temp = 24 + rng.uniform(2, 10) * np.sin(2 * np.pi * t / rng.uniform(15, 40) + rng.uniform(0, 6.3))   # degC
    if case["effect"] != "none":
        eff = get_effect(case["effect"])
        p = eff.rules.draw(rng, Scale(travel=A, load=L0, force_span=float(np.ptp(fm)), temp_span=float(np.ptp(temp)),
                                      v_fast=float(np.percentile(np.abs(np.gradient(xm, t)), 99))))
        use = {"t": t, "x": xm, "force": fm, "temperature": temp, "theta": np.full(t.shape, s["bend_rad"])}
        reading = eff.apply(Signals(**{c: a for c, a in use.items() if c == "t" or c in eff.inputs + eff.optional}), p)
        truth[case["effect"]] = p
    sf = {"motor_force": s["noise_fs"] * noise * float(np.max(np.abs(reading))),
          "tip_force": s["noise_fs"] * noise * float(np.max(np.abs(ft)))}
    sx = {e: 0.0 if s[f"{e}_encoder"] == "exact" else s["noise_fs"] * noise * float(np.ptp(xm)) for e in ("motor", "tip")}

    def encoder(a, sigma):
        return np.round((a + rng.normal(0, sigma, t.size)) / QUANTUM_M) * QUANTUM_M
    chans = {"motor_pos": encoder(xm, sx["motor"]), "tip_pos": encoder(xt, sx["tip"]),
             "motor_force": reading + rng.normal(0, sf["motor_force"], t.size),
             "tip_force": ft + rng.normal(0, sf["tip_force"], t.size),
             "bend_angle": np.full(t.shape, s["bend_rad"]), "temperature": temp + rng.normal(0, 0.02, t.size)}
    units = {"motor_pos": "m", "tip_pos": "m", "motor_force": "N", "tip_force": "N", "bend_angle": "rad",
             "temperature": "C"}
    meta = {"source": f"scenes.tendon_sheath (distributed plant), bench diagnose case {case['index']}",
            "load": "spring" if case["load"] == "spring" else "external"}
    setup = {**s, "fs_hz": fs, "spring_N_per_m": ks, "mean_tip_N": float(np.mean(ft)),
             "dead_zone_mean_m": dead_zone_uniform(float(np.mean(ft)), s["EA_N"], BENT * L, s["mu"] * s["bend_rad"]),
             "dead_zone_range_m": [dead_zone_uniform(float(q), s["EA_N"], BENT * L, s["mu"] * s["bend_rad"])
                                   for q in np.percentile(ft, [5, 95])]}
    noise_ch = {**sf, **{f"{e}_pos": math.sqrt(v ** 2 + QUANTUM_M ** 2 / 12.0) for e, v in sx.items()}}
    return {"csv": interchange_text(t, chans, units, meta), "setup": setup, "truth": truth, "noise": noise_ch,
            "trajectory": kind}


def run_distributed_case(case: dict, seed: int, duration_s: float = 20.0, noise: float = 1.0,
                         fs_hz: float | None = None, sindy: bool = False) -> dict:
    """Simulate, write, diagnose one distributed case and report what was named against the plant."""
    sim = simulate_case(case, seed, duration_s, noise, fs_hz)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"distributed_{case['index']:04d}.csv"
        path.write_text(sim["csv"], encoding="utf-8")
        rec = read_interchange(path)
        diag = diagnose(rec, sindy=sindy)
    doc = diag.as_dict()
    s = sim["setup"]
    named = {}
    for f in doc["findings"]:
        named.setdefault(f["channel"], []).append(f["effect"])
    row = {"index": case["index"], "source": "distributed", "load": case["load"], "trajectory": sim["trajectory"],
           "switched_on": list(sim["truth"]) or ["none"], "capstan_ratio": s["capstan_ratio"], "cable": s["cable"],
           "mu": s["mu"], "bend_deg": math.degrees(s["bend_rad"]), "EA_N": s["EA_N"], "length_m": s["length_m"],
           "fs_hz": s["fs_hz"], "noise_fs": s["noise_fs"], "named": named,
           "unexplained": [{"channel": u["channel"], "correlate": u["correlate"]} for u in doc["unexplained"]],
           "baseline": doc["baseline"]["effects"], "peer": peer_rows(doc, sim["noise"])}
    for res in diag.links:
        ch = res.data.link.output
        eff = dict(res.final.model.effects)
        if "capstan_friction" in eff and "mu" in eff["capstan_friction"]:
            row["capstan_mu"] = float(eff["capstan_friction"]["mu"])
            row["capstan_mu_ratio"] = row["capstan_mu"] / s["mu"]
        if ch == "tip_pos":
            play = [f for f in doc["findings"] if f["channel"] == "tip_pos" and f["effect"] == "backlash"]
            if play:
                row.update(play_against_kaneko(play[0], rec, s, case["load"]))
    tip = next((p for p in row["peer"] if p["channel"] == "tip_pos" and p.get("model_rmse") is not None), None)
    if tip is not None:
        floor = input_floor(rec, sim["noise"])
        row["tip_pos_floor_with_input_m"] = floor
        row["tip_pos_over_floor_with_input"] = tip["model_rmse"] / max(floor, 1e-300)
    row["expected_named"] = {ch: (e in named.get(ch, []) or e in doc["baseline"]["effects"].get(ch, []))
                             for ch, e in EXPECTED.items() if ch in doc["peer"]}
    if sim["truth"]:
        e = next(iter(sim["truth"]))
        row["sensor_effect_named"] = e in named.get("motor_force", [])
    return row


def input_floor(rec, noise: dict) -> float:
    """The tip position's noise floor [m] with its input's: the tip encoder's noise and the motor encoder's
    left after the diagnosis' smoothing of the drive (links.smooth_width samples averaged), in quadrature;
    an exact tip encoder's floor is its counts' alone, which a noisy motor encoder's smoothed noise can
    exceed many times over."""
    w = smooth_width(rec.channels["motor_pos"], rec.dt)
    return math.hypot(noise["tip_pos"], noise["motor_pos"] / math.sqrt(w))


def play_against_kaneko(finding: dict, rec, setup: dict, load: str) -> dict:
    """A backlash finding on tip_pos against Kaneko's dead zone: its width in motor travel [m] (`width_input`,
    else the tip's) over `dead_zone_uniform` at the mean tip tension; where its width grows with the tension,
    also its width at the 5th and 95th percentile tip tension over Kaneko's there: under a spring through
    the tip's position (`tension`; the spring law fitted on the recording gives the position of each
    tension), under an external force through the recorded tip force itself (`load_tension`); where it
    rounds its take-up, the take-up length in motor travel [m] (take_up times the half-width)."""
    p = finding["params"]
    w = float(p.get("width_input", p["width"])["value"])
    out = {"play_width_m": w, "dead_zone_mean_m": setup["dead_zone_mean_m"],
           "play_over_dead_zone": w / max(setup["dead_zone_mean_m"], 1e-300)}
    if float(p.get("take_up", {"value": 0.0})["value"]) > 0:
        out["play_take_up_m"] = 0.5 * w * float(p["take_up"]["value"])
    if "load_tension" in p and load != "spring" and "tip_force" in rec.channels:
        c, ref = float(p["load_tension"]["value"]), float(p["load"]["value"])
        q = np.percentile(rec.channels["tip_force"], [5, 95])
        wq = w * np.maximum(1.0 + c * (np.abs(q) - ref) / max(ref, 1e-300), 0.0)
        out["play_load_tension"] = c
        out["play_width_range_m"] = [float(v) for v in wq]
        out["play_over_dead_zone_range"] = [float(a / max(b, 1e-300))
                                            for a, b in zip(wq, setup["dead_zone_range_m"])]
    if "tension" in p and load == "spring" and "tip_force" in rec.channels:
        ch = rec.channels
        tension, ref = float(p["tension"]["value"]), float(p["x_ref"]["value"])
        slope, icpt = np.polyfit(ch["tip_force"], ch["tip_pos"], 1)      # the spring law, tip on tension
        q = np.percentile(ch["tip_force"], [5, 95])
        wq = w * np.maximum(1.0 + tension * (slope * q + icpt - ref), 0.0)
        out["play_tension_per_m"] = tension
        out["play_width_range_m"] = [float(v) for v in wq]
        out["play_over_dead_zone_range"] = [float(a / max(b, 1e-300))
                                            for a, b in zip(wq, setup["dead_zone_range_m"])]
    return out


def summarise_distributed(rows: list[dict]) -> dict:
    """Over distributed rows: how often each expected effect is named (or in the baseline), what is named
    per channel (counts), the sensor effects named, and per channel the held-out RMSE over the noise
    floor (median, max)."""
    def med(xs):
        return float(np.median(xs)) if xs else None
    out = {"cases": len(rows), "expected": {}, "named": {}, "model_over_noise": {}}
    for ch in EXPECTED:
        hits = [r["expected_named"][ch] for r in rows if ch in r["expected_named"]]
        out["expected"][ch] = {"effect": EXPECTED[ch], "rate": float(np.mean(hits)) if hits else None,
                               "cases": len(hits)}
    for r in rows:
        for ch, names in r["named"].items():
            for n in names:
                out["named"].setdefault(ch, {}).setdefault(n, 0)
                out["named"][ch][n] += 1
        for p in r["peer"]:
            if "model_over_noise" in p:
                out["model_over_noise"].setdefault(p["channel"], []).append(p["model_over_noise"])
    out["model_over_noise"] = {ch: {"median": med(v), "max": max(v), "cases": len(v)}
                               for ch, v in sorted(out["model_over_noise"].items())}
    sens = [r["sensor_effect_named"] for r in rows if "sensor_effect_named" in r]
    out["sensor_effect_named_rate"] = float(np.mean(sens)) if sens else None
    mus = [r["capstan_mu_ratio"] for r in rows if "capstan_mu_ratio" in r]
    out["capstan_mu_ratio_median"] = med(mus)
    floors = [r["tip_pos_over_floor_with_input"] for r in rows if "tip_pos_over_floor_with_input" in r]
    out["tip_pos_over_floor_with_input"] = {"median": med(floors), "max": max(floors)} if floors else None
    plays = [r["play_over_dead_zone"] for r in rows if "play_over_dead_zone" in r]
    out["play_over_dead_zone_median"] = med(plays)
    return out


def distributed_text(summary: dict, rows: list[dict]) -> str:
    """The distributed suite's findings as text: one line a case, then the summary."""
    lines = []
    for r in rows:
        rn = ", ".join(f"{p['channel']} {p['model_over_noise']:.2f}" for p in r["peer"] if "model_over_noise" in p)
        named = "; ".join(f"{ch}: {'+'.join(v)}" for ch, v in r["named"].items()) or "nothing"
        extra = ""
        if "capstan_mu_ratio" in r:
            extra += f", capstan mu {r['capstan_mu_ratio']:.2f}x true"
        if "play_over_dead_zone" in r:
            extra += f", play {1e3 * r['play_width_m']:.3g} mm = {r['play_over_dead_zone']:.2f}x Kaneko's dead zone"
        if "play_over_dead_zone_range" in r:
            lo, hi = r["play_over_dead_zone_range"]
            extra += f" ({lo:.2f}x, {hi:.2f}x at the 5th, 95th percentile tension)"
        if "play_take_up_m" in r:
            extra += f", taken up over {1e6 * r['play_take_up_m']:.3g} um"
        if "tip_pos_over_floor_with_input" in r:
            rn += f" (tip_pos {r['tip_pos_over_floor_with_input']:.2f}x the floor with the smoothed motor encoder's noise)"
        lines.append(f"  case {r['index']} ({r['load']}, {r['cable']}, ratio {r['capstan_ratio']:.2f}, "
                     f"{'+'.join(r['switched_on'])}): named {named}{extra}; RMSE/noise {rn}")
    for ch, e in summary["expected"].items():
        if e["rate"] is not None:
            lines.append(f"{ch}: {e['effect']} named or in the baseline in {e['rate']:.2f} of {e['cases']}")
    for ch, m in summary["model_over_noise"].items():
        lines.append(f"{ch}: held-out RMSE / noise median {m['median']:.2f}, max {m['max']:.2f}")
    f = summary.get("tip_pos_over_floor_with_input")
    if f:
        lines.append(f"tip_pos: held-out RMSE / the floor with the smoothed motor encoder's noise median "
                     f"{f['median']:.2f}, max {f['max']:.2f}")
    return "\n".join(lines)
