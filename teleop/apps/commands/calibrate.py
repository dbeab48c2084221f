"""`teleop calibrate fsr|fbg|one-sensor CSV --out FILE [--plot PNG] [--json F] [--map MAP]`: fit a sensor's
calibration from a recording and write the calibration file (TOML, docs/formats.md "Calibration files").

- fsr: the loading and unloading quintics (seed 000 eq 2 / Fig 7) from a step protocol CSV
  (tension_N, conductance_uS[, branch]).
- fbg: sensitivity [pm/N], hysteresis and the temperature ratio r (seed 001 sec. 2.1.3-2.1.4, 3.1) from
  load steps at two or more temperatures (force_N, temperature_C, dl1_pm, dl2_pm[, branch]).
- one-sensor: Kp, Kr and the transition widths (seed 001 eq 7) of one instrumented cable (interchange CSV
  with motor_force and tip_force, or any layout through --map, e.g. mrdlab).

Prints the fitted values with their standard errors (each fit keeps the terms the data ask for and reports
errors that hold with coloured noise and unconditional on that choice: teleop.core.calibration); the plot (fit and residual) goes to --plot, by
default beside --out with the suffix .png.

No measured FSR or FBG calibration recording exists in the project: those two fits have run on protocols
generated from the sensor physics only
(`python -m teleop.core.calibration.generate DIR` writes them). The one-sensor fit runs on the real MRDLab
instrument runs (`--map mrdlab`), whose spindle and jaw torques are not one pull-only cable's tensions.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from teleop import __version__
from teleop.apps.argtypes import input_file, output_file, positive_float
from teleop.core.calibration.fbg import fit_fbg, plot_fbg_fit
from teleop.core.calibration.fsr import BRANCHES, fit_fsr, plot_fsr_fit
from teleop.core.calibration.one_sensor import fit_one_sensor, plot_one_sensor_fit
from teleop.core.errors import InputError
from teleop.core.sensors import eq2_roots
from teleop.io import calfile
from teleop.io.calibration_csv import read_fbg_steps, read_fsr_steps, read_one_sensor
from teleop.io.outputs import check_output, same_file, save_figure, write_json
from teleop.io.recording_io import MAX_INPUT_MB, sniff

KINDS = ("fsr", "fbg", "one-sensor")


def register(subparsers) -> None:
    p = subparsers.add_parser("calibrate", help="fit a sensor calibration (FSR, FBG, one sensor for all cables)")
    p.add_argument("kind", choices=KINDS, help="what to calibrate")
    p.add_argument("csv", type=input_file, metavar="CSV", help="the calibration recording")
    p.add_argument("--out", type=output_file, required=True, metavar="FILE", help="calibration file to write (TOML)")
    p.add_argument("--plot", metavar="PNG", help="fit and residual plot (default: FILE with suffix .png)")
    p.add_argument("--json", metavar="F", help="write the fitted values and uncertainties as JSON")
    p.add_argument("--map", metavar="MAP", help="one-sensor: column map of the recording (shipped name or .toml)")
    p.add_argument("--max-input-mb", type=positive_float, default=MAX_INPUT_MB, metavar="MB",
                   help=f"refuse a recording larger than this before reading it ({MAX_INPUT_MB:g})")
    p.set_defaults(func=run)


def _fmt(value: float, err: float | None = None, unit: str = "") -> str:
    s = f"{value:.6g}" if err is None else f"{value:.6g} +/- {err:.2g}"
    return f"{s} {unit}".rstrip()


def run(args) -> int:
    plot_path = Path(args.plot) if args.plot else Path(args.out).with_suffix(".png")
    check_output(plot_path, "--plot")
    if same_file(plot_path, args.csv):
        raise InputError(f"--plot: {plot_path} is the input CSV {args.csv} (the same file); expected an output "
                         f"that does not overwrite an input")
    sniff(args.csv, args.max_input_mb)
    if args.map and args.kind != "one-sensor":
        raise InputError(f"--map: only for one-sensor (a column map of its recording), not {args.kind}")
    comment = f"written by teleop calibrate {args.kind} {args.csv} (cdpr-teleop {__version__})"
    lines = []
    if args.kind == "fsr":
        fit = fit_fsr(read_fsr_steps(args.csv))
        summary = fit.summary()
        values = {"loading_S": list(fit.cal.loading), "unloading_S": list(fit.cal.unloading),
                  "t_max_N": fit.cal.t_max}
        stderr = {"loading_S": list(fit.stderr["loading"]), "unloading_S": list(fit.stderr["unloading"])}
        quality = {name: {"rows": summary[name]["rows"], "rms_residual_uS": summary[name]["rms_residual_uS"],
                          "rms_residual_N": summary[name]["rms_residual_N"]} for _, name in BRANCHES}
        fig = plot_fsr_fit(fit)
        for _, name in BRANCHES:
            coefs = summary[name]["coef_S"]
            kept = np.trim_zeros(np.asarray(coefs), "b")   # up to the highest power kept
            a, roots = eq2_roots(kept)
            lines.append(f"{name}: G(t) = sum c_k t^k, c_k [uS/N^k] = " + ", ".join(
                _fmt(c * 1e6, e * 1e6) for c, e in zip(coefs, summary[name]["stderr_S"])))
            lines.append(f"  eq 2 form: a = {a * 1e6:.4g} uS/N^{kept.size - 1}, roots [N] = "
                         + ", ".join(f"{complex(r_).real:.3g}{complex(r_).imag:+.3g}j" if abs(complex(r_).imag) > 1e-9
                                     else f"{complex(r_).real:.3g}" for r_ in roots))
            lines.append(f"  powers of t kept (AIC): {', '.join(map(str, summary[name]['powers']))}; "
                         f"the others 0")
            lines.append(f"  residual RMS {summary[name]['rms_residual_uS']:.3f} uS = "
                         f"{summary[name]['rms_residual_N']:.4f} N over {summary[name]['rows']} rows")
        source = fit.data.source
    elif args.kind == "fbg":
        fit = fit_fbg(read_fbg_steps(args.csv))
        summary = fit.summary()
        p = fit.params
        values = {"S_pm_N": p.S_pm_N, "r": p.r, "kT1_pm_C": p.kT1_pm_C, "kT2_pm_C": p.kT2_pm_C, "noise_pm": p.noise_pm}
        stderr = {k: fit.stderr[k] for k in ("S_pm_N", "r", "kT1_pm_C", "kT2_pm_C")}
        quality = {k: fit.values[k] for k in ("hysteresis_pm", "hysteresis_N", "hysteresis_percent",
                                               "hysteresis_at_N", "hysteresis_terms", "rmse_pm",
                                               "rmse_compensated_pm", "force_error_N", "rmse_dl1_pm", "full_scale_N")}
        quality["hysteresis_percent_stderr"] = fit.stderr["hysteresis_percent"]
        fig = plot_fbg_fit(fit)
        v, e = fit.values, fit.stderr
        lines += [f"sensitivity S = {_fmt(v['S_pm_N'], e['S_pm_N'], 'pm/N')}   (seed 001: 34.12 pm/N)",
                  f"kT1 = {_fmt(v['kT1_pm_C'], e['kT1_pm_C'], 'pm/degC')}, kT2 = "
                  f"{_fmt(v['kT2_pm_C'], e['kT2_pm_C'], 'pm/degC')}   (seed: 11.23, 25.62)",
                  f"temperature ratio r = {_fmt(v['r'], e['r'])}   (seed: 2.28)",
                  f"hysteresis = {_fmt(v['hysteresis_percent'], e['hysteresis_percent'], '%')} of "
                  f"{v['full_scale_N']:.3g} N full scale: the largest loading - unloading gap, "
                  f"{v['hysteresis_N']:.3f} N at {v['hysteresis_at_N']:.3g} N (loop model of "
                  f"{v['hysteresis_terms']} term(s), zero at the ends)   (seed: 4.798 %)",
                  f"RMSE FBG2 {v['rmse_pm']:.3f} pm, compensated {v['rmse_compensated_pm']:.3f} pm = "
                  f"{v['force_error_N']:.3f} N   (seed: 12.59 pm = 0.37 N)"]
        source = fit.data.source
    else:
        Fp, Fd, unit, source = read_one_sensor(args.csv, args.map, max_mb=None)  # its size checked above
        fit = fit_one_sensor(Fp, Fd, unit, source)
        summary = fit.summary()
        m = fit.model
        values = {"Kp": m.Kp, "Kr": m.Kr, "bp": m.bp, "br": m.br, "unit": unit}
        stderr = dict(fit.stderr)
        quality = {"rmse": fit.rmse, "samples": int(Fp.size), "transition_width": fit.widths}
        fig = plot_one_sensor_fit(fit)
        e = fit.stderr
        lines += [f"Kp = {_fmt(m.Kp, e['Kp'])}, Kr = {_fmt(m.Kr, e['Kr'])}   "
                  f"(seed 001 Fig 5: Kp 0.609 / 0.588, Kr 1.558 / 1.626)",
                  f"bp = {_fmt(m.bp, e['bp'], unit)}, br = {_fmt(m.br, e['br'], unit)}   (kept: "
                  f"{', '.join(fit.free)} by AIC; an intercept not kept is 0)",
                  f"distal prediction RMSE {fit.rmse:.4g} {unit} over {Fp.size} samples "
                  f"(distal range {float(Fd.max() - Fd.min()):.4g} {unit})"]
        if m.Kp < 0 or m.Kr < 0:
            lines.append("note: negative slopes: the distal force falls as the proximal one rises (an inverting "
                         "transmission, e.g. a spindle's torque against its jaw's); seed 001 eq 7 is one pull-only "
                         "cable with 0 < Kp < 1 < Kr")
        for name, w in fit.widths.items():
            lines.append(f"transition width at the {name} turn (distal {w['distal']:.4g} {unit}): "
                         f"{_fmt(w['width'], w['stderr'], unit)} of proximal force")
    calfile.write_calibration(args.out, args.kind, str(source), values, stderr, quality, comment)
    save_figure(fig, plot_path)
    summary = {**summary, "calibration_file": str(args.out), "plot": str(plot_path)}
    if args.json:
        write_json(args.json, summary)
    print(f"{args.kind} calibration from {args.csv}")
    for line in lines:
        print("  " + line)
    print(f"wrote {args.out}, {plot_path}" + (f" and {args.json}" if args.json else ""))
    return 0
