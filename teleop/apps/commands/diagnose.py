"""`teleop diagnose REC...`: where simulation and recording differ, which physics is missing, and the fit
once it is modelled (JSON keys: docs/formats.md)."""

from __future__ import annotations

import sys
from pathlib import Path

from teleop.apps.argtypes import input_file, positive_float
from teleop.apps.campaign.recordings import diagnose_files
from teleop.apps.commands.campaign import add_scheduler_option
from teleop.diagnosis.crossfile import cross_file
from teleop.diagnosis.diagnose import baseline_effects, diagnose
from teleop.diagnosis.identify import applicable
from teleop.diagnosis.links import find_links, link_data
from teleop.diagnosis.plot import figure
from teleop.io.model_io import save_model
from teleop.core.errors import InputError
from teleop.io.outputs import output_problem, same_file, save_figure, write_json
from teleop.io.progress import progress
from teleop.io.recording_io import MAX_INPUT_MB, read_recording


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "diagnose", help="locate sim-vs-real mismatch in recordings, name the missing physics, show the fit")
    p.add_argument("recordings", nargs="+", type=input_file, metavar="REC",
                   help="interchange CSV (or any layout with --map)")
    p.add_argument("--map", metavar="MAP", help="column map: a .toml path or a shipped name (e.g. mrdlab)")
    p.add_argument("--holdout", type=float, default=0.4, help="fraction at the end scoring the models (0.4)")
    p.add_argument("--json", metavar="PATH", help="write the report as JSON")
    p.add_argument("--plot", metavar="PATH",
                   help="write the figure (.png, .pdf or .svg); several recordings: one each, PATH's stem + "
                        "_<recording's stem> (+ _2, _3 ... where two recordings share a file name)")
    p.add_argument("--save-model", metavar="PATH", help="write the identified link models (JSON)")
    p.add_argument("--seed", type=int, default=0, help="seed of the fits' extra starts (0)")
    p.add_argument("--max-input-mb", type=positive_float, default=MAX_INPUT_MB, metavar="MB",
                   help=f"refuse a recording larger than this before reading it ({MAX_INPUT_MB:g})")
    p.add_argument("--baseline", metavar="EFFECTS", default="default",
                   help="what your simulation already contains: 'default' (the project's simulation: capstan "
                        "friction over the bend, the spring load), 'lossless' (ideal links), or a comma list "
                        "of catalogue effects; findings are what lies beyond it")
    p.add_argument("--sindy", action="store_true",
                   help="also fit the PySINDy peer (polynomial + Fourier library, STLSQ; static and free-run "
                        "forms) on the same held-out split")

    add_scheduler_option(p)  # several files: each diagnosed where the scheduler runs tasks (teleop.apps.campaign)
    p.set_defaults(func=run)


def _summary(doc: dict) -> str:
    lines = [f"{doc['recording']}", f"  baseline: {doc['baseline']['model']}"]
    for ch, rm in doc["baseline"]["rmse"].items():
        info = doc["channels"][ch]
        peer = doc["peer"][ch]
        sindy = f", PySINDy peer {peer['sindy_rmse']:.4g}" if "sindy_rmse" in peer else ""
        lines.append(f"  {ch} ({info['link']} link): baseline rmse {rm:.4g} -> model {info['rmse_model']:.4g} "
                     f"[ARX peer {peer['arx_rmse']:.4g}{sindy}] {doc['channels'][ch]['unit']}")
    if not doc["findings"]:
        lines.append("  findings: none")
    for f in doc["findings"]:
        ps = ", ".join(f"{k}={v['value']:.4g}±{(v['stderr'] or 0):.2g} {v['unit']}" for k, v in f["params"].items())
        lines.append(f"  {f['effect']} on {f['channel']}: {f['rmse_before']:.4g} -> {f['rmse_after']:.4g} "
                     f"(x{f['improvement']:.2f}) where {f['where']['condition']}; {ps}")
    for u in doc["unexplained"]:
        lines.append(f"  unexplained on {u['channel']}: rmse {u['rmse']:.3g} (noise {u['noise_rmse']:.2g}), "
                     f"best correlate: {u['correlate']} (R2 {u['r2']:.2f})")
    return "\n".join(lines)


def plot_paths(plot: str, recordings: list) -> list:
    """The figure file of each recording for `--plot PLOT`: PLOT itself for one recording; for several,
    PLOT's stem + '_' + the recording's stem (+ '_2', '_3' ... where that name is taken), PLOT's suffix
    (.png when it has none), all distinct."""
    path = Path(plot)
    if len(recordings) == 1:
        return [path]
    out, taken = [], set()
    for rec in recordings:
        base = f"{path.stem}_{Path(rec).stem}"
        name, k = base, 2
        while name in taken:
            name, k = f"{base}_{k}", k + 1
        taken.add(name)
        out.append(path.with_name(name + (path.suffix or ".png")))
    return out


def _check_plots(paths: list, recordings: list) -> None:
    """InputError naming --plot when a figure file cannot be written or is one of the recordings."""
    for path in paths:
        problem = output_problem(path)
        if problem:
            raise InputError(f"--plot: {path} {problem}")
        for rec in recordings:
            if same_file(path, rec):
                raise InputError(f"--plot: {path} is the input recording {rec} (the same file); expected an "
                                 f"output that does not overwrite an input")


def run(args) -> int:
    baseline = baseline_effects(args.baseline)
    plots = plot_paths(args.plot, args.recordings) if args.plot else []
    _check_plots(plots, args.recordings)
    recs = [read_recording(p, args.map, args.max_input_mb) for p in args.recordings]
    docs, diags = [], []
    if args.scheduler != "none":  # each file read again and diagnosed on the scheduler's workers
        diags = diagnose_files(args.recordings, args.map, args.holdout, args.scheduler, args.max_input_mb,
                               seed=args.seed, baseline=baseline, sindy=args.sindy)
        docs, recs = [d.as_dict() for d in diags], []  # nothing left for the in-process loop below
    total = sum(3 * len(applicable(link_data(r, L))) for r in recs for L in find_links(r))
    with progress(total, "diagnose", unit="fits", leave=False) as bar:
        for rec in recs:
            diag = diagnose(rec, args.holdout, progress=bar.update, seed=args.seed, baseline=baseline,
                            sindy=args.sindy)
            diags.append(diag)
            docs.append(diag.as_dict())
    for doc in docs:
        print(_summary(doc))
    result = docs[0]
    if len(docs) > 1:
        cross = cross_file(diags)
        result = {"recordings": docs, "cross_file": cross}
        for ch, s in cross["summary"].items():
            chains = ", ".join(f"{c} (min x{m:.2f})" for c, m in s["by_chain"].items())
            print(f"across files, {ch}: effects fitted on one file, scored on another: improvement "
                  f"x{s['improvement_geomean']:.2f} (geometric mean of {s['pairs']} pairs), min "
                  f"x{s['improvement_min']:.2f}; by chain: {chains}")
    if args.json:
        write_json(args.json, result)
    for diag, path in zip(diags, plots):
        save_figure(figure(diag), path)
        print(f"wrote {path}" + (f" ({diag.rec.path})" if len(plots) > 1 else ""))
    if args.save_model:
        models = [res.final.model for res in diags[0].links]
        if len(diags) > 1:
            print("teleop: note: --save-model writes the model of the first recording", file=sys.stderr)
        save_model(args.save_model, models, diags[0].rec.path)
    return 0
