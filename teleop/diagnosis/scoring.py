"""Score diagnoses of generated cases: named-first accuracy, `none` rate, parameter error, improvement,
and the confusion matrix (true effect -> first named effect)."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from scenes.cable_rig import COLUMNS
from teleop.diagnosis.diagnose import HOLDOUT, diagnose, split
from teleop.diagnosis.generator import Case, case_effects, primary
from teleop.io.recording_io import read_interchange

PARAM_TOL = 0.2


#: a channel's quantisation step in the rig's CSV [m] (positions written to 1 um)
QUANTUM_M = 1e-6
#: held-out RMSE [SI] at or below which a fit is exact to round-off (a tip encoder reading the motor's exact
#: travel): physics and peer tie there, whatever their ratio
ROUND_OFF = 1e-12


def run_case(case: Case, workdir: str | Path | None = None, sindy: bool = False) -> dict:
    """Write the case as CSV, diagnose the CSV, and score the report against the truth (sindy: with the
    PySINDy peer on every channel the diagnosis fits, `peer_rows`)."""
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        path = Path(tmp) / f"case_{case.index:04d}.csv"
        case.write(path)
        doc = diagnose(read_interchange(path), sindy=sindy).as_dict()
    row = score(case, doc)
    if case.rig:
        row.update(rig_context(case.columns, case.load, case.rig))
        if case.effect != "none":
            row.update(detectability({case.effect: {"channel": case.channel}}, case.contributions,
                                     true_noise(case.rig)))
    row["peer"] = peer_rows(doc, true_noise(case.rig) if case.rig else {})
    return row


def true_noise(setup: dict) -> dict:
    """{channel: the noise the rig added [SI]} from a cable-rig recording's setup (scenes.cable_rig
    RigRecording.setup): the force sensors' noise, the encoders' noise with their 1 um quantisation."""
    out = {c: float(v) for c, v in setup.get("noise_N", {}).items()}
    for enc, s in setup.get("noise_m", {}).items():
        out[f"{enc}_pos"] = math.sqrt(float(s) ** 2 + QUANTUM_M ** 2 / 12.0)
    return out


#: the held-out improvement a case is scored on (>= 2x)
IMPROVEMENT = 2.0


def ceiling(contribution: dict | None, noise: float, holdout: float = HOLDOUT) -> float | None:
    """The largest held-out improvement on its channel that any model can show for an effect (scenes.cable_rig
    RigRecording.contributions: its noise-free change of the channel and the channel without it, (n,) each),
    against the channel's true noise `noise`: sqrt(1 + (c / noise)^2), c the RMS over the held-out part of
    what no baseline gain and offset can take of the change (its residual on a constant and the channel
    without it, fitted by least squares on the fit part as a baseline is). A perfect model leaves the noise;
    a baseline that took all it could leaves the noise and c. None without a contribution or noise."""
    if not contribution or not noise > 0:
        return None
    fit, hold = split(contribution["change"].size, holdout)
    change, clean = contribution["change"], contribution["clean"]
    A = np.column_stack([np.ones(change.size), clean])
    coef, *_ = np.linalg.lstsq(A[fit], change[fit], rcond=None)
    c = float(np.sqrt(np.mean(np.square((change - A @ coef)[hold]))))
    return math.sqrt(1.0 + (c / noise) ** 2)


def detectability(truth: dict, contributions: dict, noise: dict) -> dict:
    """{"ceiling": the least over the true effects of the improvement any model could show on each one's
    channel (`ceiling`), "below_detectability": True where that is under IMPROVEMENT (no method reaches
    2x there: the effect is about the size of the noise)}; {} where no effect has a contribution."""
    cs = [ceiling(contributions.get(e), noise.get(v["channel"], 0.0)) for e, v in truth.items()]
    cs = [c for c in cs if c is not None]
    if not cs:
        return {}
    return {"ceiling": min(cs), "below_detectability": min(cs) < IMPROVEMENT}


def rig_context(columns, load: str, setup: dict) -> dict:
    """The row keys of a rig recording's set-up: "columns", "subset" (which optional sensors are missing),
    "load", "capstan_ratio", "cable" and "fs_hz" (where the set-up has them)."""
    missing = [c for c in COLUMNS if c not in columns]
    return {"columns": list(columns), "subset": "all columns" if not missing else "no " + ", ".join(missing),
            "load": load, "capstan_ratio": setup.get("capstan_ratio"), "cable": setup.get("cable"),
            "fs_hz": setup.get("fs_hz")}


def peer_rows(doc: dict, noise: dict | None = None) -> list[dict]:
    """Per channel the diagnosis fits (doc["peer"]): the physics model's held-out RMSE beside the ARX peer's
    and the PySINDy peer's static, free-run and better fit (None where --sindy was not asked or the fit
    failed), "ratio" = model / PySINDy's better fit and "worse" = ratio > 1.0 (not where the physics' fit is
    exact to round-off, ROUND_OFF); with `noise` ({channel: the
    true noise}), "noise" and "model_over_noise"."""
    out = []
    for ch, p in doc["peer"].items():
        best = p.get("sindy_rmse")
        ratio = p["model_rmse"] / max(best, 1e-300) if best is not None else None
        row = {"channel": ch, "model_rmse": p["model_rmse"], "baseline_rmse": p.get("baseline_rmse"),
               "arx_rmse": p["arx_rmse"], "sindy_static_rmse": p.get("sindy_static_rmse"),
               "sindy_free_run_rmse": p.get("sindy_free_run_rmse"), "sindy_rmse": best, "ratio": ratio,
               "worse": ratio is not None and ratio > 1.0 and p["model_rmse"] > ROUND_OFF}
        if noise and ch in noise and noise[ch] > 0:
            row["noise"] = noise[ch]
            row["model_over_noise"] = p["model_rmse"] / noise[ch]
        out.append(row)
    return out


def score(case: Case, doc: dict) -> dict:
    """{"index", "truth", "named", "all_named", "correct", "param_errors", "params_ok", "improvement",
    "improved_2x", "unexplained"} for one case's report."""
    findings = doc["findings"]
    named = findings[0]["effect"] if findings else "none"
    out = {"index": case.index, "truth": case.effect, "setup": case.setup, "trajectory": case.trajectory,
           "named": named, "all_named": [f["effect"] for f in findings],
           "correct": named == case.effect,
           "unexplained": [u["correlate"] for u in doc["unexplained"]],
           "first": ({"effect": named, "rmse_after": findings[0]["rmse_after"],
                      "alternatives": findings[0]["alternatives"]} if findings else None)}
    if case.effect != "none":
        hit = [f for f in findings if f["effect"] == case.effect]
        errs = {}
        if hit:
            for p in primary()[case.effect]:
                true = case.params[p]
                errs[p] = abs(hit[0]["params"][p]["value"] - true) / abs(true)
        out["param_errors"] = errs
        out["params_ok"] = bool(errs) and max(errs.values()) <= PARAM_TOL
        # the channel it was found on (a play under a spring shows on the tip position where that is
        # recorded, else on the tip force), else the one it acts on where the diagnosis fits it
        ch = hit[0]["channel"] if hit else case.channel
        if ch in doc["baseline"]["rmse"]:
            out["improvement"] = doc["baseline"]["rmse"][ch] / max(doc["channels"][ch]["rmse_model"], 1e-300)
        else:
            out["improvement"] = 1.0
        out["improved_2x"] = out["improvement"] >= IMPROVEMENT
    return out


def summarise(rows: list[dict]) -> dict:
    """Rates and the confusion matrix over scored cases."""
    eff = [r for r in rows if r["truth"] != "none"]
    clean = [r for r in rows if r["truth"] == "none"]
    labels = list(case_effects()) + ["none"]
    named_labels = sorted({r["named"] for r in rows} | set(labels), key=lambda s: (s not in labels,
                          labels.index(s) if s in labels else 0, s))
    confusion = {t: {n: 0 for n in named_labels} for t in labels}
    for r in rows:
        confusion[r["truth"]][r["named"]] += 1

    def rate(xs):
        return float(np.mean(xs)) if xs else None

    return {
        "cases": len(rows),
        "effect_cases": len(eff),
        "clean_cases": len(clean),
        "named_first_rate": rate([r["correct"] for r in eff]),
        "none_rate": rate([r["correct"] for r in clean]),
        "params_within_20pct_rate": rate([r["params_ok"] for r in eff]),
        "improved_2x_rate": rate([r["improved_2x"] for r in eff]),
        "improvement_min": min((r["improvement"] for r in eff), default=None),
        "confusion": confusion,
    }


def confusion_text(summary: dict) -> str:
    """The confusion matrix as aligned text (rows: truth, columns: first named effect)."""
    conf = summary["confusion"]
    cols = [c for c in next(iter(conf.values())) if any(conf[t][c] for t in conf)]
    short = {c: c.replace("_friction", "").replace("_hysteresis", "_h").replace("_contact", "")[:10] for c in cols}
    w = max(len(t) for t in conf) + 1
    lines = [" " * w + " ".join(f"{short[c]:>10}" for c in cols)]
    for t, row in conf.items():
        lines.append(f"{t:<{w}}" + " ".join(f"{row[c]:>10d}" for c in cols))
    return "\n".join(lines)
