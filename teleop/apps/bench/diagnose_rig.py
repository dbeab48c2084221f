"""Rig cases of `teleop bench diagnose`: recordings of the simulated single-cable bench (scenes.cable_rig,
made apart from the diagnosis, sharing only the physics models) in several column subsets and loads, with
one catalogue effect, none, one outside the catalogue, or two at once; diagnosed from the CSV alone.

A case's truth is the set of its catalogue effects that the columns can show (scenes.cable_rig.observable):
an effect whose channel is not recorded must give `none`, like an effect-free or outside-the-catalogue
recording. Scored: the first finding is a true effect (compound: the first two are both), `none` when the
truth is empty, each true effect's primary parameters within 20 %, held-out improvement on its channel.
"""

from __future__ import annotations

import tempfile
from itertools import combinations
from pathlib import Path

import numpy as np

from scenes.cable_rig import OUTSIDE, observable, rig_effects, simulate
from teleop.core.physics import REGISTRY, get_effect
from teleop.core.physics.base import alike
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import RANGES
from teleop.diagnosis.scoring import detectability, peer_rows, rig_context, true_noise
from teleop.io.recording_io import read_interchange

#: column subsets of the interchange format a rig may record (name -> columns)
SUBSETS = {
    "spring, no tip position": ("motor_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C"),
    "all columns": ("motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg",
                    "temperature_C"),
    "no bend": ("motor_pos_mm", "motor_force_N", "tip_force_N", "temperature_C"),
    "no temperature": ("motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg"),
    "positions only": ("motor_pos_mm", "tip_pos_mm"),
}
PARAM_TOL = 0.2


def compounds() -> tuple:
    """Pairs of the rig's effects (registry order) with distinct signatures: not alike (Rules.alike: two
    constant-magnitude frictions on one channel, or a motor-sensor hysteresis beside one, are one effect to
    any data, loading and pulling coinciding on a spring)."""
    return tuple((a, b) for a, b in combinations(rig_effects(), 2) if not alike(a, b))


def separable_pairs() -> tuple:
    """Pairs of the rig's effects that are alike only on one sensor (Rules.alike): a sensor effect beside a
    force-link effect it is alike, which on the motor sensor under a spring is that friction's band but on
    the tip sensor reads the load before the sheath: (sensor effect, other), concealed with the sensor
    effect on the tip sensor."""
    sensor = [e for e in rig_effects() if get_effect(e).link == "sensor"]
    return tuple((a, b) for a in sensor for b in rig_effects()
                 if b != a and get_effect(b).link == "force" and alike(a, b))


def pair_plan(n: int, seed: int) -> list[dict]:
    """n rig cases of two effects at once: every pair of `compounds` and `separable_pairs` (the latter's
    sensor effect on the tip sensor), the separable pairs first, then the rest in an order shuffled from
    seed; each with a spring load, all columns or no tip position in turn."""
    rng = np.random.default_rng([seed, 4243])
    rest = list(compounds())
    order = [tuple(p) for p in separable_pairs()] + [rest[i] for i in rng.permutation(len(rest))]
    sep = set(separable_pairs())
    plan = []
    for i in range(n):
        effects = order[i % len(order)]
        case = {"index": i, "effects": effects, "subset": "spring, no tip position" if i % 2 else "all columns",
                "load": "spring"}
        if effects in sep:
            case["given"] = {"sensor_channel": "tip_force"}
        plan.append(case)
    return plan


def rig_plan(n: int, seed: int) -> list[dict]:
    """n rig cases: every (effect or none or outside) in turn over the column subsets and loads, and every
    third case a compound of two effects; reproducible from seed."""
    pairs = compounds()
    rng = np.random.default_rng([seed, 4242])
    singles = ["none"] + list(rig_effects()) + list(OUTSIDE)
    subsets = list(SUBSETS)
    plan = []
    for i in range(n):
        subset = subsets[i % len(subsets)]
        load = "spring" if (i // len(subsets)) % 3 != 2 else "external"
        if i % 3 == 2:
            effects = pairs[int(rng.integers(len(pairs)))]
            subset = "spring, no tip position" if i % 2 else "all columns"
            load = "spring"
        else:
            effects = (singles[(i // 3 * 2 + i % 3) % len(singles)],)
        plan.append({"index": i, "effects": effects, "subset": subset, "load": load})
    return plan


def run_rig_case(case: dict, seed: int, fs_hz: float | None = 500.0, duration_s: float = 20.0,
                 noise: float = 1.0, sindy: bool = False, ranges: str = "project") -> dict:
    """Simulate, write, diagnose and score one rig case (sindy: with the PySINDy peer on every channel;
    ranges: the rig's set-up ranges, a key of teleop.diagnosis.generator.RANGES; fs_hz None: drawn)."""
    cols = SUBSETS[case["subset"]]
    rig = simulate([seed, case["index"], 7], case["effects"], cols, case["load"], fs_hz, duration_s, noise,
                   given=case.get("given"), ranges=RANGES[ranges])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"rig_{case['index']:04d}.csv"
        rig.write(path)
        doc = diagnose(read_interchange(path), sindy=sindy).as_dict()
    truth, shown = {}, {}
    for e, v in rig.effects.items():
        if not observable(e, cols, case["load"]):
            continue
        # rig physics the catalogue knows under its own name (Rules.also_known_as: a late sensor)
        name = e if e in REGISTRY else next((n for n, x in REGISTRY.items() if e in x.rules.also_known_as), None)
        if name is not None:
            truth[name] = v
            shown[e] = v
    findings = doc["findings"]
    named = [f["effect"] for f in findings]
    if not truth:
        correct = not named
    elif len(truth) == 1:
        correct = bool(named) and named[0] in truth
    else:
        correct = set(named[: len(truth)]) == set(truth)
    row = {"index": case["index"], "source": "rig", **rig_context(cols, case["load"], rig.setup),
           "subset": case["subset"], "trajectory": rig.trajectory, "switched_on": list(case["effects"]),
           "truth": sorted(truth) or ["none"], "named": named[0] if named else "none", "all_named": named,
           "correct": correct, "unexplained": [u["correlate"] for u in doc["unexplained"]],
           "peer": peer_rows(doc, true_noise(rig.setup))}
    if truth:
        errs, imps = {}, {}
        for e, v in truth.items():
            hit = [f for f in findings if f["effect"] == e]
            for p in get_effect(e).rules.primary:
                if hit:
                    errs[f"{e}.{p}"] = abs(hit[0]["params"][p]["value"] - v["params"][p]) / abs(v["params"][p])
            # the channel it was found on (a play shows on the tip position where it is recorded, else
            # on the tip force through the spring), else the channel it acts on
            ch = hit[0]["channel"] if hit else (v["channel"] if v["channel"] in doc["baseline"]["rmse"] else None)
            if ch is not None:
                imps[e] = doc["baseline"]["rmse"][ch] / max(doc["channels"][ch]["rmse_model"], 1e-300)
        row["param_errors"] = errs
        row["params_ok"] = bool(errs) and max(errs.values()) <= PARAM_TOL and len(errs) == sum(
            len(get_effect(e).rules.primary) for e in truth)
        row["improvement"] = min(imps.values()) if imps else 1.0
        row["improved_2x"] = row["improvement"] >= 2.0
        row.update(detectability(shown, rig.contributions, true_noise(rig.setup)))
    return row


def rates(rows: list[dict]) -> dict:
    """The bench's rates over scored rows of either source (a generator row's truth is a name, a rig row's
    a list of names; "none" or ["none"] for an effect-free case)."""
    eff = [r for r in rows if r["truth"] not in ("none", ["none"])]
    clean = [r for r in rows if r["truth"] in ("none", ["none"])]

    def rate(xs):
        return float(np.mean(xs)) if xs else None
    # an effect about the size of the noise: no model could show 2x (scoring.detectability), counted apart
    able = [r for r in eff if not r.get("below_detectability")]
    return {"cases": len(rows), "effect_cases": len(eff), "clean_cases": len(clean),
            "named_first_rate": rate([r["correct"] for r in eff]),
            "none_rate": rate([r["correct"] for r in clean]),
            "params_within_20pct_rate": rate([bool(r["params_ok"]) for r in eff]),
            "improved_2x_rate": rate([bool(r["improved_2x"]) for r in eff]),
            "improvement_min": min((r["improvement"] for r in eff), default=None),
            "below_detectability": len(eff) - len(able),
            "improved_2x_rate_detectable": rate([bool(r["improved_2x"]) for r in able])}


def summarise_rig(rows: list[dict]) -> dict:
    """Rates over rig rows, overall and per column subset (compounds apart), and each subset's confusion
    matrix (true effects -> first named)."""
    groups: dict = {}
    for r in rows:
        key = "compound (two effects)" if len(r["switched_on"]) > 1 else f"{r['subset']} ({r['load']})"
        groups.setdefault(key, []).append(r)
    out = {"all": rates(rows), "by_subset": {}}
    for key, rs in sorted(groups.items()):
        conf: dict = {}
        for r in rs:
            t = "+".join(r["truth"])
            conf.setdefault(t, {})
            conf[t][r["named"]] = conf[t].get(r["named"], 0) + 1
        out["by_subset"][key] = {**rates(rs), "confusion": conf}
    return out


def rig_text(summary: dict) -> str:
    """Per-subset rates and confusion rows as text."""
    lines = []
    for key, s in summary["by_subset"].items():
        def f(v):
            return "-" if v is None else f"{v:.2f}"
        lines.append(f"{key}: {s['cases']} cases, named first {f(s['named_first_rate'])}, none "
                     f"{f(s['none_rate'])}, params {f(s['params_within_20pct_rate'])}, 2x {f(s['improved_2x_rate'])}")
        for t, row in sorted(s["confusion"].items()):
            lines.append(f"    {t:<40} -> " + ", ".join(f"{n} {c}" for n, c in sorted(row.items())))
    return "\n".join(lines)
