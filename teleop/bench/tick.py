"""`teleop bench tick --json F [--ticks N]`: time the compute of one loop tick without devices.

Project tick: `teleop.estimation.tick.TickComputer.compute` (plain floats, steady-state Kalman).
Reference tick: `ReferenceTick.compute`, the same computation written the obvious way: numpy on (6,)
arrays, scipy.spatial.transform.Rotation for R, the physics library's array functions, f = -A t with numpy,
filterpy KalmanFilter predict/update, the renderer. Both see the same inputs (a moving pose, noisy tensions
as numpy arrays), interleaved tick by tick (alternating which goes first) so machine noise hits both alike;
garbage collection is off while timing.
On a machine shared with other processes the wall-clock p99 measures the scheduler more than the tick:
`--clock cpu` times this thread's CPU time instead, and `--realtime 50` runs under SCHED_FIFO like the loop
(teleop.loop.timing.set_realtime).
JSON (DESIGN.md): {"ticks", "tick_us": {"p50","p99","max"}, "reference_tick_us": {"p50","p99","max"},
"speedup_p50"}.
"""

from __future__ import annotations

import numpy as np


def register(subparsers) -> None:
    p = subparsers.add_parser("tick", help="time one loop tick's compute (project vs plain numpy/scipy/filterpy)")
    p.add_argument("--json", metavar="F", help="write the DESIGN.md tick JSON here")
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
        from teleop.estimation.estimators import ESTIMATOR_NAMES, DynamicParams
        from teleop.estimation.kalman import FilterpyWrenchKalman, KalmanNoise, wrench_kalman_params
        from teleop.estimation.turn import TurnCompensator
        from teleop.rendering import Renderer

        self.geom = geom
        self.mode = ESTIMATOR_NAMES.index(estimator)
        self.dyn = dynamic or DynamicParams()
        self.turn = TurnCompensator(turn) if estimator == "double" else None
        self.kf = FilterpyWrenchKalman(wrench_kalman_params(geom, kalman or KalmanNoise()))
        self.renderer = renderer if renderer is not None else Renderer()
        self.reset()

    def reset(self) -> None:
        self.L_prev = None
        self.d = np.zeros(6)
        self.vel = np.zeros(6)
        self.F_dahl = np.zeros(6)
        self.phi = np.zeros(6)
        if self.turn is not None:
            self.turn.reset()
        self.kf.reset()
        self.renderer.reset()

    def compute(self, pose, tensions, dt: float, velocity=(0.0, 0.0, 0.0)):
        """(lengths (6,), wrench (6,), force (3,)) like TickComputer.compute."""
        from scipy.spatial.transform import Rotation

        from teleop.estimation.estimators import capstan_state
        from teleop.physics.capstan import motor2tip
        from teleop.physics.friction import viscous

        g, p = self.geom, self.dyn
        q = np.asarray(pose, dtype=float)
        t = np.asarray(tensions, dtype=float)
        R = Rotation.from_euler("ZYX", q[3:]).as_matrix()   # R = Rz(alpha) Ry(beta) Rx(gamma)
        Rr = g.r @ R.T
        l = q[:3] + Rr - g.B                                 # l_i = p + R r_i - B_i
        L = np.linalg.norm(l, axis=1)
        u = l / L[:, None]
        theta = np.abs(np.arcsin(np.clip(u @ g.v, -1.0, 1.0))) + g.theta0
        dL = np.zeros(6) if self.L_prev is None else L - self.L_prev
        self.d = np.where(dL != 0, np.sign(dL), self.d)     # cable direction, kept while still
        if self.mode in (1, 2):
            t = motor2tip(t, g.mu, theta, self.d <= 0)
        elif self.mode == 3:
            dx = -dL
            self.vel = self.vel + dt / (p.v_smooth + dt) * (dx / dt - self.vel)
            t = t - viscous(self.vel, p.b)
            if p.dahl_Fc > 0 and self.L_prev is not None:
                a = np.exp(-p.dahl_sigma * np.abs(dx) / p.dahl_Fc)
                self.F_dahl = a * self.F_dahl + np.sign(dx) * p.dahl_Fc * (1 - a)
                t = t - self.F_dahl
            self.phi = capstan_state(self.phi, dx, t, g.mu * theta, p.capstan_k)
            t = t * np.exp(-self.phi * g.mu * theta)
        self.L_prev = L
        A = np.vstack([-u.T, -np.cross(Rr, u).T])
        f = -A @ t                                           # f = -A t
        if self.turn is not None:
            f = f - self.turn.update(q[:3], dt)
        w = self.kf.update(f)
        return L, w, self.renderer.render(w, dt, velocity)


def _trajectory(n: int, dt: float, seed: int):
    """Moving poses (n, 6) and noisy tensions (n, 6) [N] for the benchmark (seeded)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    poses = np.zeros((n, 6))
    poses[:, 0] = 0.002 * np.sin(2 * np.pi * 0.7 * t)
    poses[:, 1] = 0.002 * np.cos(2 * np.pi * 0.5 * t)
    poses[:, 2] = 0.004 * np.sin(2 * np.pi * 0.3 * t)
    poses[:, 4] = 0.05 * np.sin(2 * np.pi * 0.2 * t)
    poses[:, 5] = 0.05 * np.cos(2 * np.pi * 0.25 * t)
    tensions = 2.85 + 0.3 * np.sin(2 * np.pi * 0.4 * t)[:, None] + rng.normal(0.0, 0.02, (n, 6))
    return poses, tensions


def _stats(ns: np.ndarray) -> dict:
    us = ns / 1e3
    return {"p50": round(float(np.percentile(us, 50)), 3), "p99": round(float(np.percentile(us, 99)), 3),
            "max": round(float(us.max()), 3)}


def bench_tick(ticks: int = 20000, estimator: str = "dynamic", seed: int = 0, warmup: int = 1000,
               clock: str = "wall") -> dict:
    """Interleaved timing of the project and reference ticks; the DESIGN.md JSON object.

    clock: "wall" (time.perf_counter_ns) or "cpu" (time.thread_time_ns: CPU time of this thread, so a tick
    preempted by another process is not charged for the wait).
    """
    import gc
    import time

    from teleop.estimation.estimators import DynamicParams
    from teleop.estimation.tick import TickComputer
    from teleop.estimation.turn import AxisTurnFit, TurnCompensation
    from teleop.geometry import default_geometry
    from teleop.rendering import Renderer, RenderParams

    geom = default_geometry()
    dt = 1e-3
    # realistic friction states (viscous, Dahl) and a turn fit so every stage does its work
    dyn = DynamicParams(b=5.0, dahl_sigma=2e4, dahl_Fc=0.05, v_smooth=0.005)
    poly = tuple((0.05, -0.1, 0.05, 0.0, 0.0) for _ in range(6))
    turn = TurnCompensation((AxisTurnFit(axis=2, duration=0.3, forward=poly, backward=poly),))
    rp = RenderParams(max_force=0.88, ramp_s=0.05)
    fast = TickComputer(geom, estimator, turn=turn, dynamic=dyn, renderer=Renderer(rp))
    ref = ReferenceTick(geom, estimator, turn=turn, dynamic=dyn, renderer=Renderer(rp))
    fast.renderer.enable()
    ref.renderer.enable()
    n = warmup + ticks
    poses, tensions = _trajectory(n, dt, seed)
    vel = np.zeros(3)
    t_fast = np.empty(n, dtype=np.int64)
    t_ref = np.empty(n, dtype=np.int64)
    clock = time.thread_time_ns if clock == "cpu" else time.perf_counter_ns
    gc.collect()
    gc.disable()
    try:
        for k in range(n):
            q, t = poses[k], tensions[k]
            if k & 1:
                t0 = clock()
                ref.compute(q, t, dt, vel)
                t1 = clock()
                fast.compute(q, t, dt, vel)
                t2 = clock()
                t_ref[k], t_fast[k] = t1 - t0, t2 - t1
            else:
                t0 = clock()
                fast.compute(q, t, dt, vel)
                t1 = clock()
                ref.compute(q, t, dt, vel)
                t2 = clock()
                t_fast[k], t_ref[k] = t1 - t0, t2 - t1
    finally:
        gc.enable()
    fs, rs = _stats(t_fast[warmup:]), _stats(t_ref[warmup:])
    return {"ticks": int(ticks), "tick_us": fs, "reference_tick_us": rs,
            "speedup_p50": round(rs["p50"] / fs["p50"], 3)}


def run(args) -> int:
    from teleop.errors import InputError
    from teleop.estimation.estimators import ESTIMATOR_NAMES
    from teleop.outputs import dumps_json, write_json

    if args.ticks < 1000:
        raise InputError(f"--ticks: expected an integer >= 1000, got {args.ticks}")
    if args.estimator not in ESTIMATOR_NAMES:
        raise InputError(f"--estimator: expected one of {', '.join(ESTIMATOR_NAMES)}, got '{args.estimator}'")
    import os
    import sys

    if args.realtime:
        from teleop.loop.timing import set_normal, set_realtime

        print(f"scheduling: {set_realtime(args.realtime)}", file=sys.stderr)
        try:
            result = bench_tick(args.ticks, args.estimator, args.seed, clock=args.clock)
        finally:
            set_normal()
    else:
        result = bench_tick(args.ticks, args.estimator, args.seed, clock=args.clock)
    if hasattr(os, "getloadavg"):  # context for the numbers: other processes sharing the cores
        print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cpus", file=sys.stderr)
    if args.json:
        write_json(args.json, result)
    print(dumps_json(result), end="")
    return 0
