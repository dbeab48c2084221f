"""`teleop bench diagnose --cases N --seed S [--json F]`: concealed-effect recordings from the generator,
diagnosed from their CSV alone; prints the confusion matrix and the rates of issue 6. With --speed, also
times the diagnosis of a 40 s, 1 kHz recording."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from teleop.apps.bench.diagnose_rig import rates, rig_plan, rig_text, run_rig_case, summarise_rig
from teleop.core.errors import InputError
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import GenConfig, case_plan, make_case
from teleop.diagnosis.scoring import confusion_text, run_case, summarise
from teleop.io.outputs import write_json
from teleop.io.progress import progress
from teleop.io.recording_io import read_interchange


def register(subparsers) -> None:
    p = subparsers.add_parser("diagnose", help="diagnosis accuracy on generated concealed-effect recordings")
    p.add_argument("--cases", type=int, default=100, help="number of generated recordings (100)")
    p.add_argument("--seed", type=int, default=0, help="generator seed (0)")
    p.add_argument("--json", metavar="PATH", help="write per-case rows and the summary as JSON")
    p.add_argument("--speed", action="store_true", help="also time a 40 s, 1 kHz recording")
    p.add_argument("--rate", type=float, default=500.0, help="sampling rate of the cases [Hz] (500)")
    p.add_argument("--seconds", type=float, default=20.0, help="duration of each case [s] (20)")
    p.add_argument("--noise", type=float, default=1.0, help="factor on every sensor noise level (1)")
    p.add_argument("--sindy", action="store_true",
                   help="also fit the PySINDy peer on each effect's channel and count where physics <= PySINDy")
    p.add_argument("--suite", choices=("all", "generator", "rig"), default="all",
                   help="cases from the concealed-effect generator, the simulated single-cable bench "
                        "(column subsets, loads, compounds; scenes.cable_rig), or half each (all)")
    p.set_defaults(func=run)


def speed_case(seed: int = 0):
    """A 40 s, 1 kHz rig recording with Dahl friction (for the timing benchmark)."""
    return make_case(999, "dahl_hysteresis", "rig", seed, GenConfig(fs_hz=1000.0, duration_s=40.0))


def run(args) -> int:
    if args.cases < 1:
        raise InputError("--cases must be >= 1")
    if not (50 <= args.rate <= 20000 and 5 <= args.seconds <= 600 and 0 <= args.noise <= 20):
        raise InputError("--rate must be 50..20000 Hz, --seconds 5..600, --noise 0..20")
    cfg = GenConfig(args.rate, args.seconds, args.noise)

    n_gen = {"all": args.cases // 2, "generator": args.cases, "rig": 0}[args.suite]
    rows, rig_rows = [], []
    plan = case_plan(n_gen)
    rplan = rig_plan(args.cases - n_gen, args.seed)
    with progress(len(plan) + len(rplan), "bench diagnose", unit="cases") as bar:
        for i, (effect, setup) in enumerate(plan):
            rows.append(run_case(make_case(i, effect, setup, args.seed, cfg), sindy=args.sindy))
            bar.update()
        for case in rplan:
            rig_rows.append(run_rig_case(case, args.seed, args.rate, args.seconds, args.noise, args.sindy))
            bar.update()
    summary = summarise(rows) if rows else {}
    rig_summary = summarise_rig(rig_rows) if rig_rows else {}
    combined = rates(rows + rig_rows)
    if args.sindy:
        peers = [r["peer"] for r in rows if "peer" in r] + [p for r in rig_rows for p in r.get("peer", [])]
        le = [p for p in peers if p["model_le_sindy"]]
        combined["model_le_sindy"] = f"{len(le)}/{len(peers)}"
        for p_ in peers:
            if not p_["model_le_sindy"]:
                print(f"PySINDy better on {p_['channel']}: model {p_['model_rmse']:.4g}, PySINDy {p_['sindy_rmse']:.4g}")
    if rig_rows:
        print("simulated single-cable bench (scenes.cable_rig):")
        print(rig_text(rig_summary))
        for r in rig_rows:
            if not r["correct"]:
                print(f"miss: rig case {r['index']} ({r['subset']}, {r['load']}, {r['trajectory']}): "
                      f"{'+'.join(r['truth'])} -> {r['all_named'] or ['none']}")
    if not rows:
        print("all: " + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}" for k, v in combined.items()))
        out = {"cases": args.cases, "seed": args.seed, "suite": args.suite, "rate_hz": args.rate,
               "seconds": args.seconds, "noise": args.noise, "summary": combined, "rig": rig_summary,
               "rig_rows": rig_rows}
        if args.json:
            write_json(args.json, out)
        return 0
    print("concealed-effect generator (teleop.diagnosis.generator):")
    print(confusion_text(summary))
    for key in ("cases", "effect_cases", "clean_cases", "named_first_rate", "none_rate",
                "params_within_20pct_rate", "improved_2x_rate", "improvement_min"):
        v = summary[key]
        print(f"{key}: {v:.4g}" if isinstance(v, float) else f"{key}: {v}")
    misses = [r for r in rows if not r["correct"]]
    for r in misses:
        print(f"miss: case {r['index']} ({r['setup']}, {r['trajectory']}): {r['truth']} -> {r['all_named'] or ['none']}")
    print("all: " + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}" for k, v in combined.items()))
    out = {"cases": args.cases, "seed": args.seed, "suite": args.suite, "rate_hz": args.rate,
           "seconds": args.seconds, "noise": args.noise, "summary": combined, "generator": summary,
           "rows": rows, "rig": rig_summary, "rig_rows": rig_rows}
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
