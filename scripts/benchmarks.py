"""The benchmarks' figures: run the benches into docs/benchmarks/*.json, render docs/benchmarks.md from them.

    python scripts/benchmarks.py run [NAME ...]     # each bench with --json; default: every bench
    python scripts/benchmarks.py render             # docs/benchmarks.md from the JSON files there
    python scripts/benchmarks.py list               # the bench names and their commands

`run` writes docs/benchmarks/<name>.json as {"command", "date", "machine": {"nproc", "cpu", "python"},
"load": the 1-minute load average before and after the run, "result": the bench's own JSON}. `render` reads
every such file and writes one table per benchmark (the figures, then the command, machine, date and load they
come from); a bench without a file is listed as not run.
The figures are read from the result by the functions below; a key a result lacks is left out of its table.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "docs" / "benchmarks"
PAGE = REPO / "docs" / "benchmarks.md"

Row = tuple[str, str]


def _get(d, *path):
    """d[path[0]][path[1]]..., or None where a key is missing."""
    for key in path:
        if not isinstance(d, dict) or key not in d:
            return None
        d = d[key]
    return d


def _fmt(value, unit: str = "", digits: int = 4) -> str | None:
    if value is None:
        return None
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        text = f"{value:.{digits}g}"
    else:
        text = str(value)
    return f"{text} {unit}".rstrip()


def _rows(pairs) -> list[Row]:
    """(label, formatted value or None) pairs, the None ones dropped."""
    return [(label, value) for label, value in pairs if value is not None]


def _pct(p50_p99: dict | None, unit: str) -> str | None:
    if not isinstance(p50_p99, dict) or "p50" not in p50_p99:
        return None
    parts = [f"{k} {p50_p99[k]:.3g}" for k in ("p50", "p99", "max") if k in p50_p99]
    return ", ".join(parts) + f" {unit}"


def tick_rows(r: dict) -> list[Row]:
    return _rows([("ticks", _fmt(r.get("ticks"))),
                  ("tick", _pct(r.get("tick_us"), "us")),
                  ("reference tick (numpy, scipy, filterpy)", _pct(r.get("reference_tick_us"), "us")),
                  ("speed-up at p50", _fmt(r.get("speedup_p50"), "x", 3))])


def loop_rows(r: dict) -> list[Row]:
    stages = r.get("stages_us") or {}
    budget = r.get("budget")
    verdict = _get(budget, "verdict") if isinstance(budget, dict) else budget
    return _rows([("rate", _fmt(r.get("rate_hz"), "Hz")), ("ticks", _fmt(r.get("ticks"))),
                  ("deadline misses", _fmt(r.get("deadline_misses"))),
                  ("tick", _pct(r.get("tick_us"), "us")), ("lateness", _pct(r.get("lateness_us"), "us")),
                  ("budget verdict", _fmt(verdict))]
                 + [(f"stage {name}", _pct(v, "us")) for name, v in stages.items()])


def link_rows(r: dict) -> list[Row]:
    silence = r.get("host_silence") or {}
    return _rows([("round trips", _fmt(r.get("roundtrips"))), ("round trip", _pct(r.get("rtt_ms"), "ms")),
                  ("firmware turnaround (emulated)", _pct(r.get("firmware_turnaround_ms"), "ms"))]
                 + [(f"watchdog stop, host {what}",
                     _fmt(f"max {_get(s, 'stop_ms', 'max'):.3g} ms, {s.get('within_50ms')} of {s.get('trials')} "
                          "within 50 ms") if _get(s, "stop_ms", "max") is not None else None)
                    for what, s in silence.items()])


def sim_rows(r: dict) -> list[Row]:
    return _rows([("simulated", _fmt(r.get("simulated_s"), "s")),
                  ("real-time factor (wall)", _fmt(r.get("realtime_factor"), "x", 3)),
                  ("real-time factor (CPU)", _fmt(r.get("realtime_factor_cpu"), "x", 3)),
                  ("budget", _fmt(r.get("budget_factor"), "x")), ("pass", _fmt(r.get("pass"))),
                  ("batch path real-time factor", _fmt(_get(r, "batch", "realtime_factor"), "x", 3)),
                  ("trajectory sha256", _fmt(_get(r, "trajectory", "sha256")))]
                 # each stage's time a tick at its median: less moved by other processes than the factors
                 + [(f"stage {name} p50", _fmt(st["per_tick_us"]["p50"], "us", 3))
                    for name, st in sorted((r.get("stages") or {}).items(), key=lambda kv: _stage_order(kv[0]))
                    if isinstance(st, dict) and (st.get("per_tick_us") or {}).get("p50")])


SIM_STAGES = ("stylus", "map", "kinematics", "pybullet_step", "physics_other", "cable_sensor", "robot_io", "estimate",
              "render", "write", "record", "loop_other")  # teleop bench sim's stages in the data flow's order


def _stage_order(name: str) -> int:
    return SIM_STAGES.index(name) if name in SIM_STAGES else len(SIM_STAGES)


def _rates(s: dict | None, prefix: str = "") -> list[Row]:
    if not isinstance(s, dict):
        return []
    pct = lambda v: None if v is None else f"{100 * v:.1f} %"  # noqa: E731
    return _rows([(f"{prefix}cases (with an effect / clean)",
                   _fmt(f"{s.get('cases')} ({s.get('effect_cases')} / {s.get('clean_cases')})")
                   if "cases" in s else None),
                  (f"{prefix}right effect named first", pct(s.get("named_first_rate"))),
                  (f"{prefix}`none` on clean cases", pct(s.get("none_rate"))),
                  (f"{prefix}parameters within 20 %", pct(s.get("params_within_20pct_rate"))),
                  (f"{prefix}held-out improvement >= 2x", pct(s.get("improved_2x_rate"))),
                  (f"{prefix}lowest held-out improvement", _fmt(s.get("improvement_min"), "x", 3)),
                  (f"{prefix}physics <= PySINDy", _fmt(s.get("model_le_sindy")))])


def diagnose_rows(r: dict) -> list[Row]:
    rows = _rates(r.get("summary"))
    if r.get("generator"):
        rows += _rates(r["generator"], "generator: ")
    if isinstance(r.get("rig"), dict) and r["rig"].get("all"):
        rows += _rates(r["rig"]["all"], "single-cable bench: ")
    return rows


def session_diagnose_rows(r: dict) -> list[Row]:
    effects = ", ".join(e.get("effect", "?") for e in r.get("effects", []))
    found = ", ".join(f"{f.get('effect')} (x{f.get('improvement', 0):.3g})" for f in r.get("found", []))
    replay = r.get("replay_rmse_N") or {}
    return _rows([("switched on", _fmt(effects or None)), ("found on the motor force", _fmt(found or None)),
                  ("recovered parameters", _fmt("; ".join(
                      f"{eff} " + ", ".join(f"{k} {v:.4g}" for k, v in sorted(ps.items()))
                      for eff, ps in sorted(r["recovered"].items()))) if r.get("recovered") else None),
                  ("column subsets naming every switched-on effect",
                   _fmt(f"{sum(1 for s in r['subsets'] if s.get('named'))} of {len(r['subsets'])}")
                   if isinstance(r.get("subsets"), list) and r["subsets"] else None),
                  ("replay RMSE as recorded / plain / identified",
                   _fmt(" / ".join(f"{replay[k]:.3g}" for k in ("as_recorded", "plain", "identified")
                                   if k in replay) + " N") if replay else None),
                  ("shrink (plain / identified)", _fmt(r.get("shrink"), "x", 3)), ("pass", _fmt(r.get("pass")))])


def blind_jnd_rows(r: dict) -> list[Row]:
    rows = [("participants per point", _fmt(r.get("participants")))]
    for pt in r.get("points", []):
        lo, hi = pt.get("ci95", (None, None))
        rows.append((f"fully correct at JND {100 * pt['jnd']:.0f} %",
                     f"{pt['correct_ranking_rate']:.2f} (95 % CI {lo:.2f}-{hi:.2f})"))
    return _rows(rows)


FIG9_SIDES = {"distal_change_N": "FSR at B", "tension_B_change_N": "true tension at B",
              "proximal_change_N": "motor side"}
FIG11_MOTIONS = {"b": "sine", "c": "sum of two sines"}
ESTIMATORS = ("fsr_raw", "non_compensated", "single", "double", "flat_transitions")


def cable_rows(r: dict) -> list[Row]:
    rows: list[Row] = [("friction mu, bend B-D", _fmt(r.get("mu_BD"), "", 3)),
                       ("friction mu, A-B", _fmt(r.get("mu_AB"), "", 3))]
    exp = r.get("experiment")
    if exp == "fig9":
        for theta, c in (r.get("cases") or {}).items():
            for key, side in FIG9_SIDES.items():
                ours, seed = c.get(key), _get(c, "seed", key)
                if isinstance(ours, (int, float)):
                    paper = f" (seed 000: {seed:.3g} N)" if isinstance(seed, (int, float)) else ""
                    rows.append((f"bend {theta} deg, {c.get('pretension_N', '?')} N: high-low change, {side}",
                                 f"{ours:.3g} N{paper}"))
    elif exp == "fig11":
        for case, c in (r.get("cases") or {}).items():
            if not isinstance(c, dict):
                continue
            where = f"{FIG11_MOTIONS.get(c.get('motion'), case)}, A-B {c.get('AB_deg', '?')} deg"
            for est in ESTIMATORS:
                e = c.get(est)
                if isinstance(e, dict) and "rmse_N" in e:
                    rows.append((f"{where}: {est.replace('_', ' ')}, error RMSE / max",
                                 f"{e['rmse_N']:.3g} / {e.get('max_abs_N', float('nan')):.3g} N"))
    elif exp == "fig13":
        for w, p in (r.get("pretensions") or {}).items():
            cases = p.get("cases") or {}
            for est in ESTIMATORS:
                e = cases.get(est)
                if isinstance(e, dict) and "rmse_N" in e:
                    ptp = e.get("peak_to_peak_moving_N")
                    rows.append((f"pretension {w} N: {est.replace('_', ' ')}, RMSE / peak-to-peak",
                                 f"{e['rmse_N']:.3g} / {ptp:.3g} N" if ptp is not None else f"{e['rmse_N']:.3g} N"))
    return _rows(rows)


def feedforward_rows(r: dict) -> list[Row]:
    sessions = r.get("sessions") or r.get("recordings") or {}
    rows = [("play width", _fmt(r.get("backlash_mm"), "mm")),
            ("feed-forward width", _fmt(_get(r, "compensation", "width_mm"), "mm", 3))]
    order = ("plain", "compensated", "no_play")
    for name in sorted(sessions, key=lambda n: order.index(n) if n in order else len(order)):
        err = sessions[name].get("tip_error_mm") or {}
        if "rms" in err:
            rows.append((f"tip error, {name.replace('_', ' ')}: RMS / p95 / max",
                         f"{err['rms']:.3g} / {err.get('p95', float('nan')):.3g} / "
                         f"{err.get('max', float('nan')):.3g} mm"))
    rows += [("RMS ratio (plain / compensated)", _fmt(r.get("ratio_rms"), "x", 3)), ("pass", _fmt(r.get("pass")))]
    return _rows(rows)


@dataclass(frozen=True)
class Bench:
    """One benchmark: its command (without --json), whether its figures are times, and its table."""

    name: str
    args: tuple[str, ...]
    timing: bool
    rows: Callable[[dict], list[Row]]
    what: str


BENCHES: tuple[Bench, ...] = (
    Bench("tick", ("teleop", "bench", "tick"), True, tick_rows,
          "one full loop tick, devices excluded, against a plain numpy/scipy/filterpy tick"),
    Bench("loop", ("teleop", "bench", "loop", "--seconds", "60"), True, loop_rows,
          "the paced loop with the simulated stylus and robot, recording on"),
    Bench("link", ("teleop", "bench", "link"), True, link_rows,
          "the Arduino link on the emulated firmware (simavr): round trip and watchdog stop"),
    Bench("sim", ("teleop", "bench", "sim", "--seconds", "10"), True, sim_rows,
          "the simulation unpaced: stylus, loop and pybullet robot, times real time"),
    Bench("sim-distributed", ("teleop", "bench", "sim", "--plant", "distributed"), True, sim_rows,
          "the simulation unpaced with the distributed tendon-sheath plant (six cables of 20 elements), times real "
          "time"),
    Bench("diagnose", ("teleop", "bench", "diagnose", "--cases", "40", "--seed", "1"), False, diagnose_rows,
          "diagnosis accuracy on generated recordings with a concealed effect"),
    Bench("session-diagnose", ("teleop", "bench", "session-diagnose", "--effect", "coulomb_friction:Fc=0.3",
                               "--seconds", "20", "--seed", "1"), False, session_diagnose_rows,
          "a friction switched on in the simulated robot, found in a recorded session and handed back"),
    Bench("blind-jnd", ("teleop", "bench", "blind-jnd"), False, blind_jnd_rows,
          "the blind test's correct-ranking share against the participants' stiffness JND"),
    Bench("cable-fig9", ("teleop", "bench", "cable", "--experiment", "fig9"), False, cable_rows,
          "seed 000 Fig 9: the single-cable bench's tension change with the bend (docs/papers.md)"),
    Bench("cable-fig11", ("teleop", "bench", "cable", "--experiment", "fig11"), False, cable_rows,
          "seed 000 Fig 11: a spring load, sensed force against the force sensor's truth"),
    Bench("cable-fig13", ("teleop", "bench", "cable", "--experiment", "fig13"), False, cable_rows,
          "seed 000 Fig 13: no load, the sensed force whose truth is zero"),
    Bench("feedforward", ("teleop", "bench", "feedforward", "--seconds", "10", "--seed", "0"), False,
          feedforward_rows, "tip tracking error on the robot with backlash, without and with the feed-forward"),
)
BY_NAME = {b.name: b for b in BENCHES}


def machine() -> dict:
    """nproc, the CPU model (from /proc/cpuinfo where there is one) and the Python version."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"nproc": os.cpu_count(), "cpu": cpu, "python": platform.python_version()}


def _load() -> float | None:
    """The 1-minute load average (None where the system has none)."""
    return round(os.getloadavg()[0], 2) if hasattr(os, "getloadavg") else None


def run(names: list[str]) -> int:
    """Run each named bench with --json and write its wrapped result to docs/benchmarks/<name>.json."""
    DATA.mkdir(parents=True, exist_ok=True)
    status = 0
    for name in names:
        bench = BY_NAME[name]
        with tempfile.TemporaryDirectory(prefix="bench-") as tmp:
            out = Path(tmp) / "result.json"
            argv = [*bench.args, "--json", str(out)]
            print(f"[{name}] {shlex.join(bench.args)}", flush=True)
            date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
            load0 = _load()
            proc = subprocess.run(argv, cwd=REPO, stdout=subprocess.DEVNULL)
            if proc.returncode != 0 or not out.exists():
                print(f"[{name}] failed (exit {proc.returncode}); nothing written", file=sys.stderr)
                status = 1
                continue
            result = json.loads(out.read_text())
        record = {"command": shlex.join(bench.args), "date": date, "machine": machine(), "result": result}
        if load0 is not None:  # the machine's load around the run: other processes sharing the cores
            record["load"] = [load0, _load()]
        (DATA / f"{name}.json").write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
    return status


def render_table(bench: Bench, record: dict) -> str:
    """One benchmark's section: what it measures, its figures as a table, then command, machine and date."""
    m = record.get("machine", {})
    lines = [f"## {bench.name}", "", bench.what[0].upper() + bench.what[1:] + ".", "", "| figure | value |", "|---|---|"]
    lines += [f"| {label} | {value} |" for label, value in bench.rows(record["result"])]
    lines += ["", f"Command: `{record['command']} --json F`; machine: {m.get('nproc')} cores, {m.get('cpu')}, "
                  f"Python {m.get('python')}; date: {record['date']}"
              + (f"; load average (1 min) {record['load'][0]:g} before, {record['load'][1]:g} after" if "load" in record
                 else "") + ".", ""]
    return "\n".join(lines)


def render(data: Path = DATA, page: Path = PAGE) -> str:
    """docs/benchmarks.md from the JSON files in `data`; returns the text written."""
    parts = ["# Benchmarks", "",
             "Generated by `python scripts/benchmarks.py render` from docs/benchmarks/*.json, which "
             "`python scripts/benchmarks.py run [NAME ...]` writes; do not edit by hand. Times depend on the "
             "machine and its load: each table says where and when it was measured. The JSON keys of every "
             "bench are in [formats.md](formats.md); the papers behind \"seed 000 / 001 / 002\" in "
             "[papers.md](papers.md).", ""]
    missing = []
    for bench in BENCHES:
        path = data / f"{bench.name}.json"
        if not path.exists():
            missing.append(bench)
            continue
        parts.append(render_table(bench, json.loads(path.read_text())))
    if missing:
        parts += ["## Not yet run", ""]
        parts += [f"- {b.name}: `{shlex.join(b.args)} --json F` ({b.what})" for b in missing]
        parts.append("")
    text = "\n".join(parts)
    page.write_text(text)
    return text


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="action", required=True)
    r = sub.add_parser("run", help="run benches into docs/benchmarks/<name>.json")
    r.add_argument("names", nargs="*", metavar="NAME", help="bench names (default: all); see `list`")
    r.add_argument("--no-timing", action="store_true", help="only the benches whose figures are not times")
    sub.add_parser("render", help="write docs/benchmarks.md from docs/benchmarks/*.json")
    sub.add_parser("list", help="the bench names and commands")
    args = p.parse_args(argv)
    if args.action == "list":
        for b in BENCHES:
            print(f"{b.name:18} {'time ' if b.timing else 'value'}  {shlex.join(b.args)}")
        return 0
    if args.action == "render":
        render()
        return 0
    unknown = [n for n in args.names if n not in BY_NAME]
    if unknown:
        p.error(f"unknown bench {', '.join(unknown)}; one of {', '.join(BY_NAME)}")
    names = args.names or [b.name for b in BENCHES if not (args.no_timing and b.timing)]
    return run(names)


if __name__ == "__main__":
    sys.exit(main())
