"""`teleop bench link [--roundtrips N] [--trials N] [--kill-trials N] [--close-trials N] [--json F]`: the
Arduino link on the real firmware.

Builds the Mega2560 firmware and the simavr harness (into ~/.cache/cdpr-teleop/arduino, or --build-dir),
runs the firmware emulated at 16 MHz behind a pseudo-terminal, and measures through pyserial at 1 Mbaud:
- round trip HEARTBEAT (8 bytes) -> TELEMETRY (30 bytes), one per millisecond, wall clock [ms], and the
  firmware's part of it on the emulated clock (request delimiter in -> reply delimiter out) [ms];
- a loop-like stream: one COMMAND + read() per 1 ms tick: fresh readings, reading age, firmware counters;
- watchdog: host silent -> last step pulse, on the emulated clock [ms]: the loop paused (--trials episodes
  on one connection), the host process SIGKILLed mid-motion (--kill-trials, a new process each) and the
  port closed without a STOP (--close-trials, a new connection each) (devices/arduino/trials.py).
JSON: {"roundtrips", "rtt_ms": {"p50","p99","max"}, "firmware_turnaround_ms": {"p50","p99","max"}, "stream_1khz": {...}, "trials",
"watchdog_stop_ms": {"max","mean","min"}, "early_trips", "host_silence": {"paused"|"killed"|"closed": {"trials",
"stop_ms": {"max","mean","min"}, "within_50ms", "latched", "early_trips"}}, "link_bytes_per_tick",
"link_fraction_of_1ms", "firmware", "host_link": {...}} (the top-level "trials"/"watchdog_stop_ms"/"early_trips" are the
paused episodes).
Wall-clock numbers depend on the machine's load (the emulator shares the CPU); nothing is asserted.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from devices.arduino import build, messages as msg
from devices.arduino.robot import ArduinoRobot
from devices.arduino.simulator import EmulatedMega
from devices.arduino.trials import close_trials, kill_trials, round_trips, stream, watchdog_trials
from teleop.apps.argtypes import positive_float, positive_int
from teleop.core.errors import InputError
from teleop.io.outputs import dumps_json, write_json


def register(subparsers) -> None:
    p = subparsers.add_parser("link", help="Arduino link on the emulated firmware: round trip, watchdog stop time")
    p.add_argument("--roundtrips", type=positive_int, default=2000, help="timed round trips (default 2000)")
    p.add_argument("--trials", type=positive_int, default=100, help="watchdog silence episodes (default 100)")
    p.add_argument("--kill-trials", type=positive_int, default=100,
                   help="host processes SIGKILLed mid-motion (default 100)")
    p.add_argument("--close-trials", type=positive_int, default=100,
                   help="ports closed mid-motion without a STOP (default 100)")
    p.add_argument("--stream-seconds", type=positive_float, default=5.0,
                   help="seconds of a 1 kHz COMMAND + read() stream (default 5)")
    p.add_argument("--build-dir", metavar="DIR", help="build directory (default ~/.cache/cdpr-teleop/arduino)")
    p.add_argument("--json", metavar="F", help="write the result JSON here")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.roundtrips < 10 or args.trials < 1:
        raise InputError("bench link: --roundtrips must be >= 10 and --trials >= 1")
    try:
        out = Path(args.build_dir) if args.build_dir else None
        elf, harness = build.build_firmware(out), build.build_harness(out)
    except build.ToolchainMissing as exc:
        raise InputError(f"bench link: {exc}") from None
    home = np.full(6, 0.030)
    with EmulatedMega(harness, elf) as mega, ArduinoRobot(mega.port, timeout_s=1.0) as robot:
        robot.home(home)
        robot.diag()
        streamed = stream(robot, home, seconds=args.stream_seconds)
        stream_diag = robot.diag()
        robot.enable()
        rtt = round_trips(robot, args.roundtrips) * 1e3
        turnaround = np.array(mega.turnaround_s()[-args.roundtrips:]) * 1e3
        wd = watchdog_trials(robot, mega, home, n=args.trials, max_attempts=3 * args.trials)
        diag = robot.diag()
        version = robot.hello.version_string
        stats = robot.stats
        robot.close()  # the kill and close episodes each open the port themselves
        killed = kill_trials(mega, home, n=args.kill_trials, seed=0, max_attempts=3 * args.kill_trials)
        closed = close_trials(mega, home, n=args.close_trials, max_attempts=3 * args.close_trials)
    wire = msg.wire_size(msg.MsgType.COMMAND) + msg.wire_size(msg.MsgType.TELEMETRY)
    result = {
        "roundtrips": int(args.roundtrips),
        "rtt_ms": {"p50": float(np.percentile(rtt, 50)), "p99": float(np.percentile(rtt, 99)),
                   "max": float(rtt.max())},
        "firmware_turnaround_ms": {"p50": float(np.percentile(turnaround, 50)),
                                   "p99": float(np.percentile(turnaround, 99)), "max": float(turnaround.max())},
        "stream_1khz": {"ticks": streamed.ticks, "fresh_fraction": streamed.fresh / streamed.ticks,
                        "reading_age_ms": {"p50": float(np.percentile(streamed.age_ms, 50)),
                                           "p99": float(np.percentile(streamed.age_ms, 99))},
                        "late_ticks": streamed.late_ticks, "watchdog_trips": streamed.watchdog_trips,
                        "firmware_counters": stream_diag.counters},
        "trials": int(args.trials),
        "watchdog_stop_ms": {"max": float(wd.stop_ms.max()), "mean": float(wd.stop_ms.mean()),
                             "min": float(wd.stop_ms.min())},
        "early_trips": int(wd.early_trips),
        "host_silence": {what: silence_summary(r) for what, r in (("paused", wd), ("killed", killed),
                                                                    ("closed", closed))},
        "link_bytes_per_tick": int(wire),
        "link_fraction_of_1ms": wire * 10 / 1e6 / 1e-3,
        "firmware": {"version": version, "handle_max_us": int(diag.handle_max_us), "counters": diag.counters},
        "host_link": {"frames": stats.frames, "gaps": stats.gaps, "duplicates": stats.duplicates,
                      "reordered": stats.reordered, "timeouts": stats.timeouts, "errors": stats.errors},
    }
    if args.json:
        write_json(args.json, result)
    print(dumps_json(result), end="")
    return 0


def silence_summary(result, bound_ms: float = 50.0) -> dict:
    """JSON view of a WatchdogTrials: stop times [ms, emulated], how many within bound_ms, latched, early trips."""
    stop = result.stop_ms
    return {"trials": int(stop.size),
            "stop_ms": {"max": float(stop.max()), "mean": float(stop.mean()), "min": float(stop.min())},
            "within_50ms": int(((stop >= 0) & (stop <= bound_ms) & (result.steps_after_silence > 0)).sum()),
            "latched": int(result.latched.sum()), "early_trips": int(result.early_trips)}
