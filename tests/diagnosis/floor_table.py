"""The baseline's floor table (issue 26 d1): held-out RMSE of the force link's baseline / the true noise on
recordings of the test-side generator (tests.diagnosis._independent), per encoder and load source, and the
distributed plant's (`plant_case`). Run:

    python -m tests.diagnosis.floor_table --seed 0 [--plant] [--bound] [--out table.json]

Rows: exact / noisy encoder x instant / pre-sliding switch x tip sensor / spring law, over capstan ratios
1.0-5.0 and the three drives; each cell the min-max of the ratio and the CPU seconds of its baseline fits.
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from teleop.core.physics.links import is_exact, predict
from teleop.diagnosis.diagnose import PROJECT_BASELINE, exact_rate, split
from teleop.diagnosis.identify import rms, simulation_baseline
from teleop.diagnosis.links import find_links, link_data
from teleop.io.recording_io import read_interchange
from tests.diagnosis._independent import Case, drive, make, plant_case, write_csv

RATIOS = (1.0, 1.5, 2.5, 3.5, 5.0)
DRIVES = ("sine", "sines", "triangle")
ENC_NOISE = 2e-6     # noisy encoder: 2 um Gaussian, counts of 1 um


def floor_ratio(made, path) -> tuple[float, object]:
    """(held-out RMSE / true noise, the baseline Fit) of made's force link, read back from its CSV."""
    rec = read_interchange(write_csv(made, path))
    fit_idx, hold_idx = split(rec.n, 0.4)
    link = next(L for L in find_links(rec) if L.kind == "force")
    d = link_data(rec, link)
    if d.v is None and is_exact(d.x):   # as diagnose: an exact drive's rate convention
        d = exact_rate(d, fit_idx, hold_idx, PROJECT_BASELINE, 0)
    base = simulation_baseline(d, fit_idx, hold_idx, PROJECT_BASELINE, 0)
    assert abs(rms((predict(d, base.model) - d.y)[hold_idx]) - base.rmse_hold) <= 1e-9 * max(base.rmse_hold, 1e-12)
    return base.rmse_hold / made.noise_N, base


def turn_bound(case: Case, made) -> float:
    """A lower bound on the held-out RMSE / true noise of an instant switch driven by a noisy encoder: each
    turn's time known no better than the Cramer-Rao bound of the encoder's samples with the drive's shape known
    exactly (information sum v^2 / sigma^2 over the samples nearer that turn than its neighbours; sigma the
    encoder's Gaussian noise and its count rounding), each sample put on the wrong side of a turn costing the
    whole band there (a turn located to sd puts sqrt(2 / pi) sd / dt samples on the wrong side on average)."""
    t = made.t
    dt = float(t[1] - t[0])
    sigma = math.hypot(case.enc_noise, case.enc_noise / 2 / math.sqrt(12.0))
    tf = np.arange(t[0], t[-1], dt / 1000.0)
    vf = drive(case, tf)[1]
    k = np.flatnonzero(np.sign(vf[1:]) * np.sign(vf[:-1]) < 0)
    turns = tf[k]
    v = drive(case, t)[1]
    T_tip = made.truth["tip_force"]
    excess = 0.0
    for j, tt in enumerate(turns):
        a = 0.5 * (tt + (turns[j - 1] if j else t[0]))
        b = 0.5 * (tt + (turns[j + 1] if j + 1 < turns.size else t[-1]))
        sel = (t > a) & (t < b)
        sd = 1.0 / math.sqrt(float(np.sum(v[sel] ** 2)) / sigma ** 2)
        band = float(T_tip[min(int(round(tt / dt)), t.size - 1)]) * (case.ratio - 1.0 / case.ratio)
        excess += math.sqrt(2.0 / math.pi) * sd / dt * band ** 2
    return math.sqrt(1.0 + excess / t.size / made.noise_N ** 2)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--plant", action="store_true", help="also the distributed plant (slow)")
    ap.add_argument("--rows", default="", help="semicolon list of row name parts to run (default all)")
    ap.add_argument("--bound", action="store_true", help="with each noisy instant case, the Cramer-Rao bound of "
                    "its turns' timing (turn_bound)")
    ap.add_argument("--out", default=None)
    ap.add_argument("--tmp", default="/tmp/floor_table.csv")
    a = ap.parse_args(argv)
    rows = {}
    for enc in ("exact", "noisy"):
        for switch in ("instant", "pre-sliding"):
            for tip in (True, False):
                rows[f"{enc}, {switch}, {'tip sensor' if tip else 'spring law'}"] = (enc, switch, tip)
    want = [r.strip() for r in a.rows.split(";") if r.strip()]
    out = {}
    for name, (enc, switch, tip) in rows.items():
        if want and not any(w in name for w in want):
            continue
        vals, cpu = [], []
        for i, ratio in enumerate(RATIOS):
            for j, drv in enumerate(DRIVES):
                case = Case(ratio=ratio, drive=drv, stick_k=8e4 if switch == "pre-sliding" else None,
                            enc_noise=ENC_NOISE if enc == "noisy" else 0.0, tip=tip, seconds=10.0, freq=1.0,
                            seed=a.seed * 100 + 10 * i + j)
                made = make(case)
                c0 = time.process_time()
                r, base = floor_ratio(made, a.tmp)
                cpu.append(time.process_time() - c0)
                vals.append(r)
                bound = (f" (bound {turn_bound(case, made):.2f})" if a.bound and enc == "noisy" and switch == "instant"
                         else "")
                print(f"  {name:32s} ratio {ratio:.1f} {drv:8s} {r:6.2f}{bound}  {dict(base.model.effects)}",
                      flush=True)
        out[name] = {"min": min(vals), "max": max(vals), "median": float(np.median(vals)), "cpu_s": max(cpu)}
        print(f"{name:32s} {min(vals):.2f}-{max(vals):.2f} (median {np.median(vals):.2f})", flush=True)
    if a.plant:
        vals = []
        for ratio in (1.5, 2.5, 4.0):
            for tip in (True, False):
                r, base = floor_ratio(plant_case(ratio=ratio, tip=tip, seed=a.seed), a.tmp)
                vals.append(r)
                print(f"  plant ratio {ratio} tip {tip}: {r:.2f} {dict(base.model.effects)}", flush=True)
        out["distributed plant"] = {"min": min(vals), "max": max(vals), "median": float(np.median(vals))}
        print(f"distributed plant {min(vals):.2f}-{max(vals):.2f}", flush=True)
    if a.out:
        with open(a.out, "w", encoding="utf-8") as fh:
            json.dump(out, fh, indent=1)
    return out


if __name__ == "__main__":
    main()
