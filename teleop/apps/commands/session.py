"""`teleop session`: run the master-slave loop between a stylus and a robot, recording everything."""

from __future__ import annotations

import argparse
import signal
import sys
from dataclasses import replace

from devices.wrappers import BacklashCompensatedRobot
from scenes.fsr_lab import robot_url_calibration
from teleop.apps.argtypes import (LOOP_RATE_HZ, ROBOT_RATE_HZ, SESSION_SECONDS, add_geometry_option, geometry_of,
                                   input_file, positive_float, rt_priority)
from teleop.core.control.feedforward import model_backlash_width
from teleop.core.errors import InputError
from teleop.core.mapping import POKE_WORKSPACE_MAX, MappingParams
from teleop.io.calfile import load_fsr
from teleop.io.calibration_csv import load_fsr_calibration
from teleop.io.model_io import load_model
from teleop.io.outputs import write_json
from teleop.io.stop_signals import STOP, exit_code
from teleop.loop.live.server import check_port
from teleop.loop.params import LOOP_RENDER, LoopParams
from teleop.loop.session import default_estimator, frame_period, is_simulated_stylus, loop_estimator, run_session


def register(subparsers) -> None:
    p = subparsers.add_parser("session", help="run teleoperation (stylus -> robot -> force feedback) and record it")
    p.add_argument("--haptic", default="sim://?script=pokes", help="stylus URL (default: simulated operator poking)")
    p.add_argument("--robot", default="sim://robot?substeps=2",
                   help="robot URL (default: the pybullet slave, 2 physics steps of 1 ms per reading)")
    p.add_argument("--record", metavar="FILE", help="record the session to FILE (.mcap)")
    p.add_argument("--seconds", type=SESSION_SECONDS, default=10.0,
                   help="session length [s] (default 10, at most 4 h)")
    p.add_argument("--rate", type=LOOP_RATE_HZ, default=1000.0, help="haptic loop rate [Hz] (default 1000)")
    p.add_argument("--robot-rate", type=ROBOT_RATE_HZ, default=500.0,
                   help="robot link rate [Hz]; the robot runs in its own process at this rate (default 500)")
    p.add_argument("--robot-rt", type=rt_priority, default=45,
                   help="SCHED_FIFO priority of the robot process, below the loop's 50 (0: time-sharing, nice -10)")
    p.add_argument("--robot-inline", action="store_true",
                   help="do the robot I/O inside the haptic tick instead (every tick)")
    p.add_argument("--motion-scale", type=float, default=None, help="robot displacement per stylus displacement")
    p.add_argument("--force-scale", type=float, default=1.0, help="stylus force per newton at the tip")
    p.add_argument("--zero-neg-z", action="store_true",
                   help="zero forces along -z of the stylus frame, i.e. toward the pad (seed 000 blind test)")
    p.add_argument("--passivity-damping", type=float, default=0.0, metavar="N_S_PER_M",
                   help="largest damping of the passivity observer/controller [N s/m] (default 0: off)")
    p.add_argument("--fsr-calibration", type=input_file, metavar="CSV|TOML",
                   help="FSR calibration for the estimator: a CSV (columns tension_N, conductance_uS, branch) or "
                        "the .toml of `teleop calibrate fsr` (default: the built-in synthetic calibration; on "
                        "sim://robot?plant=distributed the one fitted on that plant's calibration platform, "
                        "scenes.fsr_lab)")
    p.add_argument("--compensation", type=input_file, metavar="MODEL",
                   help="backlash feed-forward: a link model (JSON) with a backlash finding on its position link, "
                        "from `teleop diagnose REC --save-model MODEL` or hand-written (docs/feedforward.md); each "
                        "cable is commanded half the play ahead in its direction of motion, within v_max and the "
                        "length limits")
    add_geometry_option(p)
    p.add_argument("--stale-ms", type=positive_float, default=20.0,
                   help="telemetry older than this is a FAULT [ms] (default 20; docs/safety.md)")
    p.add_argument("--no-realtime", action="store_true", help="do not ask for SCHED_FIFO (loop 50, robot 45)")
    p.add_argument("--sim-clock", action="store_true",
                   help="tick on a simulated clock: tick k at k periods, as fast as the machine runs, so that the same "
                        "URLs and seeds record the same session on any machine and load (needs --robot-inline; "
                        "lateness is not measured)")
    p.add_argument("--json", metavar="F", help="write the timing summary and events as JSON")
    add_live_arguments(p)
    p.set_defaults(func=run)


def add_live_arguments(p) -> None:
    """--live [PORT] and --live-host (also used by `teleop bench loop` and `teleop blind-test`)."""
    p.add_argument("--live", type=port_number, nargs="?", const=8765, default=None, metavar="PORT",
                   help="serve the session live to Foxglove (WebSocket) on PORT (default 8765; 0: any free port)")
    p.add_argument("--live-host", default="127.0.0.1", metavar="HOST",
                   help="address the live view listens on (default 127.0.0.1; 0.0.0.0 exposes it on purpose)")


def port_number(text: str) -> int:
    """A TCP port 0..65535 (argparse type)."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number 0..65535, got {text!r}") from None
    if not 0 <= v <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port number 0..65535, got {v}")
    return v


def run(args) -> int:
    if not args.seconds > 0:
        raise InputError(f"--seconds must be > 0, got {args.seconds}")
    if args.record and not args.record.endswith(".mcap"):
        raise InputError(f"--record {args.record}: expected a file name ending in .mcap")
    if args.sim_clock and not args.robot_inline:
        raise InputError("--sim-clock needs --robot-inline (a robot process runs on the wall clock)")

    if args.sim_clock and not is_simulated_stylus(args.haptic):
        raise InputError(f"--sim-clock needs a simulated stylus (--haptic sim://...), got {args.haptic}")
    if args.live is not None:
        check_port(args.live_host, args.live)

    render = replace(LOOP_RENDER, scale=args.force_scale, zero_negative_z=args.zero_neg_z,
                     alpha_max=args.passivity_damping)
    params = LoopParams(rate_hz=args.rate, stale_limit=args.stale_ms * 1e-3, render=render,
                        mapping=MappingParams(workspace_max=POKE_WORKSPACE_MAX))
    if args.motion_scale is not None:
        params = replace(params, mapping=replace(params.mapping, motion_scale=args.motion_scale))

    # read before any device is opened or file written: a bad file leaves nothing
    geometry = geometry_of(args)
    if args.fsr_calibration and str(args.fsr_calibration).endswith(".toml"):
        cal = load_fsr(args.fsr_calibration)
    else:
        # no file: the built-in calibration, or on sim://robot?plant=distributed that plant's own (scenes.fsr_lab)
        cal = load_fsr_calibration(args.fsr_calibration) if args.fsr_calibration else robot_url_calibration(args.robot)
    wrapper = None
    if args.compensation:
        wrapper = compensation_wrapper(args.compensation, params.dt * params.robot_every)
    robot_hz = None if args.robot_inline else args.robot_rate
    estimator = default_estimator(frame_period(params, robot_hz), cal=cal, geometry=geometry)
    if "sensor=" in args.robot:  # sim://robot?sensor=fbg|one: the estimator reads that kind (loop_estimator)
        estimator = loop_estimator(args.robot, frame_period(params, robot_hz), cal, geometry) or estimator
    with STOP.polled():  # a stop signal ends the loop; the results below are written, marked interrupted
        res = run_session(args.haptic, args.robot, args.seconds, record=args.record, params=params,
                          estimator=estimator, robot_process_hz=robot_hz, realtime=not args.no_realtime,
                          robot_rt_priority=args.robot_rt or None,
                          live=(args.live_host, args.live) if args.live is not None else None,
                          robot_wrapper=wrapper, sim_clock=args.sim_clock, progress="session",
                          geometry=geometry, geometry_file=args.geometry)
        return report(args, res, wrapper)


def report(args, res, wrapper) -> int:
    """Write --json, print the session's summary; 0, or 128 + the signal's number when one ended it."""
    t = res.timing
    if args.json:  # first: a terminal gone (SIGHUP) may fail the prints below
        write_json(args.json, {"timing": t, "events": res.events, "final_state": res.final_state,
                               "scheduling": res.scheduling,
                               "fault_reason": res.fault_reason, "drops": res.drops, "alarm": res.alarm,
                               "live": res.live, "interrupted": res.interrupted or False,
                               "compensation": None if wrapper is None else
                               {"model": str(args.compensation), "backlash_width_mm": wrapper.width * 1e3}})
    if res.interrupted:
        print(f"session: INTERRUPTED ({res.interrupted}) after {t['ticks'] / t['rate_hz']:.3f} s of "
              f"{args.seconds:g} s")
    print(f"session: {t['ticks']} ticks at {t['rate_hz']:g} Hz, lateness p50/p99/max "
          f"{t['lateness_us']['p50']:.0f}/{t['lateness_us']['p99']:.0f}/{t['lateness_us']['max']:.0f} us, "
          f"{t['deadline_misses']} misses; final state {res.final_state}"
          + (f" ({res.fault_reason})" if res.fault_reason else "") + f"; {res.scheduling}")
    if wrapper is not None:
        print(f"compensation: backlash feed-forward of {wrapper.width * 1e3:.4g} mm per cable ({args.compensation})")
    for ev in res.events:
        print(f"  t={ev['t']:.3f} s  {ev['src']} -> {ev['dst']}" + (f": {ev['reason']}" if ev["reason"] else ""))
    if res.live:
        lv = res.live
        print(f"live view: {lv['frames_sent']} frames sent, {lv['frames_dropped']} dropped for slow viewers, "
              f"{lv['rows_skipped']} ticks skipped")
    if args.record:
        print(f"recorded {args.record}" + (f"; ALARM: {res.alarm}" if res.alarm else f", {res.drops} ticks dropped"))
    if res.alarm:
        print(f"teleop: warning: {res.alarm}", file=sys.stderr)
    if res.interrupted:
        closed = f"; {args.record} is closed and readable up to there" if args.record else ""
        print(f"teleop: interrupted ({res.interrupted}) after {t['ticks']} of "
              f"{round(args.seconds * t['rate_hz'])} ticks{closed}", file=sys.stderr)
        return exit_code(signal.Signals[res.interrupted])
    return 0


def compensation_wrapper(path, period: float):
    """robot -> devices.wrappers.BacklashCompensatedRobot with the backlash width of the link model at `path`
    (read now: a bad file is one line, before any device opens); `period` [s] between commands."""
    width = model_backlash_width(load_model(path), f"--compensation {path}")

    def wrap(robot, clock=None):
        return BacklashCompensatedRobot(robot, width, period, clock=clock)
    wrap.width = width  # [m]
    return wrap
