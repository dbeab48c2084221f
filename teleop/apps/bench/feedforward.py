"""`teleop bench feedforward`: tip tracking error of closed-loop sessions on the robot with backlash, without
and with the backlash feed-forward, in one run.

    teleop bench feedforward --backlash-mm 0.5 --seconds 10 --seed 0 --json ff.json --plot ff.png
    teleop bench feedforward --compensation MODEL.json      # the width from a link model (teleop diagnose)
    teleop bench feedforward --recordings PLAIN.mcap COMP.mcap   # the same error in recorded paced sessions

Three sessions run on a manual clock (simulated time, as `teleop bench sim`), each the whole chain: the
simulated operator (devices.simulated, `sine` script: the stylus moved back and forth along --axis, with its
tremor; the rendered force acts on the hand) -> the loop (teleop.loop.Teleop at 1 kHz, the robot link at
500 Hz as `teleop session`'s default) -> the pybullet slave (scenes.sim_robot) with each cable's play of
--backlash-mm between its motor and its cable (SimRobotParams.backlash):

  plain        the plant with play, commanded as if it had none;
  compensated  the same plant behind devices.wrappers.BacklashCompensatedRobot (the width of --compensation
               MODEL, else the plant's own width);
  no_play      the plant without play (the floor: the loop's and the tip spring's own lag).

Tip tracking error, per robot reading while ENABLED, after --settle-s: |commanded tip - actual tip| [mm];
commanded tip = the loop's setpoint pose's tool tip (position + R tip, the pose the loop computes the cable
lengths of), actual tip = the pybullet contact tip (RobotReading extras["tip"]). The stylus stays in free
space (the sine is centred on the home pose, 5 mm above the pad; --axis z would reach the pad at large
amplitudes). Seeds: the robot's ADC noise and the operator's tremor from one SeedSequence(--seed), the same
in all three sessions.

`--plant distributed`: every session's robot with the distributed tendon-sheath cable (scenes.sim_robot
DistributedCables, default parameters) for its tensions. The pose still follows the realized lengths (the
play operator), the cable's tip travel is not fed back to it: the tip error is the play's as before, what
changes is the sensed tension and so the force rendered on the operator's hand.

JSON: {"seed", "seconds", "settle_s", "backlash_mm", "compensation": {"source", "width_mm"}, "stylus":
{"axis", "amp_mm", "period_s"}, "rate_hz", "robot_rate_hz", "sessions": {name: {"tip_error_mm": {"rms",
"p95", "max"}, "readings", "final_state", "fault_reason", "max_command_step_mm"}}, "v_max_step_mm",
"ratio_rms" (plain / compensated), "pass" (ratio_rms >= 2 and no session faulted)}; "plant" when not matched.

`--plant distributed --single-cable`: offline, one distributed tendon-sheath cable (scenes.tendon_sheath, default
parameters, a constant tip force equal to its pretension, 1 kHz), no robot and no operator. Calibration: one run
of the motor on a 3 mm sine (period 4 s, two cycles) at CAL_LOAD_N gives the lost motion w (motor minus tip
stroke, second cycle) and the motor force pulling and releasing. Compensators, both from that one run:
  plain   the backlash inverse of width w (teleop.core.control.feedforward.backlash_inverse);
  pulley  seed 002's model-based compensation (pulley_precompensate) on a chain of CHAIN_PULLEYS equal pulleys
          sharing the sheath's total bend (theta0 + theta1) over its length, mu from the force ratio
          (F_pull / F_rel = exp(2 mu Theta)), EA from w: its play width and offset follow the load.
Test: the wanted tip a 2 mm sine (period 2 s, 6 s) at each tip load of TEST_LOADS_N; tip error RMS after 1 s
[mm] with the motor on the wanted tip (none), plain and pulley. The plant is deterministic (--seed unused
there). JSON: {"mode": "single_cable", "plant", "calibration": {"load_N", "lost_motion_mm", "F_pull_N",
"F_rel_N", "mu", "EA_N", "chain_pulleys"}, "loads_N", "tip_error_rms_mm": {"none", "plain", "pulley"} (per load)}.

`--cable-params TOML` (with --single-cable or --plant pulley): the cable's [tendon_sheath] or [pulley_transmission]
table (docs/formats.md) instead of the defaults.

`--plant pulley` (`--single-cable` implied): the same offline comparison on one cable over seed 002's pulley
chain with bending rigidity (scenes.pulley_transmission, default parameters: the guide on the scaffold bend
theta0 with the sheath's mu, then the instrument's pulleys; its tip travel is the motor's minus the cable's
stretch, lost motion at reversals), calibrated at PULLEY_CAL_LOAD_N and tested at PULLEY_TEST_LOADS_N. The
compensator is handed where the pulleys sit (wraps, radii, spans: the instrument's drawing), not the plant's
friction, bending rigidity or EA: its chain has no bending rigidity, one mu from the run's force ratio and EA
from its lost motion, so its play width grows with the load as the capstan's does while the plant's has the
bending losses' load-independent part. (In the closed-loop sessions the tip error is the robot's play
operator's, the cable's stretch is not fed back to the pose: the pulley plant is compared on one cable.)
"calibration" adds "plant_EI_N_m2", the plant's bending rigidity, for the record (the fit does not read it).

With --recordings the same error is read from recorded `teleop session --record` files instead (simulated
robot: its `x_tip` beside the loop's `/teleop/setpoint`, one value per robot frame after --settle-s; paced
sessions, the robot in its own process) and nothing is simulated: JSON {"settle_s", "recordings": {path:
{"tip_error_mm", "readings", "compensation"}}, "ratio_rms" (first / second file, with two)}.
"""

from __future__ import annotations

import gc
import math
import sys

import numpy as np

from devices.simulated import OperatorParams, Script, SimulatedStylus
from devices.wrappers import BacklashCompensatedRobot, LoggedDevice
from scenes.pulley_transmission import PulleyTransmission, PulleyTransmissionParams
from scenes.sim_robot import SimRobot, SimRobotParams
from scenes.tendon_sheath import SheathLoad, TendonSheath, TendonSheathParams
from teleop.apps.argtypes import add_geometry_option, geometry_of, input_file
from teleop.core.control.feedforward import backlash_inverse, model_backlash_width, pulley_precompensate
from teleop.core.errors import InputError
from teleop.core.kernels import sheath as SH
from teleop.core.kinematics import rotation_zyx
from teleop.core.mapping import POKE_WORKSPACE_MAX, MappingParams
from teleop.io.model_io import load_model
from teleop.io.figures import legend_outside
from teleop.core.physics.pulley import Pulley, PulleyChain, pulley_band, pulley_elongation
from teleop.io.outputs import check_output, save_figure, write_json
from teleop.io.recording import TOPIC_ROBOT, TOPIC_SETPOINT, read_session
from teleop.loop import LoopParams, State, Teleop
from teleop.loop.replay import geometry_from
from teleop.loop.session import default_estimator, frame_period

RATE_HZ = 1000.0      # loop rate [Hz]
ROBOT_RATE_HZ = 500.0  # robot link rate [Hz] (teleop session's default)
SUBSTEPS = 2           # 1 ms physics steps per robot reading at 500 Hz
TARGET_RATIO = 2.0     # issue 16: the feed-forward lowers the tip tracking error >= 2x
SESSIONS = ("plain", "compensated", "no_play")


def register(subparsers) -> None:
    p = subparsers.add_parser("feedforward",
                              help="tip tracking error on the robot with backlash, without and with the feed-forward")
    p.add_argument("--backlash-mm", type=float, default=0.5, help="each cable's play width [mm] (default 0.5)")
    p.add_argument("--compensation", type=input_file, metavar="MODEL",
                   help="link model (JSON) whose backlash width the feed-forward uses (teleop diagnose --save-model, "
                        "or hand-written: docs/feedforward.md); default: the plant's own width")
    p.add_argument("--seconds", type=float, default=10.0, help="simulated session length [s] (default 10)")
    p.add_argument("--settle-s", type=float, default=1.0,
                   help="error counted from this time on [s] (engagement, first reversal; default 1)")
    p.add_argument("--axis", choices=("x", "y", "z"), default="x", help="stylus motion axis (default x)")
    p.add_argument("--amp-mm", type=float, default=12.0,
                   help="stylus amplitude [mm] (x motion scale 0.25 at the robot; default 12)")
    p.add_argument("--period-s", type=float, default=2.0, help="stylus period [s] (default 2)")
    p.add_argument("--seed", type=int, default=0, help="seeds the operator's tremor and the ADC noise (default 0)")
    p.add_argument("--plant", default="matched", choices=("matched", "distributed", "pulley"),
                   help="matched (default) or distributed: the robot's tensions from the distributed tendon-sheath "
                        "cable (scenes/tendon_sheath.py); the play stays the robot's play operator; pulley: one "
                        "cable over seed 002's pulley chain (scenes/pulley_transmission.py), offline as "
                        "--single-cable")
    p.add_argument("--single-cable", action="store_true",
                   help="with --plant distributed: one distributed tendon-sheath cable offline, no compensation vs "
                        "the plain backlash inverse vs seed 002's pulley-model compensation, both calibrated on one "
                        "run of the cable (module docstring)")
    p.add_argument("--recordings", nargs="+", metavar="MCAP", type=input_file,
                   help="measure recorded sessions of the simulated robot instead (e.g. without, then with "
                        "--compensation); the ratio is first / second")
    p.add_argument("--cable-params", type=input_file, default=None, metavar="TOML",
                   help="with --single-cable or --plant pulley: the cable's parameters, a [tendon_sheath] or "
                        "[pulley_transmission] table (docs/formats.md; default the built-in values)")
    add_geometry_option(p)
    p.add_argument("--json", metavar="F", help="write the result JSON here")
    p.add_argument("--plot", metavar="F", help="write the tip error over time (PNG)")
    p.set_defaults(func=run)


def _seeds(seed: int) -> tuple[int, int]:
    """(robot seed, stylus seed) from one SeedSequence."""
    a, b = (int(s) for s in np.random.SeedSequence(seed).generate_state(2) % (2 ** 31))
    return a, b


def run_session(backlash: float, width: float | None, seconds: float, seed: int, axis: str = "x",
                amp: float = 12e-3, period: float = 2.0, plant: str = "matched", geometry=None) -> dict:
    """One closed-loop session on the manual clock; the plant's play `backlash` [m], the feed-forward's
    `width` [m] (None: off), `plant` matched or distributed (module docstring), `geometry` the robot's (None:
    the seed robot). Returns arrays per robot reading: "t" [s], "err" [m] (tip error), "enabled",
    and "final_state", "fault_reason", "max_command_step" [m]."""
    robot_seed, stylus_seed = _seeds(seed)
    params = LoopParams(rate_hz=RATE_HZ, robot_rate_hz=ROBOT_RATE_HZ,
                        mapping=MappingParams(workspace_max=POKE_WORKSPACE_MAX))
    cable = TendonSheathParams() if plant == "distributed" else None
    sim = SimRobot(params=SimRobotParams(substeps=SUBSTEPS, backlash=backlash, cable=cable,
                                         **({} if geometry is None else {"geometry": geometry})), seed=robot_seed)
    logged = LoggedDevice(sim)  # what reaches the robot: the speed check
    clock_t = [0.0]
    robot = logged if width is None else BacklashCompensatedRobot(logged, width, params.dt * params.robot_every,
                                                                  clock=lambda: clock_t[0])
    ax = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}[axis]
    stylus = SimulatedStylus(Script(kind="sine", axis=ax, amplitude=amp, period=period), OperatorParams(),
                             seed=stylus_seed, clock=lambda: clock_t[0])
    n = int(round(seconds * RATE_HZ))
    t_log, err, on = [], [], []
    with robot, stylus:
        tp = Teleop(stylus, robot, params, geom=geometry,
                    estimator=default_estimator(frame_period(params, None), geometry=geometry))
        tp.start(0.0)
        tool = np.asarray(tp.geom.tip, dtype=float)
        gc.collect()
        gc.disable()
        try:
            for k in range(n):
                clock_t[0] = (k + 1) * params.dt
                x = tp.tick(clock_t[0])
                r = x.reading
                if r is None:
                    continue
                q = tp.pose  # the setpoint pose the loop commanded (home orientation)
                wanted = q[:3] + rotation_zyx(*q[3:]) @ tool
                t_log.append(clock_t[0])
                err.append(float(np.linalg.norm(np.asarray(r.extras["tip"], dtype=float) - wanted)))
                on.append(tp.state == State.ENABLED)
        finally:
            gc.enable()
        final_state, fault_reason = tp.state.name, tp.fault_reason
    sent = np.array([a for name, a in logged.log if name == "command_lengths"])
    step = float(np.abs(np.diff(sent, axis=0)).max()) if len(sent) > 1 else 0.0
    return {"t": np.array(t_log), "err": np.array(err), "enabled": np.array(on, dtype=bool),
            "final_state": final_state, "fault_reason": fault_reason, "max_command_step": step,
            "v_max_step": float(sim.spec.v_max) * params.dt * params.robot_every}


def recorded_tip_errors(path: str, settle: float = 1.0) -> tuple[np.ndarray, dict | None]:
    """(tip errors (n,) [m] per robot frame at or after `settle` [s], the session's compensation metadata)
    of a `teleop session` recording on the simulated robot: |setpoint_cp + R(home) tip - x_tip|."""
    s = read_session(path)
    conf = s.metadata.get("session", {}).get("configuration")
    if conf is None:
        raise InputError(f"{path}: no session metadata (is this a teleop session recording?)")
    geom = geometry_from(conf.get("geometry"))
    home = np.asarray(((conf.get("loop") or {}).get("mapping") or {}).get("home", [0.0] * 6), dtype=float)
    tool = rotation_zyx(*home[3:]) @ np.asarray(geom.tip, dtype=float)
    sp = {m["tick"]: m["setpoint_cp"] for m in s.messages(TOPIC_SETPOINT)}
    err, last = [], None
    for m in s.messages(TOPIC_ROBOT):
        if m["seq"] == last or m["tick"] not in sp or "x_tip" not in m:
            continue  # one value per robot frame (the loop sees a frame on several ticks)
        last = m["seq"]
        if m["t"] >= settle:
            err.append(float(np.linalg.norm(np.asarray(m["x_tip"], dtype=float) - (np.asarray(sp[m["tick"]]) + tool))))
    if not err:
        raise InputError(f"{path}: no robot frames with the simulator's tip (x_tip) after {settle:g} s")
    return np.array(err), conf.get("compensation")


def bench_recordings(paths: list, settle: float = 1.0) -> dict:
    """The result dict for recorded sessions (module docstring)."""
    rec = {}
    for path in paths:
        e, comp = recorded_tip_errors(str(path), settle)
        rec[str(path)] = {"tip_error_mm": _stats_mm(e), "readings": int(e.size), "compensation": comp}
    rms = [v["tip_error_mm"]["rms"] for v in rec.values()]
    return {"settle_s": settle, "recordings": rec,
            "ratio_rms": round(rms[0] / rms[1], 4) if len(rms) == 2 and rms[1] else None}


def _stats_mm(e: np.ndarray) -> dict:
    if e.size == 0:
        return {"rms": None, "p95": None, "max": None}
    return {"rms": round(float(np.sqrt(np.mean(e ** 2))) * 1e3, 6),
            "p95": round(float(np.percentile(e, 95)) * 1e3, 6), "max": round(float(e.max()) * 1e3, 6)}


def bench_feedforward(backlash: float = 0.5e-3, width: float | None = None, source: str = "the plant's own width",
                      seconds: float = 10.0, settle: float = 1.0, seed: int = 0, axis: str = "x",
                      amp: float = 12e-3, period: float = 2.0, progress=None,
                      plant: str = "matched", geometry=None) -> tuple[dict, dict]:
    """(result dict of the module docstring, raw traces by session). width: the feed-forward's play [m]
    (None: `backlash`); progress(name) is called as each session starts; plant: matched or distributed;
    geometry: the robot's (None: the seed robot)."""
    width = backlash if width is None else width
    runs, sessions = {}, {}
    for name, play, w in (("plain", backlash, None), ("compensated", backlash, width), ("no_play", 0.0, None)):
        if progress is not None:
            progress(name)
        tr = run_session(play, w, seconds, seed, axis, amp, period, plant, geometry)
        runs[name] = tr
        keep = tr["enabled"] & (tr["t"] >= settle)
        sessions[name] = {"tip_error_mm": _stats_mm(tr["err"][keep]), "readings": int(keep.sum()),
                          "final_state": tr["final_state"], "fault_reason": tr["fault_reason"],
                          "max_command_step_mm": round(tr["max_command_step"] * 1e3, 6)}
    plain, comp = sessions["plain"]["tip_error_mm"]["rms"], sessions["compensated"]["tip_error_mm"]["rms"]
    ratio = round(plain / comp, 4) if plain and comp else None
    faulted = any(s["final_state"] == "FAULT" for s in sessions.values())
    out = {"seed": int(seed), "seconds": seconds, "settle_s": settle, "backlash_mm": backlash * 1e3,
           "compensation": {"source": source, "width_mm": width * 1e3},
           "stylus": {"axis": axis, "amp_mm": amp * 1e3, "period_s": period},
           "rate_hz": RATE_HZ, "robot_rate_hz": ROBOT_RATE_HZ, "sessions": sessions,
           "v_max_step_mm": round(runs["plain"]["v_max_step"] * 1e3, 6), "ratio_rms": ratio,
           "pass": bool(ratio is not None and ratio >= TARGET_RATIO and not faulted)}
    if plant != "matched":
        out["plant"] = plant
    return out, runs


def format_report(out: dict) -> str:
    c = out["compensation"]
    lines = [f"closed-loop sessions of {out['seconds']:g} s (seed {out['seed']}), stylus sine {out['stylus']['amp_mm']:g} mm "
             f"along {out['stylus']['axis']} every {out['stylus']['period_s']:g} s, plant play {out['backlash_mm']:g} mm "
             f"per cable; feed-forward width {c['width_mm']:.4g} mm ({c['source']})",
             f"tip tracking error after {out['settle_s']:g} s [mm]:",
             f"  {'session':12s} {'rms':>9s} {'p95':>9s} {'max':>9s} {'readings':>9s} {'max step':>9s}  state"]
    for name, s in out["sessions"].items():
        e = s["tip_error_mm"]
        f = (lambda v: f"{v:9.4f}" if v is not None else f"{'-':>9s}")
        lines.append(f"  {name:12s} {f(e['rms'])} {f(e['p95'])} {f(e['max'])} {s['readings']:9d} "
                     f"{s['max_command_step_mm']:9.4f}  {s['final_state']}" + (f" ({s['fault_reason']})" if s["fault_reason"] else ""))
    lines.append(f"command step limit v_max * period: {out['v_max_step_mm']:.4f} mm")
    r = out["ratio_rms"]
    lines.append(f"ratio plain / compensated (rms): {r:.2f}x, target >= {TARGET_RATIO:g}x: {'PASS' if out['pass'] else 'FAIL'}"
                 if r is not None else "ratio: n/a (no enabled readings)")
    return "\n".join(lines)


def figure(out: dict, runs: dict):
    """Tip tracking error [mm] over time [s], one line per session."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    fig, ax = plt.subplots(figsize=(9, 4))
    labels = {"plain": f"with play {out['backlash_mm']:g} mm, no compensation",
              "compensated": f"with play, feed-forward {out['compensation']['width_mm']:.3g} mm",
              "no_play": "no play (floor)"}
    for name in SESSIONS:
        tr = runs[name]
        rms = out["sessions"][name]["tip_error_mm"]["rms"]
        ax.plot(tr["t"], tr["err"] * 1e3, lw=0.8, label=f"{labels[name]} (rms {rms:.3g} mm)" if rms is not None
                else labels[name])
    ax.axvline(out["settle_s"], color="0.5", ls=":", lw=0.8, label="error counted from here")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tip tracking error |commanded - actual| [mm]")
    r = out["ratio_rms"]
    st = out["stylus"]
    ax.set_title(f"teleop bench feedforward: tip error with cable play, simulated robot, "
                 f"plant {out.get('plant', 'matched')}"
                 f"\nstylus {st['axis']} {st['amp_mm']:g} mm every {st['period_s']:g} s, seed {out['seed']}"
                 + (f": plain / compensated {r:.2f}x (rms)" if r else ""), fontsize=9)
    legend_outside(ax, "below", ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _check(args) -> None:
    def bad(flag, what, v):
        raise InputError(f"{flag}: expected {what}, got {v}")
    if not (math.isfinite(args.backlash_mm) and 0 < args.backlash_mm <= 5):
        bad("--backlash-mm", "a play width in (0, 5] mm", args.backlash_mm)
    if not (math.isfinite(args.seconds) and 0 < args.seconds <= 3600):
        bad("--seconds", "simulated seconds in (0, 3600]", args.seconds)
    if not (math.isfinite(args.settle_s) and 0 <= args.settle_s < args.seconds):
        bad("--settle-s", "seconds in [0, --seconds)", args.settle_s)
    if not (math.isfinite(args.amp_mm) and 0 < args.amp_mm <= 20):
        bad("--amp-mm", "a stylus amplitude in (0, 20] mm (the robot's workspace is +-5 mm at motion scale 0.25)",
            args.amp_mm)
    if not (math.isfinite(args.period_s) and 0.2 <= args.period_s <= 60):
        bad("--period-s", "a period in [0.2, 60] s", args.period_s)
    if not 0 <= args.seed < 2 ** 63:
        bad("--seed", "a non-negative integer", args.seed)


def run(args) -> int:
    _check(args)
    if args.single_cable or args.plant == "pulley":  # the pulley plant: one cable (module docstring)
        return run_single_cable(args)
    if args.cable_params is not None:
        raise InputError("--cable-params: the cable's parameters belong to --single-cable or --plant pulley")
    geometry = geometry_of(args)  # a bad file is one line before any session
    if args.recordings:
        out = bench_recordings(args.recordings, args.settle_s)
        print(f"tip tracking error of recorded sessions after {args.settle_s:g} s [mm]:")
        for path, v in out["recordings"].items():
            e, c = v["tip_error_mm"], v["compensation"]
            print(f"  rms {e['rms']:.4f}  p95 {e['p95']:.4f}  max {e['max']:.4f}  ({v['readings']} frames) {path}"
                  + (f"  [feed-forward {c['width_mm'][0]:.4g} mm]" if c else ""))
        if out["ratio_rms"] is not None:
            print(f"ratio first / second (rms): {out['ratio_rms']:.2f}x")
        if args.json:
            write_json(args.json, out)
        return 0
    width, source = None, "the plant's own width"
    if args.compensation:
        width = model_backlash_width(load_model(args.compensation), f"--compensation {args.compensation}")
        source = str(args.compensation)
    out, runs = bench_feedforward(args.backlash_mm * 1e-3, width, source, args.seconds, args.settle_s, args.seed,
                                  args.axis, args.amp_mm * 1e-3, args.period_s,
                                  progress=lambda name: print(f"feedforward: session {name} ...", file=sys.stderr,
                                                              flush=True), plant=args.plant, geometry=geometry)
    if args.geometry:  # listed only when given: the seed robot's JSON is what it was
        out["geometry_file"] = args.geometry
    print(format_report(out))
    if args.json:
        write_json(args.json, out)
    if args.plot:
        save_figure(figure(out, runs), args.plot)
    return 0


# ---- --single-cable: seed 002's pulley-model compensation vs the plain inverse, offline ------------------------

CAL_LOAD_N = 2.0
TEST_LOADS_N = (1.0, 2.0, 4.0, 8.0)
CHAIN_PULLEYS = 10
CABLE_HZ = 1000.0
#: --plant pulley: the instrument's loads (teleop bench pulley's 10 N grasp among them; at 1 N its bending
#: losses slacken the cable releasing)
PULLEY_CAL_LOAD_N = 5.0
PULLEY_TEST_LOADS_N = (2.5, 5.0, 10.0, 20.0)


def _cable(params: TendonSheathParams, load_N: float) -> TendonSheath:
    return TendonSheath(params, SheathLoad("force"), pretension=load_N, tick=1.0 / CABLE_HZ)


def _guide_wrap() -> float:
    """The pulley cable's guide wrap [rad] off the robot: the sheath's scaffold bend theta0 (no pose bend)."""
    return SH.Sheath().theta0


def cable_runner(plant: str, params):
    """run(x, load_N) -> (tip travel (n,) [m], motor force (n,) [N]) of one fresh cable of `plant`
    (distributed: scenes.tendon_sheath with TendonSheathParams; pulley: scenes.pulley_transmission with
    PulleyTransmissionParams, its guide on _guide_wrap and the sheath's mu) under a constant tip load, the
    motor at x (n,) [m] (1 kHz)."""
    if plant == "distributed":
        def run(x, load):
            r = _cable(params, load).run(x, tip_input=load)
            return r.x_tip[:, 0], r.f_motor[:, 0]
    else:
        def run(x, load):
            tr = PulleyTransmission(params, 1, 0.0, SH.Sheath().mu)
            full = np.full((len(x), 1), 1.0)
            r = tr.travel(-np.asarray(x, dtype=float)[:, None], load * full, _guide_wrap() * full)
            return r.x_tip[:, 0], r.t_motor[:, 0]
    return run


def fit_chain(run, load_N: float, thetas, radii, spans) -> dict:
    """One calibration run (module docstring) of run(x, load) (`cable_runner`) at load_N [N]: lost motion w [m],
    motor force pulling / releasing [N], and the capstan chain (no bending rigidity) on the known wraps
    thetas (p,) [rad], radii (p,) [m] and spans (p + 1,) [m] fitted to them: one mu [-] from F_pull / F_rel =
    exp(2 mu sum theta), EA [N] from w."""
    n = int(4.0 * CABLE_HZ)
    xm = 3e-3 * np.sin(2 * np.pi * np.arange(2 * n) / n)
    xt, fm = run(xm, load_N)
    w = float(np.ptp(xm[n:]) - np.ptp(xt[n:]))
    v = np.gradient(xm)
    second = np.arange(xm.size) >= n
    F_pull = float(np.median(fm[second & (v > 0.5 * v.max())]))
    F_rel = float(np.median(fm[second & (v < 0.5 * v.min())]))
    mu = math.log(F_pull / F_rel) / (2.0 * float(np.sum(thetas)))
    unit = PulleyChain(tuple(Pulley(t, R, mu, d) for t, R, d in zip(thetas, radii, spans[1:])), EA=1.0,
                       d_tip=spans[0])
    lo, hi = pulley_band([load_N], unit)
    EA = float(pulley_elongation(hi, [load_N], unit)[0] - pulley_elongation(lo, [load_N], unit)[0]) / w
    return {"load_N": load_N, "w": w, "F_pull_N": F_pull, "F_rel_N": F_rel, "mu": mu, "EA_N": EA,
            "chain": PulleyChain(unit.pulleys, EA=EA, d_tip=spans[0])}


def calibrate_single_cable(params: TendonSheathParams, load_N: float = CAL_LOAD_N) -> dict:
    """fit_chain on the distributed cable: CHAIN_PULLEYS equal pulleys sharing the sheath's bend over its length."""
    theta = params.theta0 + params.theta1
    span = params.length / (CHAIN_PULLEYS + 1)
    return fit_chain(cable_runner("distributed", params), load_N, [theta / CHAIN_PULLEYS] * CHAIN_PULLEYS,
                     [1.0] * CHAIN_PULLEYS, [span] * (CHAIN_PULLEYS + 1))


def calibrate_pulley_cable(params: PulleyTransmissionParams, load_N: float = PULLEY_CAL_LOAD_N) -> dict:
    """fit_chain on the pulley cable: the compensator knows where the pulleys sit (the guide's wrap, the
    layout's wraps, radii and spans: the instrument's drawing), not its friction, bending rigidity or EA."""
    layout = params.chain()
    thetas = [_guide_wrap()] + [p.theta for p in layout.pulleys]
    radii = [params.guide_R] + [p.R for p in layout.pulleys]
    spans = [params.tip_span] + list(layout.spans)
    return fit_chain(cable_runner("pulley", params), load_N, thetas, radii, spans)


def bench_single_cable(params=None, plant: str = "distributed") -> tuple[dict, dict]:
    """(JSON-ready result, one trace per compensator at the largest load for the figure) on one cable of
    `plant` (distributed or pulley; params its TendonSheathParams or PulleyTransmissionParams, None: defaults)."""
    if plant == "distributed":
        params = TendonSheathParams() if params is None else params
        cal, loads = calibrate_single_cable(params), TEST_LOADS_N
    else:
        params = PulleyTransmissionParams() if params is None else params
        cal, loads = calibrate_pulley_cable(params), PULLEY_TEST_LOADS_N
    run = cable_runner(plant, params)
    chain = cal["chain"]
    t = np.arange(int(6.0 * CABLE_HZ)) / CABLE_HZ
    y_d = 2e-3 * np.sin(2 * np.pi * t / 2.0)
    after = t >= 1.0
    rms = {"none": [], "plain": [], "pulley": []}
    traces = {}
    for load in loads:
        # the plant's travel starts at the uniform stretch of its pretension: the model's absolute elongation
        # is taken from there
        cmds = {"none": y_d, "plain": backlash_inverse(y_d, cal["w"]),
                "pulley": pulley_precompensate(y_d, load, chain) - load * float(np.sum(chain.spans)) / chain.EA}
        for name, x in cmds.items():
            e = run(x, load)[0] - y_d
            rms[name].append(float(np.sqrt(np.mean(e[after] ** 2))) * 1e3)
            if load == loads[-1]:
                traces[name] = e * 1e3
    traces["t"] = t
    calib = {"load_N": cal["load_N"], "lost_motion_mm": cal["w"] * 1e3, "F_pull_N": cal["F_pull_N"],
             "F_rel_N": cal["F_rel_N"], "mu": cal["mu"], "EA_N": cal["EA_N"]}
    if plant == "distributed":
        calib["chain_pulleys"] = CHAIN_PULLEYS
    else:
        calib["chain_pulleys"] = len(chain.pulleys)
        calib["plant_EI_N_m2"] = params.EI
    out = {"mode": "single_cable", "plant": plant, "calibration": calib, "loads_N": list(loads),
           "tip_error_rms_mm": rms}
    return out, traces


PLANT_TITLES = {"distributed": "plant distributed (one tendon-sheath cable, 2 mm sine)",
                "pulley": "plant pulley (one cable over seed 002's pulley chain with bending rigidity, 2 mm sine)"}


def single_cable_figure(out: dict, traces: dict):
    import matplotlib  # heavy: loaded only to draw
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.6))
    labels = {"none": "no compensation", "plain": "plain backlash inverse",
              "pulley": "seed 002 pulley-model compensation"}
    for i, (name, label) in enumerate(labels.items()):
        a1.plot(out["loads_N"], out["tip_error_rms_mm"][name], "o-", color=f"C{i}", label=label)
        a2.plot(traces["t"], traces[name], color=f"C{i}", lw=1.0, label=label)
    a1.set_yscale("log")
    a1.set_xlabel("tip load [N]")
    a1.set_ylabel("tip error RMS after 1 s [mm]")
    a1.set_title(f"tip tracking error (calibrated at {out['calibration']['load_N']:g} N)")
    legend_outside(a1, "below")
    a2.set_xlabel("time [s]")
    a2.set_ylabel("tip error [mm]")
    a2.set_title(f"tip error at {out['loads_N'][-1]:g} N")
    legend_outside(a2, "below")
    fig.suptitle(f"teleop bench feedforward --single-cable: {PLANT_TITLES[out['plant']]}")
    fig.tight_layout()
    return fig


def run_single_cable(args) -> int:
    if args.plant not in ("distributed", "pulley"):
        raise InputError("--single-cable: runs on one distributed tendon-sheath or pulley cable; expected --plant "
                         "distributed or --plant pulley")
    if args.recordings or args.compensation:
        raise InputError("--single-cable: calibrates its own compensators; drop --recordings and --compensation")
    for flag, path in (("--json", args.json), ("--plot", args.plot)):
        if path:
            check_output(path, flag)
    params = None
    if args.cable_params is not None:
        params = (TendonSheathParams if args.plant == "distributed" else PulleyTransmissionParams).from_toml(
            args.cable_params)
    out, traces = bench_single_cable(params, plant=args.plant)
    what = {"distributed": "one distributed tendon-sheath cable",
            "pulley": "one cable over the pulley chain (bending rigidity, the compensator's chain without)"}
    print(f"{what[args.plant]}, calibrated at {out['calibration']['load_N']:g} N: lost motion "
          f"{out['calibration']['lost_motion_mm']:.4f} mm, pulley chain mu {out['calibration']['mu']:.4f}, "
          f"EA {out['calibration']['EA_N']:.0f} N")
    print("tip load [N]   tip error RMS [mm]: none    plain    pulley")
    r = out["tip_error_rms_mm"]
    for i, load in enumerate(out["loads_N"]):
        print(f"{load:>12g}   {r['none'][i]:>22.4f} {r['plain'][i]:>8.4f} {r['pulley'][i]:>9.4f}")
    if args.json:
        write_json(args.json, out)
    if args.plot:
        save_figure(single_cable_figure(out, traces), args.plot)
    return 0
