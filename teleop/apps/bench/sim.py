"""`teleop bench sim`: the simulation's real-time factor, unpaced (budget, docs/safety.md: >= 20x real time).

    teleop bench sim --seconds 60 --seed 0 --json sim.json

What runs is the whole simulated chain, on a manual clock (simulated time, never sleeping), as the
blind-test rig runs it: a simulated stylus (devices.simulated operator model, `pokes` script: raised-cosine
presses along the stylus -z) -> the loop (teleop.loop.Teleop at 1 kHz: mapping, kinematics, the `dynamic`
estimator with its Kalman filter, rendering) -> the pybullet slave (scenes.sim_robot.SimRobot: forward
kinematics, pybullet pad contact, tension distribution, capstan friction, FSR hysteresis and ADC), a robot
reading every `--substeps` ticks. Garbage collection is paused during the run, as in a session.

Reported: simulated, wall and CPU seconds [s], the real-time factors simulated / wall and simulated / CPU,
pass/fail against the 20x budget, and where the wall time goes, stage by stage (total [s], fraction, and
per tick [us] p50/p99), in the order of the data flow:
  stylus        the loop's READ stage: simulated operator (hand model) + state machine
  map           the loop's MAP stage: stylus -> target -> cable lengths
  kinematics    SimRobot.command_lengths: forward kinematics (lengths -> pose) and the new pose's terms
                (structure matrix, capstan wraps, tip target)
  pybullet_step pybullet's stepSimulation (the contact solver; 1 ms per step)
  physics_other the rest of PadWorld.advance (the steps, the contact force, the tip): series spring, contact
                and state queries
  cable_sensor  SimRobot.read minus PadWorld: contact wrench, tension distribution, capstan friction, FSR
                hysteresis and ADC, motor steps, the reading record
  robot_io      the rest of the loop's ROBOT stage
  estimate      the loop's ESTIMATE stage: FSR calibration, friction compensation, Kalman, safety monitors
  render, write, record   the loop's stages of those names
  loop_other    the tick outside its stages;  harness: clock and trajectory log, outside the tick.
The stages sum to the wall time. The robot's own stages (kinematics to cable_sensor) need timers inside the
robot that a session does not have (they cost time of their own): they run with `--stages` only; without it
those stages read 0, robot_io holds the whole ROBOT stage, and the real-time factor is the simulation's.

With the batch path (default; `--no-batch` skips it) the same commanded lengths, one row per reading, are
replayed through a fresh SimRobot's batched `run()` (the palpation path), timed the same way
(pybullet_step, physics_other; arrays: the rest), and its FSR counts compared with the loop's.

`--plant rich|distributed` runs the robot with that plant (`--cable-params` the distributed cable's TOML);
`--vs-matched` then also runs the loop path with the matched plant right after, in the same process, and
reports the plant's factor over the matched one's: on a shared machine the ratio of two runs made together
says more than either factor.

JSON: {"seed", "pad", "rate_hz", "robot_rate_hz", "substeps", "simulated_s", "wall_s", "cpu_s",
"realtime_factor", "realtime_factor_cpu", "budget_factor", "pass", "ticks", "readings", "physics_steps",
"stages_timed", "pybullet_timed", "stages": {stage: {"wall_s", "fraction", "per_tick_us": {"p50", "p99"}}},
"trajectory": {...},
"batch": {"simulated_s", "wall_s", "cpu_s", "realtime_factor", "realtime_factor_cpu", "pass", "readings",
"stages": {stage: {"wall_s", "fraction"}}, "counts_max_abs_diff_vs_loop"}}. Wall-clock numbers depend on
the machine's load; tests check only their consistency. With --plant other than matched, also "plant"; with
--vs-matched, "vs_matched": {"realtime_factor", "realtime_factor_cpu", "wall_s", "cpu_s" (the matched plant's
loop path), "ratio", "ratio_cpu" (this plant's factors over those)}.
"""

from __future__ import annotations

import argparse
import gc
import hashlib
import math
import os
import sys
import time

import numpy as np

from devices.simulated import OperatorParams, Script, SimulatedStylus
from scenes.fsr_lab import plant_fsr_calibration
from scenes.sim_robot import PLANTS
from teleop.apps.argtypes import add_geometry_option, geometry_of, input_file
from teleop.core.errors import InputError
from teleop.core.geometry import Geometry
from teleop.core.kernels.jit import bind
from teleop.core.kernels.tap import sim_log, sim_log_row_fixed
from teleop.core.mapping import POKE_WORKSPACE_MAX, MappingParams
from teleop.io.outputs import write_json
from teleop.loop import LoopParams, State, Teleop
from teleop.loop.devices_by_url import open_device
from teleop.loop.session import default_estimator, frame_period

BUDGET_FACTOR = 20.0  # docs/safety.md performance budget: simulation >= 20x real time when not paced
RATE_HZ = 1000.0  # loop rate [Hz] (the physics step is 1 ms too)
LOOP_STAGES = ("stylus", "map", "robot", "estimate", "render", "write", "record")  # teleop.loop.core.STAGES
STAGES = ("stylus", "map", "kinematics", "pybullet_step", "physics_other", "cable_sensor", "robot_io", "estimate",
          "render", "write", "record", "loop_other", "harness")


def register(subparsers) -> None:
    p = subparsers.add_parser("sim", help="simulation speed: stylus + loop + pybullet robot unpaced, x real time")
    p.add_argument("--seconds", type=float, default=60.0, help="simulated time [s] (default 60)")
    p.add_argument("--seed", type=int, default=0, help="seeds the stylus tremor and the FSR noise (default 0)")
    p.add_argument("--pad", default="z60", help="sim://robot pad name (default z60, the z-test pad)")
    p.add_argument("--substeps", type=int, default=1,
                   help="1 ms physics steps per robot reading; the robot link runs at 1 kHz / this (default 1)")
    p.add_argument("--depth-mm", type=float, default=30.0,
                   help="stylus poke depth [mm] (x motion scale 0.25 at the robot; the pad is 5 mm ahead)")
    p.add_argument("--period-s", type=float, default=2.0, help="poke period [s] (default 2)")
    p.add_argument("--plant", default="matched", choices=PLANTS,
                   help="the simulated robot's plant (sim://robot plant=): matched (default), rich, or distributed "
                        "(the distributed tendon-sheath cable, scenes/tendon_sheath.py)")
    p.add_argument("--cable-params", type=input_file, default=None, metavar="TOML",
                   help="with --plant distributed: the cable's [tendon_sheath] table (docs/formats.md)")
    p.add_argument("--vs-matched", action="store_true",
                   help="with --plant rich|distributed: also time the matched plant's loop path right after and report "
                        "the ratio of the two factors (JSON vs_matched)")
    p.add_argument("--no-batch", action="store_true", help="skip the batched SimRobot.run path")
    p.add_argument("--stages", action="store_true",
                   help="split the robot's time (kinematics .. cable_sensor) with timers inside it, which cost "
                        "~3 us a tick: the factor then includes them (the loop's own stages are always timed)")
    p.add_argument("--no-stages", action="store_true", help=argparse.SUPPRESS)  # the default; kept so older command lines parse
    p.add_argument("--json", metavar="F", help="write the result JSON here")
    add_geometry_option(p)
    p.set_defaults(func=run)


class CallTimer:
    """Wall time [ns] spent in wrapped calls; a call made inside another wrapped call of the same meter
    (PadWorld.step calling contact_force) is counted once."""

    def __init__(self):
        self.acc = [0, 0, False]  # wall time [ns], calls, inside a wrapped call (a list: the timer's closure cell)

    ns = property(lambda self: self.acc[0], doc="wall time in wrapped calls so far [ns]")
    calls = property(lambda self: self.acc[1], doc="wrapped calls so far (outermost ones)")

    def wrap(self, fn):
        """`fn` timed (positional arguments only: the robot's and the world's calls take no keywords)."""
        pc = time.perf_counter_ns
        acc = self.acc

        def timed(*args):
            if acc[2]:
                return fn(*args)
            acc[2] = True
            t0 = pc()
            try:
                return fn(*args)
            finally:
                acc[0] += pc() - t0
                acc[1] += 1
                acc[2] = False

        return timed


def _meter_world(world, meter: CallTimer, solver: CallTimer) -> bool:
    """Time the pybullet world's public calls with `meter` (instance attributes shadow the methods) and,
    inside them, pybullet's stepSimulation (PadWorld keeps it as `_step`) with `solver`. Only that one call
    is timed inside: a timer costs about as much as one of pybullet's small state queries on a slow
    machine. False when PadWorld no longer has `_step` (`solver` then stays at 0)."""
    for name in ("advance", "step", "contact_force", "tip"):
        setattr(world, name, meter.wrap(getattr(world, name)))
    if not callable(getattr(world, "_step", None)):
        return False
    world._step = solver.wrap(world._step)
    return True


def _make_robot(pad: str, seed: int, substeps: int, plant: str = "matched", cable_params: str | None = None,
                geometry: Geometry | None = None):
    url = f"sim://robot?pad={pad}&seed={seed}&substeps={substeps}"
    if plant != "matched":
        url += f"&plant={plant}"
    if cable_params is not None:
        url += f"&cable_params={cable_params}"
    try:
        return open_device(url, geometry=geometry)
    except InputError as exc:
        raise InputError(f"--pad/--substeps/--plant/--cable-params: {exc}") from None


def _seeds(seed: int) -> tuple[int, int]:
    """(robot seed, stylus seed) drawn from one SeedSequence."""
    robot_seed, stylus_seed = (int(s) for s in np.random.SeedSequence(seed).generate_state(2) % (2 ** 31))
    return robot_seed, stylus_seed


def _digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _pcts(ns: np.ndarray) -> dict:
    p50, p99 = np.percentile(ns / 1e3, [50, 99])
    return {"p50": round(float(p50), 3), "p99": round(float(p99), 3)}


def _factor(simulated: float, spent: float) -> float:
    return round(simulated / max(spent, 1e-9), 3)


def bench_sim(seconds: float = 60.0, seed: int = 0, pad: str = "z60", substeps: int = 1, depth: float = 0.030,
              period: float = 2.0, batch: bool = True, stages: bool = True, plant: str = "matched",
              cable_params: str | None = None, vs_matched: bool = False, geometry: Geometry | None = None) -> dict:
    """Run the unpaced simulation for `seconds` of simulated time [s]; the result dict (module docstring).

    depth: stylus poke depth [m]; period: poke period [s]; plant, cable_params: the robot's plant
    (scenes.sim_robot.PLANTS; the JSON's "plant" when not matched); vs_matched: with a plant other than matched,
    time the matched plant's loop path right after (JSON "vs_matched"); geometry: the robot's (None: the seed
    robot), for the simulated robot, the kinematics and the estimator."""
    n = int(round(seconds * RATE_HZ))
    robot_seed, stylus_seed = _seeds(seed)
    robot = _make_robot(pad, robot_seed, substeps, plant, cable_params, geometry)
    clock_t = [0.0]
    stylus = SimulatedStylus(Script(kind="pokes", amplitude=depth, period=period), OperatorParams(),
                             seed=stylus_seed, clock=lambda: clock_t[0])
    params = LoopParams(rate_hz=RATE_HZ, robot_rate_hz=None if substeps == 1 else RATE_HZ / substeps,
                        mapping=MappingParams(workspace_max=POKE_WORKSPACE_MAX))
    # the FSR calibration of the robot's plant (scenes.fsr_lab: on the distributed plant its own, as teleop session)
    estimator = default_estimator(frame_period(params, None), geometry=geometry,
                                  cal=plant_fsr_calibration(robot.params))
    kin, phys, solver, rd = CallTimer(), CallTimer(), CallTimer(), CallTimer()
    solver_timed = False
    n_read = -(-n // params.robot_every)
    Lf_log = np.zeros((n_read, 7))  # a reading's commanded lengths [m] and contact force along -z [N]
    L_log, f_truth = Lf_log[:, :6], Lf_log[:, 6]
    counts_log = np.zeros((n_read, 6), dtype=np.int64)
    pF_log = np.zeros((n, 6))  # a tick's stylus position [m] and force [N]
    p_log, F_log = pF_log[:, :3], pF_log[:, 3:]
    enabled = 0
    # a tick's timers [ns]: the loop's stages, the robot's cumulative kinematics, physics, stepSimulation and read,
    # the tick (one array: the log's kernel call checks each array argument's type)
    ns_log = np.zeros((n, len(LOOP_STAGES) + 5), dtype=np.int64)
    stage_ns, sub_ns, tick_ns = ns_log[:, :len(LOOP_STAGES)], ns_log[:, len(LOOP_STAGES):-1], ns_log[:, -1]
    with robot, stylus:
        if stages:
            robot.command_lengths = kin.wrap(robot.command_lengths)
            robot.read = rd.wrap(robot.read)
            solver_timed = _meter_world(robot.world, phys, solver)
        tp = Teleop(stylus, robot, params, geom=geometry, estimator=estimator)
        tp.start(0.0)
        log_row, no_L, no_counts = None, np.zeros(6), np.zeros(6, dtype=np.int64)  # log_row: bound at tick 0
        ka, pa, sa, ra = kin.acc, phys.acc, solver.acc, rd.acc  # the robot's timers [ns]: acc[0]
        dt = params.dt
        pc = time.perf_counter_ns
        enabled_state = State.ENABLED  # a local: the member's lookup on its class costs ~0.17 us
        j = 0
        gc.collect()
        gc.disable()
        try:
            cpu0, wall0 = time.process_time(), pc()
            for k in range(n):
                clock_t[0] = (k + 1) * dt
                t0 = pc()
                x = tp.tick(clock_t[0])
                t1 = pc()
                # the tick's row of every log in one compiled call (kernel tap.sim_log_row_fixed: the logs held
                # together, tap.sim_log)
                r = x.reading
                if log_row is None:  # the log's kernel bound to its argument types (jit.bind): the bench's arrays
                    logs = sim_log(tp.stage_ns, ns_log, pF_log, Lf_log, counts_log)
                    log_row = bind(sim_log_row_fixed, k, t1 - t0, logs, ka[0], pa[0], sa[0], ra[0], stylus.p, x.F, -1,
                                   no_L, no_counts, no_L)
                if r is not None:
                    log_row(k, t1 - t0, logs, ka[0], pa[0], sa[0], ra[0], stylus.p, x.F, j, r.commanded_lengths,
                            r.fsr_counts, r.wrench_truth)
                    j += 1
                else:
                    log_row(k, t1 - t0, logs, ka[0], pa[0], sa[0], ra[0], stylus.p, x.F, -1, no_L, no_counts, no_L)
                enabled += tp.state == enabled_state
            wall_ns, cpu = pc() - wall0, time.process_time() - cpu0
        finally:
            gc.enable()
        final_state, fault_reason = tp.state.name, tp.fault_reason
    simulated = n / RATE_HZ
    wall = wall_ns / 1e9
    sub = np.diff(np.vstack([np.zeros((1, 4), dtype=np.int64), sub_ns]), axis=0)
    kin_t, phys_t, solver_t, read_t = sub[:, 0], sub[:, 1], sub[:, 2], sub[:, 3]
    per_tick = {
        "stylus": stage_ns[:, 0], "map": stage_ns[:, 1], "kinematics": kin_t, "pybullet_step": solver_t,
        "physics_other": phys_t - solver_t, "cable_sensor": read_t - phys_t,
        "robot_io": stage_ns[:, 2] - kin_t - read_t, "estimate": stage_ns[:, 3],
        "render": stage_ns[:, 4], "write": stage_ns[:, 5], "record": stage_ns[:, 6],
        "loop_other": tick_ns - stage_ns.sum(axis=1),
    }
    table = {}
    for name in STAGES:
        if name == "harness":
            total = wall_ns - int(tick_ns.sum())
            pt = None
        else:
            v = per_tick[name]
            total, pt = int(v.sum()), _pcts(v)
        table[name] = {"wall_s": round(total / 1e9, 6), "fraction": round(total / wall_ns, 4), "per_tick_us": pt}
    factor = _factor(simulated, wall)
    contact = f_truth > 0.01
    out = {
        "seed": int(seed), "pad": pad, "rate_hz": RATE_HZ, "robot_rate_hz": RATE_HZ / params.robot_every,
        "substeps": int(substeps), "simulated_s": simulated, "wall_s": round(wall, 6), "cpu_s": round(cpu, 6),
        "realtime_factor": factor, "realtime_factor_cpu": _factor(simulated, cpu), "budget_factor": BUDGET_FACTOR,
        "pass": bool(factor >= BUDGET_FACTOR and final_state != "FAULT"),
        "ticks": n, "readings": j, "physics_steps": j * substeps,
        "stages_timed": bool(stages), "pybullet_timed": bool(solver_timed), "stages": table,
        "trajectory": {
            "sha256": _digest(L_log[:j], counts_log[:j], f_truth[:j], p_log, F_log),
            "final_state": final_state, "fault_reason": fault_reason, "enabled_s": enabled / RATE_HZ,
            "contacts": int(np.count_nonzero(contact[1:] & ~contact[:-1]) + (1 if j and contact[0] else 0)),
            "peak_contact_force_N": round(float(f_truth[:j].max(initial=0.0)), 6),
            "peak_stylus_force_N": round(float(np.linalg.norm(F_log, axis=1).max(initial=0.0)), 6),
        },
    }
    if plant != "matched":
        out["plant"] = plant
        if vs_matched:
            m = bench_sim(seconds, seed, pad, substeps, depth, period, batch=False, stages=stages, geometry=geometry)
            out["vs_matched"] = {"realtime_factor": m["realtime_factor"],
                                 "realtime_factor_cpu": m["realtime_factor_cpu"],
                                 "wall_s": m["wall_s"], "cpu_s": m["cpu_s"],
                                 "ratio": round(m["wall_s"] / max(wall, 1e-9), 4),
                                 "ratio_cpu": round(m["cpu_s"] / max(cpu, 1e-9), 4)}
    if batch:
        out["batch"] = bench_batch(np.ascontiguousarray(L_log[:j]), counts_log[:j], pad, robot_seed, substeps, plant,
                                   cable_params, geometry)
    return out


def bench_batch(lengths: np.ndarray, counts: np.ndarray, pad: str, robot_seed: int, substeps: int,
                plant: str = "matched", cable_params: str | None = None, geometry: Geometry | None = None) -> dict:
    """The same commanded lengths (n, 6) [m] through a fresh SimRobot.run (the palpation path), timed."""
    robot = _make_robot(pad, robot_seed, substeps, plant, cable_params, geometry)
    phys, solver = CallTimer(), CallTimer()
    with robot:
        _meter_world(robot.world, phys, solver)
        gc.collect()
        gc.disable()
        try:
            cpu0, wall0 = time.process_time(), time.perf_counter_ns()
            trace = robot.run(lengths)
            wall_ns, cpu = time.perf_counter_ns() - wall0, time.process_time() - cpu0
        finally:
            gc.enable()
    simulated = len(lengths) * robot.params.dt
    wall = wall_ns / 1e9
    factor = _factor(simulated, wall)
    table = {name: {"wall_s": round(ns / 1e9, 6), "fraction": round(ns / wall_ns, 4)}
             for name, ns in (("pybullet_step", solver.ns), ("physics_other", phys.ns - solver.ns),
                              ("arrays", wall_ns - phys.ns))}
    diff = int(np.abs(trace.counts - counts).max(initial=0))
    return {"simulated_s": simulated, "wall_s": round(wall, 6), "cpu_s": round(cpu, 6), "realtime_factor": factor,
            "realtime_factor_cpu": _factor(simulated, cpu), "pass": bool(factor >= BUDGET_FACTOR),
            "readings": len(lengths), "stages": table, "counts_max_abs_diff_vs_loop": diff}


def _check(args) -> None:
    s = args.seconds
    if not (math.isfinite(s) and 0 < s <= 3600):
        raise InputError(f"--seconds: expected a number of simulated seconds in (0, 3600], got {s}")
    n = round(s * RATE_HZ)
    if abs(n / RATE_HZ - s) > 1e-9 or n < 1:
        raise InputError(f"--seconds: expected a whole number of 1 ms loop ticks, got {s}")
    if not 1 <= args.substeps <= 100:
        raise InputError(f"--substeps: expected an integer in 1..100, got {args.substeps}")
    if n % args.substeps:
        raise InputError(f"--seconds: {s} s is not a whole number of robot readings of {args.substeps} ms")
    if not (math.isfinite(args.depth_mm) and 0 < args.depth_mm <= 60):
        raise InputError(f"--depth-mm: expected a poke depth in (0, 60] mm, got {args.depth_mm}")
    if not (math.isfinite(args.period_s) and 0 < args.period_s <= 60):
        raise InputError(f"--period-s: expected a poke period in (0, 60] s, got {args.period_s}")
    if not 0 <= args.seed < 2 ** 63:
        raise InputError(f"--seed: expected a non-negative integer, got {args.seed}")
    if args.vs_matched and args.plant == "matched":
        raise InputError("--vs-matched: expected --plant rich or distributed (it compares that plant with the "
                         "matched one)")


def format_table(out: dict) -> str:
    """The printed report: factors, budget verdict, per-stage wall time."""
    tr = out["trajectory"]
    lines = [f"simulated {out['simulated_s']:g} s ({out['ticks']} ticks at {out['rate_hz']:g} Hz, "
             f"{out['readings']} robot readings, {out['physics_steps']} physics steps) on pad {out['pad']}, "
             f"seed {out['seed']}: final state {tr['final_state']}"
             + (f" ({tr['fault_reason']})" if tr["fault_reason"] else "")
             + f", {tr['contacts']} contacts, peak contact force {tr['peak_contact_force_N']:.3f} N",
             f"{'path':8s} {'sim s':>8s} {'wall s':>8s} {'cpu s':>8s} {'x wall':>8s} {'x cpu':>8s}  budget "
             f">= {out['budget_factor']:g}x"]
    rows = [("loop", out)] + ([("batch", out["batch"])] if "batch" in out else [])
    for name, r in rows:
        lines.append(f"{name:8s} {r['simulated_s']:8.3f} {r['wall_s']:8.3f} {r['cpu_s']:8.3f} "
                     f"{r['realtime_factor']:8.2f} {r['realtime_factor_cpu']:8.2f}  {'PASS' if r['pass'] else 'FAIL'}")
    lines.append(f"loop wall time by stage{'' if out['stages_timed'] else ' (robot not split: --stages splits it)'}:")
    lines.append(f"  {'stage':13s} {'wall s':>8s} {'share':>7s} {'p50 us':>9s} {'p99 us':>9s}")
    for name, st in out["stages"].items():
        pt = st["per_tick_us"]
        p50, p99 = (f"{pt['p50']:9.1f}", f"{pt['p99']:9.1f}") if pt else (f"{'':9s}", f"{'':9s}")
        lines.append(f"  {name:13s} {st['wall_s']:8.3f} {100 * st['fraction']:6.1f}% {p50} {p99}")
    if "vs_matched" in out:
        v = out["vs_matched"]
        lines.append(f"matched plant's loop right after: {v['realtime_factor']:.2f}x wall, "
                     f"{v['realtime_factor_cpu']:.2f}x "
                     f"cpu; {out['plant']} / matched: {v['ratio']:.3f} (wall), {v['ratio_cpu']:.3f} (cpu)")
    if "batch" in out:
        b = out["batch"]
        parts = ", ".join(f"{k} {v['wall_s']:.3f} s ({100 * v['fraction']:.1f}%)" for k, v in b["stages"].items())
        lines.append(f"batch (SimRobot.run, same commanded lengths): {parts}; "
                     f"FSR counts vs loop: max |diff| {b['counts_max_abs_diff_vs_loop']}")
    return "\n".join(lines)


def run(args) -> int:
    _check(args)
    geometry = geometry_of(args)  # a bad file: one line before any run
    out = bench_sim(args.seconds, args.seed, args.pad, args.substeps, args.depth_mm * 1e-3, args.period_s,
                    batch=not args.no_batch, stages=args.stages and not args.no_stages, plant=args.plant,
                    cable_params=args.cable_params, vs_matched=args.vs_matched, geometry=geometry)
    if args.geometry:
        out["geometry_file"] = args.geometry
    print(format_table(out))
    if hasattr(os, "getloadavg"):  # context for the numbers: other processes sharing the cores
        print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cpus", file=sys.stderr)
    if args.json:
        write_json(args.json, out)
    return 0
