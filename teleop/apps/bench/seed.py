"""`teleop bench seed [--plant distributed|matched] [--cable-params F] [--seed S] [--only LIST] [--quick]
[--participants N] [--json F]`: seed 000's figures predicted by the simulated robot, side by side with the
seed's numbers, each with a verdict against the issue's goal.

Nothing here is fitted to the figure it is checked against: the distributed cable's parameters come from
the sources written beside them (scenes.tendon_sheath.TendonSheathParams, docs/plant-distributed.md); the
estimators are the project's, calibrated on the no-load runs as the seed's were. The experiments are the
existing ones, called:

- fig9, fig10b, fig11: the single-cable bench (teleop.apps.bench.cable; `teleop bench cable --experiment ...`);
- fig13 (robot level): the no-load z run of the stiffness test, every estimator's z wrench (the truth is 0)
  without, with single and with double compensation (teleop.apps.protocols.palpation, `no_load`), and table1
  from the same run's pokes (`teleop palpate --test stiffness`);
- fig16z, fig16xy: `teleop palpate --test z|xy`;
- table3: the blind study (teleop.apps.protocols.blind) with the rating rule "anchored", which fixes no pad's
  rating (participants.py), on the simulated rig with the same plant.

Goals (issue 25): a number the seed reports with a spread (Table 3's std) is met when ours lies within it; an
error figure is met within a factor GOAL_FACTOR either way (a prediction 15x below the hardware's error is a
miss as much as one 15x above); a claim the seed makes in words is met when the stated inequality holds;
and the project's `dynamic` estimator should stay ahead of `double` (a lower MAE) on every palpation test.
"""

from __future__ import annotations

import dataclasses
import sys
import time

import numpy as np

from scenes.tendon_sheath import TendonSheathParams
from teleop.apps.argtypes import input_file, positive_int
from teleop.apps.bench import cable as cable_bench
from teleop.apps.protocols import palpation
from teleop.apps.protocols.blind.participants import ParticipantParams
from teleop.apps.protocols.blind.rig import RigOptions, SimRig
from teleop.apps.protocols.blind.stats import SEED_TABLE3
from teleop.apps.protocols.blind.study import run_simulated_study
from teleop.apps.protocols.palpation_sensors import SEED_FIGURES
from teleop.core.errors import InputError
from teleop.io.outputs import check_output, write_json

FIGURES = ("fig9", "fig10b", "fig11", "fig13", "table1", "fig16z", "fig16xy", "table3")
PLANTS = ("distributed", "matched")
GOAL_FACTOR = 1.5
SEED_Z = (SEED_FIGURES["seed 000 z palpation MAE (FSR array, double compensation, hardware)"],
          SEED_FIGURES["seed 000 z palpation RMSE"])
SEED_XY = (SEED_FIGURES["seed 000 x/y palpation MAE"], 0.321)  # seed 000 §5.1 test 2: x/y RMSE 0.321 N


def register(subparsers) -> None:
    p = subparsers.add_parser("seed", help="seed 000's figures (Fig 9-16, Tables 1 and 3) predicted by the simulated "
                                           "robot beside the seed's numbers")
    p.add_argument("--plant", default="distributed", choices=PLANTS,
                   help="the cables: distributed (the distributed tendon-sheath cable, default) or matched")
    p.add_argument("--cable-params", type=input_file, default=None, metavar="TOML",
                   help="with --plant distributed: the cable's [tendon_sheath] table (docs/formats.md), for every "
                        "figure including the blind study's rig")
    p.add_argument("--seed", type=int, default=1, help="seed of the noise, the palpation and the study (default 1)")
    p.add_argument("--only", default=None, metavar="LIST",
                   help=f"comma-separated figures to run (default all: {','.join(FIGURES)})")
    p.add_argument("--quick", action="store_true",
                   help="a quick look: 2 pokes a palpation run, 1 z repetition, 3 weights in fig10b, 2 participants")
    p.add_argument("--participants", type=positive_int, default=None, metavar="N",
                   help="blind-study participants (default 10, as the seed; 2 with --quick)")
    p.add_argument("--json", metavar="F", help="write the numbers and verdicts as JSON")
    p.set_defaults(func=run)


# ---- verdicts --------------------------------------------------------------------------------------------

def within_factor(ours: float, seed: float, factor: float = GOAL_FACTOR) -> bool:
    """True when ours lies within `factor` of seed either way (both > 0)."""
    return bool(ours > 0 and seed > 0 and seed / factor <= ours <= seed * factor)


def within_spread(ours: float, mean: float, std: float) -> bool:
    """True when ours lies within mean +- std."""
    return bool(abs(ours - mean) <= std)


def _mae(values, truth) -> float:
    return float(np.mean(np.abs(np.asarray(values, dtype=float) - np.asarray(truth, dtype=float))))


# ---- the figures -----------------------------------------------------------------------------------------

def fig9(seed: int, cable: TendonSheathParams | None) -> dict:
    res = cable_bench.fig9(seed, cable=cable)
    rows, checks = {}, {}
    for deg in ("0", "30"):
        c = res["cases"][deg]
        s = c["seed"]
        rows[deg] = {"fsr_change_N": c["distal_change_N"], "tension_B_change_N": c["tension_B_change_N"],
                     "proximal_change_N": c["proximal_change_N"], "seed_fsr_change_N": s["distal_change_N"],
                     "seed_proximal_change_N": s["proximal_change_N"]}
        checks[f"fsr_{deg}deg"] = within_factor(c["distal_change_N"], s["distal_change_N"])
        checks[f"proximal_{deg}deg"] = within_factor(c["proximal_change_N"], s["proximal_change_N"])
    # a number a parameter was taken from is its source, not a check of it
    sources = ("fsr_30deg",) if cable is not None else ("fsr_0deg", "fsr_30deg", "proximal_0deg")
    return {"cases": rows, "checks": {k: v for k, v in checks.items() if k not in sources},
            "sources_not_checks": {k: checks[k] for k in sources},
            "mu_source": "the cable's mu_c from Fig 9b's FSR swing" if cable is not None else
            "the bench's mu(B-D) fitted to Fig 9a and 9b's FSR swings, mu(A-B) to Fig 9a's proximal swing"}


def fig10b(seed: int, cable: TendonSheathParams | None, quick: bool = False) -> dict:
    weights = np.array([50, 250, 500]) * 1e-3 * cable_bench.G_N_PER_KG if quick else None
    res = cable_bench.fig10b(seed, cable=cable, weights_N=weights)
    n = len(res["cases"])
    return {"cases": res["cases"], "smaller_after_compensation": res["smaller_after_compensation"], "weights": n,
            "seed": res["seed"], "checks": {"smaller_at_every_weight": res["smaller_after_compensation"] == n}}


def fig11(seed: int, cable: TendonSheathParams | None) -> dict:
    res = cable_bench.fig11(seed, cable=cable)
    cases = {k: {"fsr_raw_rmse_N": c["fsr_raw"]["rmse_N"], "single_rmse_N": c["single"]["rmse_N"],
                 "single_rmse_off_turns_N": c["single"]["rmse_away_from_turns_N"],
                 "single_max_near_turns_N": c["single"]["max_abs_near_turns_N"]} for k, c in res["cases"].items()}
    aligns = all(c["single_rmse_off_turns_N"] < c["fsr_raw_rmse_N"] for c in cases.values())
    shift = all(c["single_max_near_turns_N"] > 2 * c["single_rmse_off_turns_N"] for c in cases.values())
    same = all(abs(cases[f"{m}_360"]["single_rmse_N"] - cases[f"{m}_180"]["single_rmse_N"])
               <= 0.2 * max(cases[f"{m}_360"]["single_rmse_N"], 1e-9) for m in ("b", "c"))
    return {"cases": cases, "seed": res["seed"],
            "checks": {"compensated_aligns_better_than_raw": aligns, "shift_at_turns": shift,
                       "AB_360_and_180_within_20_percent": same}}


def palpation_run(test: str, seed: int, plant: str, cable_params, quick: bool, no_load: bool = False):
    """One palpation test (teleop.apps.protocols.palpation.run_test) with the bench's options."""
    params = palpation.PalpationParams()
    if quick:
        params = dataclasses.replace(params, repeats_z=1)
    return palpation.run_test(test, "uniform", seed, params, limit=2 if quick else None, plant=plant,
                              cable_params=cable_params, no_load=no_load)


def fig13(result) -> dict:
    """Robot-level Fig 13 from a palpation result run with no_load (its z no-load run)."""
    nl = next(v["z"] for v in result.extra["no_load"].values() if "z" in v)
    checks = {"single_steadier_than_none_off_turns":
              nl["single"]["rmse_off_turns_N"] < nl["non_compensated"]["rmse_off_turns_N"],
              "double_diminishes_the_turns": nl["double"]["max_abs_near_turns_N"] < nl["single"]["max_abs_near_turns_N"]}
    return {"z": nl, "seed": cable_bench.SEED["fig13"], "checks": checks,
            "note": "double's turn polynomials are fitted on this same run, as the seed's step 3"}


def _palpation_summary(result, seed_mae: float, seed_rmse: float | None) -> dict:
    s = result.summary
    out = {"summary": s, "seed_double_mae_N": seed_mae, "seed_double_rmse_N": seed_rmse,
           "checks": {"double_mae_within_1.5x": within_factor(s["double"]["mean_abs_error_N"], seed_mae),
                      "dynamic_ahead_of_double":
                      s["dynamic"]["mean_abs_error_N"] < s["double"]["mean_abs_error_N"]}}
    if seed_rmse is not None:
        out["checks"]["double_rmse_within_1.5x"] = within_factor(s["double"]["rmse_N"], seed_rmse)
    return out


def table1(result) -> dict:
    t = palpation.SEED_TABLE1
    seed_mae = {n: _mae(t[n], t["ground_truth"]) for n in ("non_compensated", "double")}
    out = _palpation_summary(result, seed_mae["double"], None)
    out["seed_non_compensated_mae_N"] = seed_mae["non_compensated"]
    out["checks"]["non_compensated_mae_within_1.5x"] = within_factor(
        result.summary["non_compensated"]["mean_abs_error_N"], seed_mae["non_compensated"])
    out["regions"] = result.extra.get("regions")
    out["load_response"] = result.extra.get("load_response")
    out["seed_load_response"] = result.extra.get("seed_table1_load_response")
    out["checks"]["ranks_correctly_double"] = bool(result.extra["ranks_correctly"]["double"])
    return out


def fig16(result, seed_pair) -> dict:
    return _palpation_summary(result, *seed_pair)


def table3(seed: int, plant: str, participants: int, cable_params=None) -> dict:
    with SimRig(RigOptions(plant=plant, cable_params=cable_params)) as rig:
        study = run_simulated_study(rig, participants, seed, ParticipantParams(), rating="anchored")
    ms = study.mean_std()
    rows, checks = {}, {}
    for area, s in zip(study.areas, SEED_TABLE3):
        m, sd = ms[area.name]
        rows[area.name] = {"label": area.label, "mean": m, "std": sd, "seed_mean": s["mean"], "seed_std": s["std"]}
        checks[f"{area.name}_mean_within_seed_std"] = within_spread(m, s["mean"], s["std"])
    checks["every_participant_ranks_right"] = study.correct_ranking_rate == 1.0
    return {"rating_rule": "anchored", "participants": participants, "areas": rows,
            "correct_ranking_rate": study.correct_ranking_rate, "kendall_w": study.kendall_w, "checks": checks,
            "ratings": {a.name: [r.ratings[a.name] for r in study.records] for a in study.areas}}


def run_figures(figures, seed: int, plant: str, cable_params=None, quick: bool = False,
                participants: int = 10, progress=print) -> dict:
    """{figure: result} of the named figures (FIGURES) with --plant `plant`; progress(str) after each."""
    cable = None
    if plant == "distributed":
        cable = TendonSheathParams() if cable_params is None else TendonSheathParams.from_toml(cable_params)
    out = {}
    stiffness = None
    for name in figures:
        t0 = time.perf_counter()
        if name == "fig9":
            out[name] = fig9(seed, cable)
        elif name == "fig10b":
            out[name] = fig10b(seed, cable, quick)
        elif name == "fig11":
            out[name] = fig11(seed, cable)
        elif name in ("fig13", "table1"):
            if stiffness is None:
                stiffness = palpation_run("stiffness", seed, plant, cable_params, quick, no_load=True)
            out[name] = fig13(stiffness) if name == "fig13" else table1(stiffness)
        elif name == "fig16z":
            out[name] = fig16(palpation_run("z", seed, plant, cable_params, quick), SEED_Z)
        elif name == "fig16xy":
            out[name] = fig16(palpation_run("xy", seed, plant, cable_params, quick), SEED_XY)
        elif name == "table3":
            out[name] = table3(seed, plant, participants, cable_params)
        out[name]["command"] = command(name, seed, plant, cable_params)
        out[name]["wall_s"] = time.perf_counter() - t0
        progress(f"{name}: done in {out[name]['wall_s']:.0f} s")
    return out


def command(name: str, seed: int, plant: str, cable_params=None) -> str:
    """The command that reproduces one figure on its own."""
    extra = f" --cable-params {cable_params}" if cable_params else ""
    if name in ("fig9", "fig10b", "fig11"):
        return f"teleop bench cable --experiment {name} --plant {plant} --seed {seed}{extra}"
    if name in ("fig13", "table1"):
        return f"teleop palpate --test stiffness --plant {plant} --seed {seed}{extra}" + (
            "  (fig13: the no-load z run, palpation.run_test(no_load=True))" if name == "fig13" else "")
    if name in ("fig16z", "fig16xy"):
        return f"teleop palpate --test {name[5:]} --plant {plant} --seed {seed}{extra}"
    return (f"teleop bench seed --only table3 --plant {plant} --seed {seed}{extra}  (blind study, rating rule "
            f"anchored)")


# ---- output ----------------------------------------------------------------------------------------------

def _ok(b: bool) -> str:
    return "met" if b else "MISSED"


def table(res: dict) -> str:
    L = []
    for name, r in res.items():
        L.append(f"== {name}: {r['command']}")
        if name == "fig9":
            L.append(f"{'theta':>6} {'FSR change':>11} {'(seed)':>7} {'tension at B':>13} {'proximal':>9} {'(seed)':>7}")
            for deg, c in r["cases"].items():
                L.append(f"{deg:>6} {c['fsr_change_N']:11.2f} {c['seed_fsr_change_N']:7.2f} "
                         f"{c['tension_B_change_N']:13.2f} {c['proximal_change_N']:9.2f} "
                         f"{c['seed_proximal_change_N']:7.2f}")
            L.append(f"mu: {r['mu_source']} (source, not a check: {', '.join(r['sources_not_checks'])})")
        elif name == "fig10b":
            L.append(f"{'weight':>7} {'FSR swing':>10} {'compensated':>12} {'tension at B':>13}")
            for c in r["cases"].values():
                L.append(f"{c['weight_N']:7.2f} {c['fsr_change_N']:10.3f} {c['compensated_change_N']:12.3f} "
                         f"{c['tension_B_change_N']:13.3f}")
            L += ["seed (in words): " + s for s in r["seed"]]
        elif name == "fig11":
            L.append(f"{'case':>6} {'FSR raw RMSE':>13} {'single RMSE':>12} {'off turns':>10} {'max near turns':>15}")
            for k, c in r["cases"].items():
                L.append(f"{k:>6} {c['fsr_raw_rmse_N']:13.3f} {c['single_rmse_N']:12.3f} "
                         f"{c['single_rmse_off_turns_N']:10.3f} {c['single_max_near_turns_N']:15.3f}")
            L += ["seed (in words): " + s for s in r["seed"]]
        elif name == "fig13":
            z = r["z"]
            L.append(f"no-load z run, {z['turns']} turns (near a turn: {z['turn_window_s']:.2f} s after it); "
                     f"z wrench [N], truth 0")
            L.append(f"{'estimator':>16} {'RMSE':>6} {'p-p':>6} {'RMSE off turns':>15} {'max near turns':>15}")
            for n in palpation.ESTIMATORS:
                e = z[n]
                L.append(f"{n:>16} {e['rmse_N']:6.3f} {e['peak_to_peak_N']:6.3f} {e['rmse_off_turns_N']:15.3f} "
                         f"{e['max_abs_near_turns_N']:15.3f}")
            L += ["seed (in words): " + s for s in r["seed"]]
        elif name in ("table1", "fig16z", "fig16xy"):
            s = r["summary"]
            L.append(f"{'estimator':>16} {'MAE':>6} {'RMSE':>6}")
            for n in palpation.ESTIMATORS:
                L.append(f"{n:>16} {s[n]['mean_abs_error_N']:6.3f} {s[n]['rmse_N']:6.3f}")
            seed_line = f"seed: double MAE {r['seed_double_mae_N']:.3f}"
            if r.get("seed_double_rmse_N") is not None:
                seed_line += f", RMSE {r['seed_double_rmse_N']:.3f}"
            if "seed_non_compensated_mae_N" in r:
                seed_line += f"; non-compensated MAE {r['seed_non_compensated_mae_N']:.3f}"
            L.append(seed_line)
        elif name == "table3":
            L.append(f"rating rule {r['rating_rule']}, {r['participants']} participants, correct ranking "
                     f"{r['correct_ranking_rate']:.0%}, Kendall W {r['kendall_w']:.3f}")
            L.append(f"{'area':>16} {'mean':>5} {'std':>5} | {'seed mean':>9} {'std':>5}")
            for a in r["areas"].values():
                L.append(f"{a['label']:>16} {a['mean']:5.2f} {a['std']:5.2f} | {a['seed_mean']:9.1f} {a['seed_std']:5.2f}")
        L.append("goal: " + ", ".join(f"{k} {_ok(v)}" for k, v in r["checks"].items()))
        L.append("")
    met, total = goals_met(res)
    L.append(f"goals met: {met} of {total} (docs/plant-distributed.md: the physics the missed ones would need)")
    return "\n".join(L)


def goals_met(res: dict) -> tuple:
    """(met, total) over every figure's checks."""
    checks = [v for r in res.values() for v in r["checks"].values()]
    return sum(bool(v) for v in checks), len(checks)


def parse_only(text: str | None) -> tuple:
    """The figures of --only (all when None); an unknown name is an InputError naming the flag."""
    if text is None:
        return FIGURES
    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    bad = [n for n in names if n not in FIGURES]
    if bad or not names:
        raise InputError(f"--only: unknown figure(s) {', '.join(bad) or '(none given)'}; expected a comma-separated "
                         f"list of {', '.join(FIGURES)}")
    return names


def run(args) -> int:
    if args.json:
        check_output(args.json, "--json")
    if args.cable_params is not None and args.plant != "distributed":
        raise InputError("--cable-params: the cable's parameters belong to --plant distributed")
    figures = parse_only(args.only)
    participants = args.participants or (2 if args.quick else 10)
    res = run_figures(figures, args.seed, args.plant, args.cable_params, args.quick, participants,
                      progress=lambda s: print(s, file=sys.stderr, flush=True))
    print(table(res))
    if args.json:
        cable = (TendonSheathParams() if args.cable_params is None else TendonSheathParams.from_toml(args.cable_params))
        write_json(args.json, {"plant": args.plant, "seed": args.seed, "quick": bool(args.quick),
                               "cable": dataclasses.asdict(cable) if args.plant == "distributed" else None,
                               "goal_factor": GOAL_FACTOR, "figures": res})
    return 0

