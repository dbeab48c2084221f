"""Wiring of a session: open the devices by URL, start the recorder process, run the paced loop, close.

Used by `teleop session` and `teleop bench loop`. The loop thread only copies numbers into the recorder's
shared-memory ring; the garbage collector is paused while the loop runs (a gen-2 collection would be a
multi-millisecond stall).
"""

from __future__ import annotations

import gc
import platform
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

from urllib.parse import parse_qs, urlparse

import numpy as np

import teleop
from scenes.fsr_lab import robot_url_calibration
from scenes.sensor_identification import identify_one_sensor_on
from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.sensor_reading import make_estimator
from teleop.core.geometry import Geometry, default_geometry, geometry_dict
from teleop.core.kinematics import pose2lengths
from teleop.io.recording import Recorder, Ring
from teleop.io.recording.sensors import TOPIC_FBG
from teleop.io.stop_signals import STOP
from teleop.loop.core import Teleop
from teleop.loop.devices_by_url import open_device, process_robot
from teleop.loop.live import LiveView
from teleop.loop.loop_progress import LoopProgress
from teleop.loop.params import LoopParams
from teleop.loop.sensor_tap import FbgTap, with_fbg_channel
from teleop.loop.tap import RowTap, numeric_extras, session_layout
from teleop.loop.timing import SimClock, TimingLog, run_paced, run_stepped, set_normal, set_realtime


@dataclass
class SessionResult:
    """What a session did: timing summary (bench JSON), state changes, final state, recording health."""

    timing: dict
    events: list = field(default_factory=list)
    final_state: str = ""
    fault_reason: str = ""
    drops: int = 0
    alarm: str = ""
    record: str | None = None
    scheduling: str = ""
    live: dict = field(default_factory=dict)  # the live view's counters (teleop.loop.live.LiveView.stats), if served
    interrupted: str = ""  # "SIGINT" (Ctrl-C), "SIGTERM" or "SIGHUP" when a signal ended the run before `seconds`


def software_version() -> str:
    """cdpr-teleop version plus the git commit when run from a checkout."""
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=2,
                             cwd=Path(teleop.__file__).parent).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        rev = ""
    return f"cdpr-teleop {teleop.__version__}" + (f" ({rev})" if rev else "")


def session_metadata(tp: Teleop, haptic_url: str, robot_url: str, seconds: float, seed: int | None,
                     geometry_file: str | None = None) -> dict:
    """Configuration, calibration, firmware and software versions of a session (stored in the recording): the
    geometry the loop ran on (SI, teleop.core.geometry.Geometry's fields) and the file it came from
    (`geometry_file`, None: the built-in seed robot)."""
    g = tp.geom
    robot = tp.robot
    return {
        "configuration": {"haptic": haptic_url, "robot": robot_url, "seconds": seconds, "seed": seed,
                          "loop": tp.params.as_dict(),
                          "geometry": geometry_dict(g),
                          "geometry_file": None if geometry_file is None else str(geometry_file),
                          "haptic_spec": vars(tp.haptic.spec) if hasattr(tp.haptic.spec, "__dict__") else
                          str(tp.haptic.spec),
                          "robot_spec": vars(robot.spec) if hasattr(robot.spec, "__dict__") else str(robot.spec),
                          "compensation": getattr(robot, "compensation", None)},
        "calibration": tp.estimator.describe(),
        "firmware_version": str(getattr(robot, "firmware_version", None) or f"n/a ({type(robot).__name__})"),
        "software_version": software_version(),
        "platform": f"{platform.python_implementation()} {platform.python_version()} {platform.machine()}",
        "start_time_ns": time.time_ns(),
    }


PAD_COLORS = ((0.85, 0.85, 0.8, 0.9), (0.9, 0.4, 0.4, 0.9), (0.4, 0.7, 0.9, 0.9), (0.5, 0.85, 0.5, 0.9),
              (0.9, 0.75, 0.3, 0.9))


def pad_scene(robot) -> list:
    """The pad of a simulated robot (scenes.sim_robot.SimRobot: `.pad`, `.params.world.surface_z`) as the live
    view's scene pads: the pad body (filling z in [surface_z, surface_z + thickness], scenes.world) and each
    region as a thin patch on its surface, coloured by material. [] for a robot without a pad."""
    pad = getattr(robot, "pad", None)
    world = getattr(getattr(robot, "params", None), "world", None)
    if pad is None or world is None:
        return []
    z = float(world.surface_z)
    colors = {}

    def color(material):
        return colors.setdefault(material, PAD_COLORS[len(colors) % len(PAD_COLORS)])
    out = [{"name": pad.name, "center": (0.0, 0.0, z + pad.thickness / 2), "size": (pad.size, pad.size),
            "outline": pad.outline, "thickness": pad.thickness, "color": color(pad.background)}]
    for i, r in enumerate(pad.regions):
        size = (2 * r.size[0], 2 * r.size[0]) if r.shape == "disc" else (2 * r.size[0], 2 * r.size[1])
        out.append({"name": f"{pad.name}/{r.label or i}", "center": (r.centre[0], r.centre[1], z - 0.0003),
                    "size": size, "outline": "disc" if r.shape == "disc" else "square", "thickness": 0.0005,
                    "color": color(r.material)})
    return out


def _start_live(tp, layout, extras, recorder, live: tuple, scene: dict | None):
    """Start the live view on the recorder's ring (or a ring of its own, overwritten when no one records)."""
    if recorder is not None:
        ring = recorder.ring
    else:
        ring = Ring(layout.width, 4096, gated=False)
        tp.tap = session_tap(layout, ring.push, extras, tp.estimator)
    g = tp.geom
    # home lengths and steps per metre turn the motors' steps into the lengths they measure
    spec = getattr(tp.robot, "spec", None)
    geometry = {"B": g.B.tolist(), "r": g.r.tolist(),
                "L_home": np.asarray(pose2lengths(np.asarray(tp.params.mapping.home, dtype=float), g)).tolist(),
                "steps_per_m": float(getattr(spec, "steps_per_m", 0.0) or 0.0)}
    view = LiveView(layout, ring, host=live[0], port=live[1],
                    scene={"geometry": geometry, **(scene or {})}).start()
    if view.failed:
        view.close()
        return None
    print(f"live view: ws://{live[0]}:{view.port} (Foxglove WebSocket)", flush=True)
    on_event = tp.on_event

    def both(ev):
        if on_event is not None:
            on_event(ev)
        view.event(vars(ev))
    tp.on_event = both
    return view


def session_tap(layout, push, extras: dict, estimator):
    """The session's Teleop.tap: a RowTap on `layout`, behind an FbgTap when the layout has the FBG channel
    (teleop.loop.sensor_tap.with_fbg_channel for an estimator of the FBG sensor kinds)."""
    tap = RowTap(layout, push, extras)
    return FbgTap(tap, layout, estimator) if TOPIC_FBG in layout.topics() else tap


def frame_period(params: LoopParams, robot_process_hz: float | None) -> float:
    """Period [s] of the robot frames the estimator sees: the robot process's rate, or every robot_every ticks."""
    return max(params.dt, 1.0 / robot_process_hz) if robot_process_hz else params.dt * params.robot_every


def default_estimator(frame_dt: float, cal=None, geometry: Geometry | None = None):
    """The session's estimator: "dynamic" on `geometry` (None: the seed robot's) with its Kalman gain designed
    for `frame_dt` [s]."""
    return ReadingEstimator(geometry or default_geometry(), "dynamic", cal=cal, kalman=KalmanNoise(dt=frame_dt))


def loop_estimator(robot_url: str, frame_dt: float, cal=None, geometry: Geometry | None = None):
    """The loop's estimator for a `sim://robot?sensor=fbg|one` URL ("dynamic" name, Kalman gain for
    `frame_dt` [s], FSR calibration `cal` for one's proximal tensions; for one, Kp and Kr identified on the
    URL's robot, scenes.sensor_identification.identify_one_sensor_on), the robot built on `geometry` (None: the
    seed robot); None for any other URL or sensor=fsr (the FSR estimator serves)."""
    u = urlparse(robot_url)
    if (u.scheme, u.netloc) != ("sim", "robot") or parse_qs(u.query).get("sensor", ["fsr"])[-1] == "fsr":
        return None
    p = open_device(robot_url, geometry=geometry).params  # built, not opened: the URL's checked options
    kw = {"model": identify_one_sensor_on(p, 0, p.fbg_cable), "cable": p.fbg_cable} if p.sensor == "one" else {}
    return make_estimator(p.geometry, p.sensor, "dynamic", cal=cal, kalman=KalmanNoise(dt=frame_dt), **kw)


def is_simulated_stylus(url: str) -> bool:
    """True for a `sim://` stylus URL (devices.simulated), the one device that can run on a simulated clock."""
    return url == "sim://" or url.startswith(("sim://?", "sim://#"))


def run_session(haptic_url: str, robot_url: str, seconds: float, record: str | None = None,
                params: LoopParams | None = None, estimator=None, seed: int | None = None,
                spin_us: float | None = None, flush_interval: float = 0.1, haptic=None, robot=None,
                robot_process_hz: float | None = 1000.0, realtime: bool = True,
                robot_rt_priority: int | None = None, live: tuple | None = None,
                live_scene: dict | None = None, robot_wrapper=None, sim_clock: bool = False,
                progress: str = "", geometry: Geometry | None = None,
                geometry_file: str | None = None) -> SessionResult:
    """Run one paced session; `haptic`/`robot` may be given as device objects instead of URLs.

    With `robot_process_hz` (default) the robot runs in its own process at that rate (devices.wrappers
    .ProcessRobot) and the loop exchanges the latest command/reading with it every tick; None runs the
    robot's I/O inline in the tick (at LoopParams.robot_rate_hz). With `realtime` the loop runs under
    SCHED_FIFO 50 when the OS allows it; the robot process (SCHED_FIFO `robot_rt_priority` if given, else nice -10)
    and the recorder (nice -10) stay behind it. `live` = (host, port) serves the session to Foxglove from
    another process reading the same ring (teleop.loop.live; port 0 picks a free one, printed on stdout);
    `live_scene` adds pads to its 3D scene. `robot_wrapper(robot, clock)` wraps the robot the loop talks to (on the
    loop's side of the robot process), e.g. the backlash feed-forward devices.wrappers.BacklashCompensatedRobot.
    `sim_clock` ticks on a simulated clock instead (timing.run_stepped: tick k at k periods, no waiting; the
    same inputs give the same session on any machine); it needs the robot inline (robot_process_hz None) and a
    simulated stylus (sim://, opened here on that clock); `robot_wrapper(robot, clock)` is handed the clock
    (None: the wall clock). `progress`, a name ("session"), shows the run's ticks, state, misses and faults
    on stderr under that name (teleop.loop.loop_progress; "": none). `geometry` (None: the seed robot's) is the
    robot's: the loop's kinematics, the default estimator and a robot built here from its URL
    (devices_by_url.open_device) all use it; a given `estimator` must have been built on it. The recording's
    metadata holds it, with `geometry_file` it came from.

    A stop signal (teleop.io.stop_signals: SIGINT, SIGTERM, SIGHUP, with the CLI's handler installed) ends the
    loop between two ticks; the devices are stopped, the recording closed with the signal's name in its
    `session_end` record, and the result's `interrupted` names it. Without that handler Ctrl-C's
    KeyboardInterrupt does the same ("SIGINT").
    """
    if sim_clock and robot_process_hz:
        raise ValueError("a simulated clock needs the robot inline (robot_process_hz=None): a robot process runs "
                         "on the wall clock")
    realtime = realtime and not sim_clock  # flat out under SCHED_FIFO would starve the machine
    clock = SimClock() if sim_clock else None
    if sim_clock and haptic is None:
        if not is_simulated_stylus(haptic_url):
            raise ValueError(f"a simulated clock needs a simulated stylus (sim://), got {haptic_url}")
        haptic = open_device(haptic_url, clock=clock)
    params = params or LoopParams()
    if estimator is None:
        # on sim://robot?plant=distributed the plant's own FSR calibration (scenes.fsr_lab), else the built-in
        estimator = default_estimator(frame_period(params, robot_process_hz), geometry=geometry,
                                      cal=robot_url_calibration(robot_url) if robot is None else None)
    haptic = haptic if haptic is not None else open_device(haptic_url)
    built = robot  # the robot as built from its URL (a ProcessRobot runs it elsewhere): its pad for the scene
    if robot is None:
        if robot_process_hz:
            built = open_device(robot_url, geometry=geometry)  # validates here (one clear line) before forking
            robot = process_robot(robot_url, rate_hz=robot_process_hz,
                                  rt_priority=robot_rt_priority if realtime else None,
                                  **({} if geometry is None else {"geometry": geometry}))
        else:
            robot = built = open_device(robot_url, geometry=geometry)
    if robot_wrapper is not None:
        robot = robot_wrapper(robot, clock)
    recorder = live_view = bar = None
    try:
        with haptic, robot:
            tp = Teleop(haptic, robot, params, geom=geometry, estimator=estimator)
            first = robot.read()  # telemetry only; no motion command is sent before ENABLED
            tp.last_reading = first
            extras = numeric_extras(first)
            layout = with_fbg_channel(session_layout(extras), estimator)  # + the FBG channel (sensor_tap)
            if record:
                meta = session_metadata(tp, haptic_url, robot_url, seconds, seed, geometry_file)
                recorder = Recorder(record, layout, meta, flush_interval=flush_interval,
                                    t0_ns=meta["start_time_ns"]).start()
                tp.tap = session_tap(layout, recorder.push, extras, estimator)
                tp.on_event = lambda ev: recorder.event(vars(ev))
            if live is not None:
                live_view = _start_live(tp, layout, extras, recorder, live,
                                        {"pads": pad_scene(built), **(live_scene or {})})
            log = TimingLog(int(round(seconds * params.rate_hz)))
            scheduling = (set_realtime(50) if realtime else
                          "simulated clock (not paced)" if sim_clock else "SCHED_OTHER (not requested)")
            gc.collect()
            gc.disable()
            interrupted = ""
            on_start = (recorder.set_t0 if recorder is not None else
                        live_view.ring.set_t0 if live_view is not None else None)
            if progress:
                bar = LoopProgress(tp, log, len(log.tick), params.rate_hz, desc=progress)
            try:
                with STOP.polled():  # a signal sets STOP.signum; the loop ends after the tick under way
                    if sim_clock:
                        run_stepped(tp, seconds, params.rate_hz, log, on_start=on_start, clock=clock,
                                    should_stop=STOP.requested, on_tick=bar and bar.on_tick)
                    else:
                        run_paced(tp, seconds, params.rate_hz, log, spin_us=spin_us, on_start=on_start,
                                  should_stop=STOP.requested, on_tick=bar and bar.on_tick)
                interrupted = STOP.name
            except KeyboardInterrupt:
                interrupted = STOP.name or "SIGINT"
            finally:
                gc.enable()
                if realtime:
                    set_normal()
                try:
                    haptic.servo_cf(np.zeros(3))
                finally:
                    try:
                        robot.stop()
                    except Exception:  # noqa: BLE001 - closing anyway; the robot's own watchdog stops it
                        pass
                if bar is not None:  # after the devices: a terminal gone (SIGHUP) cannot keep them running
                    bar.close()
            timing = log.summary(params.rate_hz)
            result = SessionResult(timing=timing, events=[vars(e) for e in tp.events], final_state=tp.state.name,
                                   fault_reason=tp.fault_reason, record=record, scheduling=scheduling,
                                   interrupted=interrupted)
    finally:
        if live_view is not None:
            live_stats = live_view.close()
            if "result" in locals():
                result.live = live_stats
        if recorder is not None:
            end = {"timing": timing if "timing" in locals() else {},
                   "final_state": result.final_state if "result" in locals() else "unknown",
                   "fault_reason": result.fault_reason if "result" in locals() else "",
                   "drops": recorder.drops, "event_drops": recorder.event_drops,
                   "interrupted": result.interrupted if "result" in locals() else "unknown"}
            recorder.close(end)
            if "result" in locals():
                result.drops, result.alarm = recorder.drops, recorder.alarm
    return result
