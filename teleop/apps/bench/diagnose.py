"""`teleop bench diagnose --cases N --seed S [--json F]`: concealed-effect recordings from the generator,
diagnosed from their CSV alone; prints the confusion matrix and the rates of issue 6, and the rates per
column subset and capstan-ratio band. With --speed, also times the diagnosis of a 40 s, 1 kHz recording.

Suites: the concealed-effect generator, the single-cable bench's column subsets and compounds (rig), the
distributed tendon-sheath plant (distributed: teleop.apps.bench.diagnose_distributed), or all of them; pairs:
the rig with two effects in every case (diagnose_rig.pair_plan). An effect case whose effect is about the size
of the noise says so ("below detectability": no model could show 2x, scoring.detectability, from the truth);
--ranges literature (default) draws the rigs' set-ups over the literature's ranges (scenes.cable_rig
LITERATURE), project over the rig's own. --sindy: per channel, the physics' held-out RMSE beside PySINDy's
static and free-run fits on the same split, and the channels where the physics is worse (ratio > 1.0).
--recordings: real recordings (any layout with --map), the peer comparison alone (no truth to score).
--scheduler (as for `teleop campaign`): each case, or each recording, runs where the scheduler runs tasks; the
report does not depend on where.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from teleop.apps.bench.diagnose_distributed import (distributed_plan, distributed_text, run_distributed_case,
                                                    summarise_distributed)
from teleop.apps.argtypes import input_file
from teleop.apps.bench.diagnose_rig import pair_plan, rates, rig_plan, rig_text, run_rig_case, summarise_rig
from teleop.apps.campaign.recordings import diagnose_files
from teleop.apps.campaign.scheduler import open_scheduler
from teleop.apps.commands.campaign import add_scheduler_option
from teleop.core.errors import InputError
from teleop.diagnosis.diagnose import HOLDOUT, diagnose
from teleop.diagnosis.generator import RANGES, GenConfig, case_plan, make_case
from teleop.diagnosis.scoring import confusion_text, peer_rows, run_case, summarise
from teleop.io.outputs import write_json
from teleop.io.progress import progress
from teleop.io.recording_io import read_interchange, read_recording

#: capstan-ratio bands the figures are given per (lower edges; the last open)
BANDS = (1.0, 1.5, 2.5, 4.0)


def register(subparsers) -> None:
    p = subparsers.add_parser("diagnose", help="diagnosis accuracy on generated concealed-effect recordings")
    p.add_argument("--cases", type=int, default=100, help="number of generated recordings (100)")
    p.add_argument("--seed", type=int, default=0, help="generator seed (0)")
    p.add_argument("--json", metavar="PATH", help="write per-case rows and the summary as JSON")
    p.add_argument("--speed", action="store_true", help="also time a 40 s, 1 kHz recording")
    p.add_argument("--rate", type=float, default=None,
                   help="sampling rate of the cases [Hz] (default: drawn 200-2000 Hz with --ranges literature, "
                        "500 with project)")
    p.add_argument("--seconds", type=float, default=20.0, help="duration of each case [s] (20)")
    p.add_argument("--noise", type=float, default=1.0, help="factor on every sensor noise level (1)")
    p.add_argument("--sindy", action="store_true",
                   help="also fit the PySINDy peer on every channel: the physics' held-out RMSE beside PySINDy's "
                        "static and free-run fits, and the channels where the physics is worse")
    p.add_argument("--suite", choices=("all", "generator", "rig", "distributed", "pairs"), default="all",
                   help="cases from the concealed-effect generator, the simulated single-cable bench "
                        "(column subsets, loads, compounds; scenes.cable_rig), the distributed tendon-sheath "
                        "plant (scenes.tendon_sheath), all: half generator, an eighth distributed, the rest rig; "
                        "or pairs: the bench with two effects at once in every case (a sensor effect beside a "
                        "friction it is alike on the motor sensor sits on the tip sensor)")
    p.add_argument("--ranges", choices=tuple(RANGES), default="literature",
                   help="the rigs' set-up ranges: literature (mu 0.05-0.25, bends to 540 deg, capstan ratio to 5, "
                        "steel and polymer cables, noise 0.2-3 %% of full scale, 0.05-5 Hz drives, 200-2000 Hz, "
                        "exact and noisy encoders, sensors present or absent; default) or project (the rig's own)")
    p.add_argument("--recordings", nargs="+", metavar="REC", type=input_file,
                   help="instead of generated cases: real recordings, diagnosed with the PySINDy peer; prints "
                        "the per-channel comparison")
    p.add_argument("--map", metavar="MAP", help="column map of --recordings (a .toml path or a shipped name)")
    add_scheduler_option(p)  # each generated case simulated, diagnosed and scored where the scheduler runs tasks
    p.set_defaults(func=run)


def bench_case(item: tuple) -> dict:
    """One generated case's scored row: item = (suite, index in its plan, plan entry, (seed, GenConfig, rate,
    seconds, noise, sindy, ranges)); a module-level function so that a Dask worker can run it."""
    suite, i, entry, (seed, cfg, rate, seconds, noise, sindy, ranges) = item
    if suite == "generator":
        effect, setup = entry
        return run_case(make_case(i, effect, setup, seed, cfg), sindy=sindy)
    if suite == "rig":
        return run_rig_case(entry, seed, rate, seconds, noise, sindy, ranges)
    return run_distributed_case(entry, seed, seconds, noise, rate, sindy)


def speed_case(seed: int = 0):
    """A 40 s, 1 kHz rig recording with Dahl friction (for the timing benchmark)."""
    return make_case(999, "dahl_hysteresis", "rig", seed, GenConfig(fs_hz=1000.0, duration_s=40.0))


def _band(ratio) -> str:
    """The capstan-ratio band of `ratio` ("1.0-1.5", ..., "4.0+"), or "n/a"."""
    if ratio is None:
        return "n/a"
    lo = [b for b in BANDS if ratio >= b - 1e-12]
    if not lo:
        return f"<{BANDS[0]}"
    i = BANDS.index(lo[-1])
    return f"{BANDS[i]:.1f}-{BANDS[i + 1]:.1f}" if i + 1 < len(BANDS) else f"{BANDS[i]:.1f}+"


def grouped(rows: list[dict], key) -> dict:
    """{group: rates} of scored rows grouped by key(row) (rows where it gives None are left out)."""
    groups: dict = {}
    for r in rows:
        k = key(r)
        if k is not None:
            groups.setdefault(k, []).append(r)
    return {k: rates(v) for k, v in sorted(groups.items())}


def peer_summary(items: list[tuple[str, dict]]) -> dict:
    """Over (case label, peer row) pairs: per channel the cases, the ratio physics / PySINDy (median,
    max), the physics' and PySINDy's held-out RMSE medians, and the count where physics is worse;
    "worse": every (case, channel) with ratio > 1.0; "model_le_sindy": "k/n" channels where physics <= PySINDy."""
    by: dict = {}
    worse = []
    fitted = [(lab, p) for lab, p in items if p.get("ratio") is not None]
    for lab, p in fitted:
        by.setdefault(p["channel"], []).append(p)
        if p["worse"]:
            worse.append({"case": lab, "channel": p["channel"], "model_rmse": p["model_rmse"],
                          "sindy_static_rmse": p["sindy_static_rmse"], "sindy_free_run_rmse": p["sindy_free_run_rmse"],
                          "ratio": p["ratio"]})
    out = {}
    for ch, ps in sorted(by.items()):
        r = [p["ratio"] for p in ps]
        out[ch] = {"cases": len(ps), "ratio_median": float(np.median(r)), "ratio_max": float(max(r)),
                   "model_rmse_median": float(np.median([p["model_rmse"] for p in ps])),
                   "sindy_static_rmse_median": float(np.median([p["sindy_static_rmse"] for p in ps])),
                   "worse": sum(p["worse"] for p in ps)}
        mon = [p["model_over_noise"] for p in ps if "model_over_noise" in p]
        if mon:
            out[ch]["model_over_noise_median"] = float(np.median(mon))
    return {"by_channel": out, "worse": worse,
            "model_le_sindy": f"{len(fitted) - len(worse)}/{len(fitted)}"}


def _detect_text(row: dict) -> str:
    """', improvement I; a perfect model: at most C (below detectability)' for a scored effect row."""
    if "improvement" not in row:
        return ""
    out = f", improvement {row['improvement']:.2f}"
    if row.get("ceiling") is not None:
        out += f"; a perfect model: at most {row['ceiling']:.2f}"
        out += " (below detectability)" if row["below_detectability"] else ""
    return out


def _num(v, fmt=".4g") -> str:
    return "-" if v is None else format(v, fmt)


def peer_text(summary: dict) -> str:
    """The per-channel table of peer_summary and the list of channels where physics is worse."""
    lines = [f"{'channel':<12} {'cases':>5} {'physics':>10} {'SINDy stat':>10} {'ratio med':>9} {'ratio max':>9} "
             f"{'worse':>5} {'RMSE/noise':>10}"]
    for ch, c in summary["by_channel"].items():
        lines.append(f"{ch:<12} {c['cases']:>5d} {c['model_rmse_median']:>10.4g} {c['sindy_static_rmse_median']:>10.4g} "
                     f"{c['ratio_median']:>9.3f} {c['ratio_max']:>9.3f} {c['worse']:>5d} "
                     f"{_num(c.get('model_over_noise_median'), '.3g'):>10}")
    for w in summary["worse"]:
        lines.append(f"physics worse than PySINDy: {w['case']} {w['channel']}: physics {w['model_rmse']:.4g}, "
                     f"PySINDy static {_num(w['sindy_static_rmse'])}, free run {_num(w['sindy_free_run_rmse'])} "
                     f"(ratio {w['ratio']:.3f})")
    if not summary["worse"]:
        lines.append("physics worse than PySINDy: none")
    return "\n".join(lines)


def run_recordings(args) -> int:
    """--recordings: each diagnosed with the PySINDy peer; per recording and channel the physics' held-out
    RMSE beside the peers'."""
    out_rows, items = [], []
    recs = [read_recording(path, args.map) for path in args.recordings]   # every one read before any work
    remote = None  # with a scheduler: each file read again and diagnosed on its workers (their progress shown)
    if args.scheduler != "none":
        remote = diagnose_files(args.recordings, args.map, HOLDOUT, args.scheduler, seed=args.seed, sindy=True)
    with progress(len(args.recordings), "bench diagnose", unit="recordings") as bar:
        for k, (path, rec) in enumerate(zip(args.recordings, recs)):
            doc = (remote[k] if remote else diagnose(rec, seed=args.seed, sindy=True)).as_dict()
            rows = peer_rows(doc)
            out_rows.append({"recording": str(path), "peer": rows,
                             "findings": [{"channel": f["channel"], "effect": f["effect"]} for f in doc["findings"]]})
            items += [(Path(path).name, p) for p in rows]
            bar.update()
    print(f"{'recording':<22} {'channel':<12} {'physics':>10} {'SINDy stat':>10} {'SINDy free':>10} {'ARX':>10} {'ratio':>7}")
    for r in out_rows:
        for p in r["peer"]:
            print(f"{Path(r['recording']).name:<22} {p['channel']:<12} {p['model_rmse']:>10.4g} "
                  f"{_num(p['sindy_static_rmse']):>10} {_num(p['sindy_free_run_rmse']):>10} {p['arx_rmse']:>10.4g} "
                  f"{_num(p['ratio'], '.3f'):>7}")
    summary = peer_summary(items)
    print(peer_text(summary))
    if args.json:
        write_json(args.json, {"recordings": out_rows, "map": args.map, "seed": args.seed, "peer": summary})
    return 0


def run(args) -> int:
    if args.recordings:
        return run_recordings(args)
    if args.map:
        raise InputError("--map belongs to --recordings")
    if args.cases < 1:
        raise InputError("--cases must be >= 1")
    if args.rate is None and args.ranges == "project":
        args.rate = 500.0
    if not ((args.rate is None or 50 <= args.rate <= 20000) and 5 <= args.seconds <= 600 and 0 <= args.noise <= 20):
        raise InputError("--rate must be 50..20000 Hz, --seconds 5..600, --noise 0..20")
    cfg = GenConfig(args.rate, args.seconds, args.noise, args.ranges)

    n_gen = {"all": args.cases // 2, "generator": args.cases}.get(args.suite, 0)
    n_dist = {"all": args.cases // 8, "distributed": args.cases}.get(args.suite, 0)
    plans = {"generator": case_plan(n_gen),
             "rig": (pair_plan if args.suite == "pairs" else rig_plan)(args.cases - n_gen - n_dist, args.seed),
             "distributed": distributed_plan(n_dist)}
    opts = (args.seed, cfg, args.rate, args.seconds, args.noise, args.sindy, args.ranges)
    items = [(suite, i, entry, opts) for suite, plan in plans.items() for i, entry in enumerate(plan)]
    done = {}
    with open_scheduler(args.scheduler) as sched, progress(len(items), "bench diagnose", unit="cases") as bar:
        for item, outcome in sched.run(bench_case, items):
            if not outcome.ok:  # a bug, not the user's input: the worker's traceback with it
                raise RuntimeError(f"{item[0]} case {item[1]} failed: {outcome.error}\n{outcome.traceback}")
            done[item[:2]] = outcome.value
            bar.update()
    rows, rig_rows, dist_rows = ([done[suite, i] for i in range(len(plans[suite]))]
                                 for suite in ("generator", "rig", "distributed"))
    summary = summarise(rows) if rows else {}
    rig_summary = summarise_rig(rig_rows) if rig_rows else {}
    scored = rows + rig_rows
    combined = rates(scored) if scored else {}
    out = {"cases": args.cases, "seed": args.seed, "suite": args.suite, "ranges": args.ranges,
           "rate_hz": args.rate, "seconds": args.seconds, "noise": args.noise, "summary": combined}
    if rows:
        out.update({"generator": summary, "rows": rows})
    out.update({"rig": rig_summary, "rig_rows": rig_rows})
    if dist_rows:
        out["distributed"] = summarise_distributed(dist_rows)
        out["distributed_rows"] = dist_rows
    rig_like = [r for r in scored if r.get("capstan_ratio") is not None]
    out["by_subset"] = grouped(rig_like, lambda r: r.get("subset"))
    out["by_capstan_band"] = grouped(rig_like, lambda r: _band(r.get("capstan_ratio")))
    if args.sindy:
        items = ([(f"case {r['index']}", p) for r in rows for p in r["peer"]]
                 + [(f"rig case {r['index']}", p) for r in rig_rows for p in r["peer"]]
                 + [(f"distributed case {r['index']}", p) for r in dist_rows for p in r["peer"]])
        out["peer"] = peer_summary(items)
        if combined:
            combined["model_le_sindy"] = out["peer"]["model_le_sindy"]
    if rows:
        print("concealed-effect generator (teleop.diagnosis.generator):")
        print(confusion_text(summary))
        for key in ("cases", "effect_cases", "clean_cases", "named_first_rate", "none_rate",
                    "params_within_20pct_rate", "improved_2x_rate", "improvement_min"):
            v = summary[key]
            print(f"{key}: {v:.4g}" if isinstance(v, float) else f"{key}: {v}")
        for r in rows:
            if not r["correct"] or r.get("improved_2x") is False:
                print(f"{'miss' if not r['correct'] else 'under 2x'}: case {r['index']} ({r['setup']}, "
                      f"{r.get('subset', 'all columns')}, {r['trajectory']}): {r['truth']} -> "
                      f"{r['all_named'] or ['none']}{_detect_text(r)}")
    if rig_rows:
        print("simulated single-cable bench (scenes.cable_rig):")
        print(rig_text(rig_summary))
        for r in rig_rows:
            if not r["correct"] or r.get("improved_2x") is False:
                print(f"{'miss' if not r['correct'] else 'under 2x'}: rig case {r['index']} ({r['subset']}, "
                      f"{r['load']}, {r['trajectory']}): {'+'.join(r['truth'])} -> {r['all_named'] or ['none']}"
                      f"{_detect_text(r)}")
    if rig_like:
        for title, key in (("per column subset", "by_subset"), ("per capstan-ratio band", "by_capstan_band")):
            print(f"generator and rig cases {title}:")
            for g, rt in out[key].items():
                print(f"  {g}: {rt['cases']} cases, named first {_num(rt['named_first_rate'], '.2f')}, none "
                      f"{_num(rt['none_rate'], '.2f')}, params {_num(rt['params_within_20pct_rate'], '.2f')}, 2x "
                      f"{_num(rt['improved_2x_rate'], '.2f')}")
    if dist_rows:
        print("distributed tendon-sheath plant (scenes.tendon_sheath):")
        print(distributed_text(out["distributed"], dist_rows))
    if args.sindy:
        print("physics against the PySINDy peer per channel (held-out RMSE, ratio = physics / PySINDy's better fit):")
        print(peer_text(out["peer"]))
    if combined:
        print("all: " + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}" for k, v in combined.items()))
    if args.speed:
        case = speed_case(args.seed)
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "speed_40s_1kHz.csv"
            case.write(path)
            t0 = time.process_time()
            w0 = time.perf_counter()
            diagnose(read_interchange(path))
            cpu, wall = time.process_time() - t0, time.perf_counter() - w0
        print(f"40 s, 1 kHz recording: {wall:.2f} s wall, {cpu:.2f} s CPU")
        out["speed_40s_1kHz"] = {"wall_s": wall, "cpu_s": cpu}
    if args.json:
        write_json(args.json, out)
    return 0
