"""`teleop bench tick --json F [--ticks N]`: time one full loop tick without devices.

Project tick: `teleop.core.estimation.tick.LoopTick.compute`, its `map`, `estimate` and `render` back to back:
the stages the loop (teleop.loop.core.Teleop) calls at MAP, ESTIMATE and RENDER: stylus position -> mapping
(motion scale, workspace clip, v_max step limit; teleop.core.mapping.Follower) -> cable lengths; FSR counts ->
tensions -> estimation with the steady-state Kalman filter in one compiled call (ReadingEstimator.update_arrays);
rendered stylus force (Renderer.render_tick).
Reference tick: `ReferenceLoopTick.compute`, the same path written the obvious way: teleop.core.mapping's numpy
functions and teleop.core.kinematics.pose2lengths, the FSR branch trigger and calibration tables on numpy arrays,
then `ReferenceTick` (numpy on (6,) arrays, scipy.spatial.transform.Rotation for R, the physics library's
array functions and the sheath's law (teleop.core.kernels.sheath), f = -A t with numpy, filterpy KalmanFilter
predict/update, the renderer). Both see the
same inputs (a stylus trajectory that hits the workspace box and the cable speed limit, FSR counts with
1 count RMS noise), interleaved tick by tick (alternating which goes first) so machine noise hits both alike;
garbage collection is off while timing.
On a machine shared with other processes the wall-clock p99 measures the scheduler more than the tick:
`--clock cpu` times this thread's CPU time instead, and `--realtime 50` runs under SCHED_FIFO like the loop
(teleop.loop.timing.set_realtime).
JSON (docs/formats.md): {"ticks", "tick_us": {"p50","p99","max"}, "reference_tick_us": {"p50","p99","max"},
"speedup_p50"}.
"""

from __future__ import annotations

import gc
import os
import sys
import time

import numpy as np
from scipy.spatial.transform import Rotation

from teleop.apps.argtypes import add_geometry_option, geometry_of
from teleop.core.errors import InputError
from teleop.core.estimation.estimators import ESTIMATOR_NAMES, DynamicParams
from teleop.core.estimation.kalman import FilterpyWrenchKalman, KalmanNoise, wrench_kalman_params
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.tick import LoopTick
from teleop.core.estimation.turn import AxisTurnFit, TurnCompensation, TurnCompensator
from teleop.core.geometry import Geometry, default_geometry
from teleop.core.kernels import sheath as SH
from teleop.core.kinematics import pose2lengths
from teleop.core.mapping import MappingParams, limit_lengths, stylus2target
from teleop.core.physics.capstan import motor2tip
from teleop.core.physics.friction import viscous
from teleop.core.rendering import Renderer, RenderParams
from teleop.core.sensors import LOADING, UNLOADING, default_fsr_calibration, synthesize_fsr_counts
from teleop.io.outputs import dumps_json, write_json
from teleop.loop.timing import set_normal, set_realtime


def register(subparsers) -> None:
    p = subparsers.add_parser("tick", help="time one full loop tick, devices excluded "
                                           "(project vs plain numpy/scipy/filterpy)")
    p.add_argument("--json", metavar="F", help="write the tick JSON here (keys: docs/formats.md)")
    add_geometry_option(p)
    p.add_argument("--ticks", type=int, default=20000, help="timed ticks of each kind (>= 1000; default 20000)")
    p.add_argument("--estimator", default="dynamic", help="estimator name (default: dynamic)")
    p.add_argument("--seed", type=int, default=0, help="seed of the tension noise")
    p.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                   help="wall: perf_counter (includes preemption by other processes); cpu: this thread's CPU "
                        "time (compute only; ~1 us clock-read overhead included)")
    p.add_argument("--realtime", type=int, default=0, metavar="PRIO",
                   help="run under SCHED_FIFO at this priority, as the loop does (0: no; default)")
    p.set_defaults(func=run)


class ReferenceTick:
    """The plain tick: numpy on (6,) arrays + scipy Rotation + filterpy KalmanFilter (12 states, started at
    the steady state). Same numbers as TickComputer (tested); deadband 0 cable directions."""

    def __init__(self, geom, estimator: str = "dynamic", *, turn=None, dynamic=None, kalman=None, renderer=None):
        self.geom = geom
        self.mode = ESTIMATOR_NAMES.index(estimator)
        self.dyn = dynamic or DynamicParams()
        self.sheath = SH.Sheath(mu=geom.mu, theta0=geom.theta0, stick_k=self.dyn.capstan_k)
        self._sc = self.sheath.constants()
        self.turn = TurnCompensator(turn) if estimator == "double" else None
        self.kf = FilterpyWrenchKalman(wrench_kalman_params(geom, kalman or KalmanNoise()))
        self.renderer = renderer if renderer is not None else Renderer()
        self.reset()

    def reset(self) -> None:
        self.L_prev = None
        self.d = np.zeros(6)
        self.vel = np.zeros(6)
        self.F_dahl = np.zeros(6)
        self.sheath_state = SH.new_state(6)
        if self.turn is not None:
            self.turn.reset()
        self.kf.reset()
        self.renderer.reset()

    def compute(self, pose, tensions, dt: float, velocity=(0.0, 0.0, 0.0)):
        """(lengths (6,), wrench (6,), force (3,)) like TickComputer.compute."""
        g, p, sh = self.geom, self.dyn, self.sheath
        q = np.asarray(pose, dtype=float)
        t = np.asarray(tensions, dtype=float)
        R = Rotation.from_euler("ZYX", q[3:]).as_matrix()   # R = Rz(alpha) Ry(beta) Rx(gamma)
        Rr = g.r @ R.T
        l = q[:3] + Rr - g.B                                 # l_i = p + R r_i - B_i
        L = np.linalg.norm(l, axis=1)
        u = l / L[:, None]
        theta = np.abs(np.arcsin(np.clip(u @ g.v, -1.0, 1.0))) + sh.theta0
        dL = np.zeros(6) if self.L_prev is None else L - self.L_prev
        self.d = np.where(dL != 0, np.sign(dL), self.d)     # cable direction, kept while still
        if self.mode in (1, 2):
            t = motor2tip(t, sh.mu, theta, self.d <= 0)
        elif self.mode == 3:
            dx = -dL
            self.vel = self.vel + dt / (p.v_smooth + dt) * (dx / dt - self.vel)
            t = t - viscous(self.vel, p.b)
            if p.dahl_Fc > 0 and self.L_prev is not None:
                a = np.exp(-p.dahl_sigma * np.abs(dx) / p.dahl_Fc)
                self.F_dahl = a * self.F_dahl + np.sign(dx) * p.dahl_Fc * (1 - a)
                t = t - self.F_dahl
            t = SH.tip_tensions(self.sheath_state, dx, t, theta, self._sc, np.empty(6))  # the sheath's inverse
        self.L_prev = L
        A = np.vstack([-u.T, -np.cross(Rr, u).T])
        f = -A @ t                                           # f = -A t
        if self.turn is not None:
            f = f - self.turn.update(q[:3], dt)
        w = self.kf.update(f)
        return L, w, self.renderer.render(w, dt, velocity)


class ReferenceLoopTick:
    """The full tick written the obvious way (numpy arrays throughout); same numbers as
    teleop.core.estimation.tick.LoopTick (tested). Mapping: stylus2target, kinematics.pose2lengths, the straight-line
    step limit and limit_lengths; FSR: a numpy Schmitt trigger on the counts and FsrCalibration.tension on
    arrays; then ReferenceTick at the commanded pose."""

    def __init__(self, geom, mapping, estimator: str = "dynamic", *, cal=None, deadband_counts: float = 8.0,
                 turn=None, dynamic=None, kalman=None, renderer=None, cmd_dt: float = 1e-3):
        self.geom, self.mapping = geom, mapping
        self.cal = cal if cal is not None else default_fsr_calibration()
        self.db = float(deadband_counts)
        self.dmax = geom.v_max * cmd_dt
        self.tick = ReferenceTick(geom, estimator, turn=turn, dynamic=dynamic, kalman=kalman, renderer=renderer)
        self.renderer = self.tick.renderer
        self.reset()

    def reset(self) -> None:
        self.pose = np.array(self.mapping.home, dtype=float)
        self.anchor_stylus = np.zeros(3)
        self.anchor_robot = self.pose[:3].copy()
        self.L_last = None
        self.branch_dir = np.zeros(6)
        self.branch_ext = np.full(6, np.nan)
        self.tick.reset()
        self._lengths = lambda q: pose2lengths(q, self.geom)

    def engage(self, p_stylus) -> None:
        self.anchor_stylus = np.array(p_stylus, dtype=float)
        self.anchor_robot = self.pose[:3].copy()
        if self.L_last is None:
            self.L_last = self._lengths(self.pose)

    def compute(self, p_stylus, v_stylus, counts, dt: float):
        """(L (6,), tensions (6,), wrench (6,), force (3,)) like LoopTick.compute."""
        g, m = self.geom, self.mapping
        q = self.pose.copy()
        q[:3] = stylus2target(p_stylus, self.anchor_stylus, self.anchor_robot, m)
        L = self._lengths(q)
        step = np.max(np.abs(L - self.L_last))
        if step > self.dmax:  # along the line from the last target, as far as v_max dt allows
            q[:3] = self.pose[:3] + (q[:3] - self.pose[:3]) * (self.dmax / step)
            L = self._lengths(q)
        L = np.clip(L, g.l_min, g.l_max)
        if np.max(np.abs(L - self.L_last)) > self.dmax:
            L = limit_lengths(L, self.L_last, g, self.dmax / g.v_max)
        self.pose, self.L_last = q, L
        # FSR branch: Schmitt trigger on the counts (estimation.direction), then the calibration tables
        c = np.asarray(counts, dtype=float)
        d, e = self.branch_dir, np.where(np.isnan(self.branch_ext), c, self.branch_ext)
        up = (d <= 0) & (c > e + self.db)
        down = ~up & (d >= 0) & (c < e - self.db)
        e = np.where(up | down, c, np.where(d > 0, np.maximum(e, c), np.where(d < 0, np.minimum(e, c), e)))
        self.branch_dir = d = np.where(up, 1.0, np.where(down, -1.0, d))
        self.branch_ext = e
        t = self.cal.tension(self.cal.counts2conductance(c), np.where(d < 0, UNLOADING, LOADING))
        _, w, F = self.tick.compute(q, t, dt, v_stylus)
        return L, t, w, F


def _trajectory(n: int, dt: float, seed: int, mapping=None, cal=None):
    """Stylus positions (n, 3) [m] and velocities (n, 3) [m/s] in the device frame, raw FSR counts (n, 6),
    seeded. The robot target the stylus asks for runs past the workspace box in x and faster than the cable
    speed limit around x = 0, so the clip and the step limit both act; tensions rise and fall per cable
    (both FSR branches) with 1 count RMS ADC noise."""
    m = mapping if mapping is not None else MappingParams()
    cal = cal if cal is not None else default_fsr_calibration()
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    w = 2 * np.pi * np.array([0.7, 0.5, 0.3])
    amp = np.array([0.006, 0.002, 0.004])  # robot target [m]
    target = amp * np.sin(w * t[:, None])
    target_v = amp * w * np.cos(w * t[:, None])
    back = m.R_reg.T / m.motion_scale  # robot displacement -> stylus displacement
    p_stylus, v_stylus = target @ back.T, target_v @ back.T
    phase = 2 * np.pi * 0.4 * t[:, None] + np.arange(6) * np.pi / 3
    tension = 2.85 + 0.3 * np.sin(2 * np.pi * 0.4 * t[:, None]) + 0.02 * np.sin(phase)  # [N]
    rate = 0.3 * np.cos(2 * np.pi * 0.4 * t[:, None]) + 0.02 * np.cos(phase)
    branch = np.where(rate < 0, UNLOADING, LOADING)
    counts = np.empty((n, 6))
    for b in (LOADING, UNLOADING):
        sel = branch == b
        counts[sel] = synthesize_fsr_counts(tension[sel], b, cal, rng=rng, noise_counts=1.0)
    return p_stylus, v_stylus, counts


def _stats(ns: np.ndarray) -> dict:
    us = ns / 1e3
    return {"p50": round(float(np.percentile(us, 50)), 3), "p99": round(float(np.percentile(us, 99)), 3),
            "max": round(float(us.max()), 3)}


def make_ticks(estimator: str = "dynamic", dt: float = 1e-3, geometry: Geometry | None = None):
    """(LoopTick, ReferenceLoopTick) with the loop's default mapping and FSR calibration, realistic friction
    states (viscous, Dahl) and a turn fit so every stage does its work, renderers enabled (ramping in at once,
    as in the loop) and the mapping engaged at the stylus origin; on `geometry` (None: the seed robot)."""
    geom, mapping, cal = geometry or default_geometry(), MappingParams(), default_fsr_calibration()
    dyn = DynamicParams(b=5.0, dahl_sigma=2e4, dahl_Fc=0.05, v_smooth=0.005)
    poly = tuple((0.05, -0.1, 0.05, 0.0, 0.0) for _ in range(6))
    turn = TurnCompensation((AxisTurnFit(axis=2, duration=0.3, forward=poly, backward=poly),))
    noise = KalmanNoise(dt=dt)
    rp = RenderParams(max_force=0.88, ramp_s=0.05, engage_ticks=0)  # as the loop: ramps in at once
    est = ReadingEstimator(geom, estimator, cal=cal, turn=turn if estimator == "double" else None, dynamic=dyn,
                           kalman=noise)
    fast = LoopTick(geom, mapping, est, Renderer(rp), cmd_dt=dt)
    ref = ReferenceLoopTick(geom, mapping, estimator, cal=cal, turn=turn if estimator == "double" else None,
                            dynamic=dyn, kalman=noise, renderer=Renderer(rp), cmd_dt=dt)
    for tk in (fast, ref):
        tk.renderer.enable()
        tk.engage(np.zeros(3))
    return fast, ref


def bench_tick(ticks: int = 20000, estimator: str = "dynamic", seed: int = 0, warmup: int = 1000,
               clock: str = "wall", geometry: Geometry | None = None) -> dict:
    """Interleaved timing of the project and reference full ticks; the JSON object of docs/formats.md
    (geometry: the robot's, None: the seed robot).

    clock: "wall" (time.perf_counter_ns) or "cpu" (time.thread_time_ns: CPU time of this thread, so a tick
    preempted by another process is not charged for the wait).
    """
    dt = 1e-3
    fast, ref = make_ticks(estimator, dt, geometry)
    n = warmup + ticks
    p_s, v_s, counts = _trajectory(n, dt, seed)
    t_fast = np.empty(n, dtype=np.int64)
    t_ref = np.empty(n, dtype=np.int64)
    clock = time.thread_time_ns if clock == "cpu" else time.perf_counter_ns
    gc.collect()
    gc.disable()
    try:
        for k in range(n):
            p, v, c = p_s[k], v_s[k], counts[k]
            # alternate which tick runs first, so neither always finds the caches the other left
            first, second = (ref, fast) if k & 1 else (fast, ref)
            t0 = clock()
            first.compute(p, v, c, dt)
            t1 = clock()
            second.compute(p, v, c, dt)
            t2 = clock()
            (t_ref if k & 1 else t_fast)[k], (t_fast if k & 1 else t_ref)[k] = t1 - t0, t2 - t1
    finally:
        gc.enable()
    fs, rs = _stats(t_fast[warmup:]), _stats(t_ref[warmup:])
    return {"ticks": int(ticks), "tick_us": fs, "reference_tick_us": rs,
            "speedup_p50": round(rs["p50"] / fs["p50"], 3)}


def run(args) -> int:
    if args.ticks < 1000:
        raise InputError(f"--ticks: expected an integer >= 1000, got {args.ticks}")
    if args.estimator not in ESTIMATOR_NAMES:
        raise InputError(f"--estimator: expected one of {', '.join(ESTIMATOR_NAMES)}, got '{args.estimator}'")
    geometry = geometry_of(args)
    if args.realtime:
        print(f"scheduling: {set_realtime(args.realtime)}", file=sys.stderr)
        try:
            result = bench_tick(args.ticks, args.estimator, args.seed, clock=args.clock, geometry=geometry)
        finally:
            set_normal()
    else:
        result = bench_tick(args.ticks, args.estimator, args.seed, clock=args.clock, geometry=geometry)
    if args.geometry:
        result["geometry_file"] = args.geometry
    if hasattr(os, "getloadavg"):  # context for the numbers: other processes sharing the cores
        print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cpus", file=sys.stderr)
    if args.json:
        write_json(args.json, result)
    print(dumps_json(result), end="")
    return 0
