"""`teleop bench loop`: the paced master-slave loop's timing (JSON keys: docs/formats.md), recording on by default.

    teleop bench loop --seconds 60 --rate 1000 --json loop.json --plot loop.png
    teleop bench loop --find-max-rate --seconds 10 --json maxrate.json

Besides the loop-timing keys the JSON has "period_us" (mean, p50, p99, p999, max, min of the tick-to-tick
period), "period_histogram" (bins of T/20 over [0, 3 T) and an overflow count), printed as a text histogram,
and "budget": the timing budget of docs/safety.md (<= 0.1 % of ticks more than 0.5 ms late, skipped deadlines
counted). The check is conclusive only with `--seconds 60` (or more) at `--rate 1000` with recording on;
the default 10 s run prints PASS/FAIL marked "not conclusive" and why. The exit code is 0 either way
(a benchmark, not a test). `--plot F` writes the period histogram as a PNG.
"""

from __future__ import annotations

import os
import signal
import tempfile

import numpy as np

from teleop.apps.argtypes import (LOOP_RATE_HZ, ROBOT_RATE_HZ, SESSION_SECONDS, add_geometry_option, geometry_of,
                                  nonnegative_float, positive_float, rt_priority)
from teleop.apps.commands.session import add_live_arguments
from teleop.core.errors import InputError
from teleop.core.mapping import POKE_WORKSPACE_MAX, MappingParams
from teleop.io.outputs import save_figure, write_json
from teleop.io.stop_signals import STOP, exit_code
from teleop.loop.live.server import check_port
from teleop.loop.params import LoopParams
from teleop.loop.session import run_session
from teleop.loop.timing import budget_verdict, default_spin_us, format_histogram

MISS_FRACTION = 0.001  # <= 0.1 % of ticks more than 0.5 ms late (docs/safety.md)


def register(subparsers) -> None:
    p = subparsers.add_parser("loop", help="loop timing: lateness, tick and per-stage times (recording on)")
    p.add_argument("--seconds", type=SESSION_SECONDS, default=10.0)
    p.add_argument("--rate", type=LOOP_RATE_HZ, default=1000.0)
    p.add_argument("--json", metavar="F", help="write the loop JSON (keys: docs/formats.md)")
    p.add_argument("--plot", metavar="F", help="write the period histogram as a PNG")
    p.add_argument("--haptic", default="sim://?script=pokes")
    p.add_argument("--robot", default="sim://robot?substeps=2",
                   help="robot URL (default: the pybullet slave, 2 physics steps of 1 ms per reading)")
    p.add_argument("--record", metavar="FILE", help="keep the recording here (default: a temporary file)")
    p.add_argument("--no-record", action="store_true", help="benchmark without the recorder")
    p.add_argument("--spin-us", type=nonnegative_float, default=None,
                   help="spin this long before each deadline [us] (default: 200, at most half the period)")
    p.add_argument("--stale-ms", type=positive_float, default=20.0,
                   help="telemetry older than this is a FAULT [ms] (default 20; docs/safety.md)")
    p.add_argument("--no-realtime", action="store_true", help="do not ask for SCHED_FIFO")
    add_geometry_option(p)
    p.add_argument("--robot-rate", type=ROBOT_RATE_HZ, default=500.0, help="robot process rate [Hz] (default 500)")
    p.add_argument("--robot-rt", type=rt_priority, default=45,
                   help="SCHED_FIFO priority of the robot process, below the loop's 50 (0: time-sharing, nice -10)")

    add_live_arguments(p)
    p.add_argument("--find-max-rate", action="store_true",
                   help="run --seconds at increasing rates; report the highest with <= 0.1 %% misses")
    p.set_defaults(func=run)




def rt_throttle() -> float | None:
    """The fraction of each period real-time tasks may run (sched_rt_runtime_us / sched_rt_period_us;
    None where unknown, 1.0 when unlimited)."""
    try:
        with open("/proc/sys/kernel/sched_rt_runtime_us") as f:
            run_us = int(f.read())
        with open("/proc/sys/kernel/sched_rt_period_us") as f:
            per_us = int(f.read())
    except (OSError, ValueError):
        return None
    return 1.0 if run_us < 0 else run_us / per_us


def bench_once(args, rate: float) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        record = None if args.no_record else (args.record or os.path.join(tmp, "bench.mcap"))

        params = LoopParams(rate_hz=rate, stale_limit=args.stale_ms * 1e-3,
                            mapping=MappingParams(workspace_max=POKE_WORKSPACE_MAX))
        spin_us = default_spin_us(rate) if args.spin_us is None else args.spin_us
        res = run_session(args.haptic, args.robot, args.seconds, record=record, params=params,
                          spin_us=spin_us, realtime=not args.no_realtime, robot_rt_priority=args.robot_rt or None,
                          robot_process_hz=args.robot_rate,
                          live=(args.live_host, args.live) if args.live is not None else None,
                          progress=f"bench loop {rate:g} Hz", geometry=geometry_of(args),
                          geometry_file=args.geometry)
    out = dict(res.timing)
    out["live"] = res.live or {"on": False}
    out["recording"] = {"on": record is not None, "drops": res.drops, "alarm": res.alarm}
    out["final_state"] = res.final_state
    out["fault_reason"] = res.fault_reason
    out["scheduling"] = res.scheduling
    out["interrupted"] = res.interrupted or False  # "SIGINT", "SIGTERM", "SIGHUP" when a signal ended the run
    # what the pacing costs the core: spinning plus the median tick, against the real-time throttle's share
    out["spin_us"] = spin_us
    out["busy_fraction_p50"] = round((spin_us + out["tick_us"]["p50"]) * rate * 1e-6, 4)
    out["rt_throttle"] = rt_throttle()
    out["budget"] = budget_verdict(out, args.seconds, record is not None)
    out["miss_fraction"] = out["budget"]["miss_fraction"]
    return out


def verdict_line(budget: dict) -> str:
    """One line: PASS/FAIL against the budget, and whether the run could decide it."""
    word = "PASS" if budget["pass"] else "FAIL"
    tail = "" if budget["conclusive"] else f" (not conclusive: {'; '.join(budget['why_not'])})"
    return f"budget {budget['criterion']}: {word}, {100 * budget['miss_fraction']:.3f} % late{tail}"


def plot_histogram(out: dict, path: str) -> None:
    """PNG of the period histogram (log count) with the nominal period and the late threshold (half a period)."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    h = out["period_histogram"]
    edges = np.asarray(h["edges_us"])
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.bar(edges[:-1], h["counts"], width=h["bin_us"], align="edge", log=True, color="tab:blue",
           label=f"{out['ticks']} ticks")
    if h["overflow"]:
        ax.bar(edges[-1], h["overflow"], width=h["bin_us"], align="edge", log=True, color="tab:red",
               label=f">= {edges[-1]:g} us: {h['overflow']}")
    ax.axvline(h["nominal_us"], color="k", lw=0.8, label="nominal period")
    late = out["late_threshold_us"]
    ax.axvline(h["nominal_us"] + late, color="tab:red", ls="--", lw=0.8, label=f"+{late:g} us (half a period)")
    ax.set_xlabel("tick-to-tick period [us]")
    ax.set_ylabel("ticks [count]")
    rec = "recording on" if out.get("recording", {}).get("on") else "recording off"
    ax.set_title(f"teleop bench loop: tick-to-tick period of the {out['rate_hz']:g} Hz loop, {rec}\n" +
                 verdict_line(out["budget"]).split(":")[0] + ": " +
                 ("PASS" if out["budget"]["pass"] else "FAIL") +
                 ("" if out["budget"]["conclusive"] else " (not conclusive)"), fontsize=8)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside: off the bars
    save_figure(fig, path)


def run(args) -> int:
    if not args.seconds > 0 or not args.rate > 0:
        raise InputError("--seconds and --rate must be > 0")
    if args.live is not None:
        check_port(args.live_host, args.live)
    geometry_of(args)  # a bad --geometry is one line before any run
    with STOP.polled():  # a stop signal ends the run under way; what ran is reported, marked interrupted
        return _run(args)


def _run(args) -> int:
    if not args.find_max_rate:
        out = bench_once(args, args.rate)
        if args.json:  # first: a terminal gone (SIGHUP) may fail the prints below
            write_json(args.json, out)
        la = out["lateness_us"]
        print(f"loop {out['rate_hz']:g} Hz, {out['ticks']} ticks: lateness p50 {la['p50']} us, p99 {la['p99']} us, "
              f"p99.9 {la['p999']} us, max {la['max']} us; misses {out['deadline_misses']} "
              f"({100 * out['miss_fraction']:.3f} %); tick p50 {out['tick_us']['p50']} us; {out['scheduling']}; "
              f"final state {out['final_state']}")
        print(f"spin {out['spin_us']:g} us before each deadline: the loop keeps its core busy "
              f"{100 * out['busy_fraction_p50']:.0f} % of the time (p50 tick)"
              + (f"; real-time tasks may use {100 * out['rt_throttle']:.0f} % of each second"
                 if out["rt_throttle"] is not None else ""))
        for name, st in out["stages_us"].items():
            print(f"  {name:9s} p50 {st['p50']:8.1f} us  p99 {st['p99']:8.1f} us")
        res_live = out["live"]
        if res_live.get("port") is not None:
            print(f"live view: {res_live['frames_sent']} frames sent, {res_live['frames_dropped']} dropped, "
                  f"{res_live['rows_skipped']} ticks skipped, {res_live['viewers']} viewers at the end")
        pe = out["period_us"]
        print(f"period mean {pe['mean']} us, p99 {pe['p99']} us, p99.9 {pe['p999']} us, max {pe['max']} us, "
              f"min {pe['min']} us")
        print(format_histogram(out["period_histogram"]))
        print(verdict_line(out["budget"]))
        if args.plot:
            plot_histogram(out, args.plot)
        return exit_code(signal.Signals[out["interrupted"]]) if out["interrupted"] else 0
    trials = []
    best = None
    for rate in (1000.0, 1500.0, 2000.0, 3000.0, 4000.0, 5000.0, 6000.0, 8000.0):
        out = bench_once(args, rate)
        ok = out["miss_fraction"] <= MISS_FRACTION
        trials.append({"rate_hz": rate, "miss_fraction": out["miss_fraction"], "ok": ok,
                       "late_threshold_us": out["late_threshold_us"], "lateness_us": out["lateness_us"],
                       "tick_us": out["tick_us"], "final_state": out["final_state"]})
        print(f"{rate:6.0f} Hz: misses {100 * out['miss_fraction']:.3f} %, tick p50 {out['tick_us']['p50']} us, "
              f"final {out['final_state']} -> {'ok' if ok else 'FAIL'}")
        if out["interrupted"]:
            break  # this rate's run was cut short: neither ok nor a failure of the rate
        if ok:
            best = rate
        elif out["miss_fraction"] > 0.5:
            break  # far past the limit: faster rates only miss more
    interrupted = out["interrupted"]
    res = {"max_rate_hz": best, "criterion": "<= 0.1 % ticks more than half a period late (skipped ticks count)",
           "trials": trials, "interrupted": interrupted}
    if args.json:
        write_json(args.json, res)
    print(f"highest sustained rate: {best} Hz" + (f" (interrupted by {interrupted})" if interrupted else ""))
    return exit_code(signal.Signals[interrupted]) if interrupted else 0
