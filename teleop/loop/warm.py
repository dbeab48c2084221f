"""Compile (or load from numba's on-disk cache) every kernel the loop and the simulated robot call, with the
argument types they call them with, before the loop starts: the first tick must not pay for a compile.

    seconds = warm_up(geom)        # once per process (later calls return 0.0 at once)
    warm_up(say=None)              # silent (by default a cold cache is announced on stderr before compiling)
    warm_up(on_group=report)       # report(name, seconds) after each group (`teleop warm`)

A cold cache compiles each kernel (seconds, once per machine and source version); a warm one loads them
(well under a second, most of it numba's own start-up). The cache is cold when the kernels the last
complete warm-up dispatched (listed in WARMED_FILE beside numba's cache) are not all in numba's on-disk cache
for their current source, or when no warm-up completed there yet.
"""

from __future__ import annotations

import json
import os
import sys
import time
from types import SimpleNamespace

import numpy as np

from scenes import fsr_sensor_kernels, sim_robot_kernels, tendon_sheath_kernels
from scenes.fsr_sensor import FsrSensor
from scenes.sim_robot import DistributedCables
from scenes.sim_robot_kernels import fixed_fsr, reading_cables, reading_cables_fsr_fixed
from scenes.tendon_sheath import TendonSheathParams
from teleop.core.estimation.estimators import ESTIMATOR_NAMES, DynamicParams
from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.tick import LoopTick
from teleop.core.estimation.turn import AxisTurnFit, TurnCompensation
from teleop.core.geometry import default_geometry
from teleop.core.kernels import estimate, friction, geometry, kalman, mapping, operator, render, safety, sensor, \
    sheath, sim, tap, tension, ufuncs
from teleop.core.kernels import operator as KO
from teleop.core.kernels import sheath as SH
from teleop.core.kernels import sim as KS
from teleop.core.kernels import tap as KTap
from teleop.core.kernels import tension as KT
from teleop.core.kernels.geometry import forward_kinematics
from teleop.core.kernels.safety import all_finite, all_finite2
from teleop.core.kernels.tap import sim_log, sim_log_row_fixed, tap_row
from teleop.core.kinematics import FREE_AXIAL, check_lengths, lengths2pose, pose2lengths, poses2lengths, rotation_zyx, \
    structure_matrix
from teleop.core.mapping import MappingParams
from teleop.core.rendering import Renderer, engage_count
from teleop.core.sensors import FsrBranchLag, default_fsr_calibration
from teleop.core.tension import TensionSolver
from teleop.loop.safety import StuckCable, TensionRange, is_finite_reading, is_finite_sample, tension_monitors

_done = []  # [True] once warmed (the argument types do not depend on the geometry's values)
_MODULES = (estimate, friction, geometry, kalman, mapping, operator, render, safety, sensor, sheath, sim, tap, tension,
            ufuncs, tendon_sheath_kernels, fsr_sensor_kernels, sim_robot_kernels)


def kernels() -> list:
    """Every compiled kernel (numba dispatcher) of teleop.core.kernels and the simulated robot's distributed
    cable, its FSR alone and its fused reading (scenes.tendon_sheath_kernels, fsr_sensor_kernels, sim_robot_kernels)."""
    out = []
    for mod in _MODULES:
        out += [v for v in vars(mod).values() if hasattr(v, "py_func") and getattr(v, "__module__", "") == mod.__name__]
    return out


COLD_MESSAGE = "compiling kernels (first run only) ..."
WARMED_FILE = "teleop_warmed_kernels.json"  # in numba's cache directory: the kernels a complete warm-up dispatched


def _name(kernel) -> str:
    return f"{kernel.py_func.__module__}:{kernel.py_func.__qualname__}"


def _warmed_path() -> str:
    return os.path.join(kernels()[0]._cache._cache_path, WARMED_FILE)


def _cached(kernel) -> bool:
    """True when numba's on-disk cache holds `kernel` compiled from its current source."""
    try:
        return bool(kernel._cache._cache_file._load_index())
    except (AttributeError, OSError):
        return False


def cache_is_cold() -> bool:
    """True when warming up will compile: no complete warm-up recorded in numba's cache directory, or one
    of the kernels it dispatched is missing from the cache (first run, a new source version, another cache)."""
    try:
        with open(_warmed_path()) as f:
            names = set(json.load(f))
    except (OSError, ValueError):
        return True
    by_name = {_name(k): k for k in kernels()}
    return not names <= set(by_name) or not all(_cached(by_name[n]) for n in names)


def _record_warmed() -> None:
    """Write the names of the kernels this process dispatched (after a complete warm-up) to WARMED_FILE."""
    path = _warmed_path()
    tmp = f"{path}.{os.getpid()}"
    try:
        with open(tmp, "w") as f:
            json.dump(sorted(_name(k) for k in kernels() if k.signatures), f)
        os.replace(tmp, path)  # whole or not at all: processes warming at once never read half a list
    except OSError:  # a read-only cache: the next run says "compiling" again, nothing worse
        pass


def say_stderr(text: str) -> None:
    """One line on stderr, flushed."""
    print(text, file=sys.stderr, flush=True)


def warm_up(geom=None, say=say_stderr, on_group=None) -> float:
    """Run every hot-path kernel once with the loop's argument types (default geometry if None); seconds.

    say(text) (default: a line on stderr; None: silent) is told COLD_MESSAGE before anything compiles when
    the cache is cold; on_group(name, seconds) after each group of GROUPS."""
    if _done:
        return 0.0
    if say is not None and cache_is_cold():
        say(COLD_MESSAGE)
    geom = default_geometry() if geom is None else geom
    t0 = time.perf_counter()
    s = SimpleNamespace(geom=geom, n=len(geom.B))
    for name, group in GROUPS:
        t = time.perf_counter()
        group(s)
        if on_group is not None:
            on_group(name, time.perf_counter() - t)
    _done.append(True)
    _record_warmed()
    return time.perf_counter() - t0


def _loop(s) -> None:
    """The loop's path: mapping, FSR counts, estimate + Kalman, render, for every estimator."""
    geom, n = s.geom, s.n
    poly = tuple((0.0, 0.0) for _ in range(6))
    turn = TurnCompensation((AxisTurnFit(axis=2, duration=0.1, forward=poly, backward=poly),))
    dyn = DynamicParams(b=1.0, dahl_sigma=1e4, dahl_Fc=0.01)
    for name in ESTIMATOR_NAMES:  # the loop's path: mapping, FSR counts, estimate + Kalman, render
        for kal in (KalmanNoise(),):  # (no filter: the same array types)
            est = ReadingEstimator(geom, name, turn=turn, dynamic=dyn, kalman=kal)
            lt = LoopTick(geom, MappingParams(), est, Renderer())
            lt.renderer.enable()
            lt.engage(np.zeros(3))
            for k in range(3):
                est.update_arrays(np.full(n, 400.0 + k), np.zeros(6), 1e-3)
                est.update_arrays(np.full(n, 400 + k, dtype=np.int64), np.zeros(6), 1e-3)  # a robot's ADC counts
                lt.compute(np.full(3, 1e-4 * k), np.zeros(3), np.full(n, 400.0 + k), 1e-3)
                lt.compute(np.full(3, 1e-4 * k), np.zeros(3), np.full(n, 400.5 + k), 1e-3)  # a non-table count
                est.update_floats([400.0] * n, [0.0] * 6, 1e-3)
            # the loop's own stages (teleop.loop.core.Teleop: its anchors, pose view and lengths)
            L0 = lt.map(np.zeros(3), np.zeros(6), np.zeros(6)[:3], np.array(lt.follower.lengths(0.0, 0.0, 0.0)))
            lt.map(np.zeros(3), np.zeros(6), np.zeros(6)[:3], L0)
            lt.estimate(np.full(n, 400.0), np.zeros(6), 1e-3)
            lt.render(0.1, 0.0, 0.0, 1e-3, 0.0, 0.0, 0.0)
            est.tick.estimate([0.0] * 6, [2.0] * n, 1e-3)


def _sim_robot(s) -> None:
    """The simulated robot's reading: forward kinematics, pose terms, tension distribution, capstan chain."""
    geom, n = s.geom, s.n
    q = np.zeros(6)
    L = pose2lengths(q, geom)
    forward_kinematics(np.ascontiguousarray(L), q.copy(), FREE_AXIAL, geom.r, geom.B, 1e-12, 12)
    A, theta, tip = np.empty((6, n)), np.empty(n), np.empty(3)
    KS.pose_terms(q, geom.r, geom.B, np.asarray(geom.v, dtype=float), float(geom.theta0),
                  np.asarray(geom.tip, dtype=float), np.empty((n, 6)), A, theta, tip)
    # the sim robot's sheath (scenes.sim_robot.SimRobotParams.sheath): the seed robot's, on this geometry
    sc = SH.Sheath(mu=geom.mu, theta0=geom.theta0).constants()
    P = float(sc[SH.PRETENSION])  # tensions of the warm-up [N]
    f = -structure_matrix(q, geom) @ np.full(n, P)
    cap = SH.new_state(n)
    for _ in range(2):  # its first reading, then the next
        KS.cable_sensor(f, A, theta, -L, float(geom.t_min), float(geom.t_max), sc, cap, np.empty(n), np.empty(n))
    SH.motor_forces(cap, -L, np.full(n, P), theta, sc, np.empty(n))  # the reading when the kernel defers
    KS.contact_moment(tip, np.zeros(3), np.empty(6))
    KS.position_steps(L, L, 1e5, np.empty(n, dtype=np.int64))
    for implicit in (True, False):  # scenes.world.PadWorld.step: pybullet's tuples in, a tuple out
        KS.series_spring_force((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), np.zeros(3), 0.005, np.zeros((3, 3, 3)), 0.1,
                               (0.0, 0.0, 0.0), implicit)
    KS.pose_target(q, geom.r, geom.B, np.asarray(geom.v, dtype=float), float(geom.theta0),
                   np.asarray(geom.tip, dtype=float), np.empty((n, 6)), A, theta, tip, np.empty(3))
    # scenes.pose_follow.PoseFollower.follow: its fixed arguments held together, then the command
    fixed = KS.fixed_follow(float(geom.l_min), float(geom.l_max), q.copy(), FREE_AXIAL, geom.r, geom.B, 1e-12, 12, 1e-6,
                            np.asarray(geom.v, dtype=float), float(geom.theta0), np.asarray(geom.tip, dtype=float),
                            np.empty((n, 6)), A, theta, tip, np.empty(3))
    KS.follow_pose_fixed(np.ascontiguousarray(L), fixed)
    # the sim robot's reading (scenes.sim_robot.SimRobot.read): the contact force as pybullet's tuple
    kc = np.empty(KS.N_READING_CONST)
    kc[:SH.N_CONST] = sc
    kc[[KS.T_MIN, KS.T_MAX, KS.STEPS_PER_M]] = geom.t_min, geom.t_max, 1e5
    KS.reading(tip, (0.0, 0.0, 0.0), A, theta, -L, L, L, kc, SH.new_state(n), np.empty(6), np.empty(n),
               np.empty(n), np.empty(n, dtype=np.int64))
    for fsr in (True, False):  # with the FSR chain (the matched plant) and without (effects in between)
        KS.reading_counts(tip, (0.0, 0.0, 0.0), A, theta, -L, L, L, kc, SH.new_state(n), np.empty(6),
                          np.empty(n), np.empty(n), np.empty(n, dtype=np.int64), fsr,
                          *FsrBranchLag(default_fsr_calibration(), n).kernel_args(), np.zeros((1, n)), 0,
                          np.empty(n, dtype=np.int64))
    KS.conductance_loop(np.full(n, P), np.asarray(default_fsr_calibration().loading, dtype=float), np.empty(n))
    s.q, s.L, s.A, s.P = q, L, A, P
    s.tip, s.theta, s.kc = tip, theta, kc


def _cables(s) -> None:
    """The distributed cable (sim://robot?plant=distributed), a reading then a batch, and the FSR's lag."""
    n, P = s.n, s.P
    cables = DistributedCables(TendonSheathParams(), n, P, 1e-3)
    cables.step(np.zeros(n), np.full(n, P), np.zeros(n))
    cables.run(np.zeros((2, n)), np.full((2, n), P), np.zeros((2, n)))
    S, cab, p, T, rows = cables.kernel_args()  # its reading in one call (scenes.sim_robot_kernels)
    reading_cables(s.tip, (0.0, 0.0, 0.0), s.A, s.theta, s.L, s.L, s.kc, np.empty(6), np.empty(n),
                   np.empty(n, dtype=np.int64), s.L, S, cab, p, T, np.empty((rows, n)), rows - 1,
                   *FsrBranchLag(default_fsr_calibration(), n).kernel_args(), np.zeros((1, n)), 0,
                   np.empty(n, dtype=np.int64))
    lag = FsrBranchLag(default_fsr_calibration(), n)
    for _ in range(2):  # the first reading, then the lag
        lag.counts(np.full(n, P), np.zeros(n))
    cal = default_fsr_calibration()  # the distributed robot's FSR alone (SimRobotParams.fsr): a reading, a batch
    sensor_alone = FsrSensor(n, 0, cal=cal)
    fixed = fixed_fsr(s.tip, s.A, s.theta, s.L, s.kc, S, cab, p, T, rows - 1, *sensor_alone.kernel_args())
    reading_cables_fsr_fixed(fixed, (0.0, 0.0, 0.0), s.L, s.L, np.zeros((1, n)), 0, np.empty(6), np.empty(n),
                             np.empty(n, dtype=np.int64), np.empty((rows, n)), np.empty(n, dtype=np.int64))
    sensor_alone.counts_into(np.full((1, n), P), np.zeros((1, n)), np.empty((1, n), dtype=np.int64))
    sensor_alone.log_conductance(np.full((2, n), P))


def _safety(s) -> None:
    """The loop's safety monitors and finiteness checks (float and int arrays)."""
    n, P, L = s.n, s.P, s.L
    TensionRange(5.5, 0.2, 0.05, n).update(0.0, np.full(n, P))
    StuckCable(0.05, 0.3, 1e-7, n).update(0.0, np.full(n, P), np.zeros(n))
    tension_monitors(TensionRange(5.5, 0.2, 0.05, n), StuckCable(0.05, 0.3, 1e-7, n), 0.0, np.full(n, P), np.zeros(n))
    check = type("R", (), {"fsr_counts": np.zeros(n, dtype=np.int64), "position_steps": np.zeros(n, dtype=np.int64),
                           "commanded_lengths": L, "t": 0.0, "measured_cp": np.zeros(3), "measured_cv": np.zeros(3),
                           "orientation": np.eye(3)})()
    is_finite_reading(check)
    is_finite_sample(check)
    check.fsr_counts, check.position_steps = np.zeros(n), np.zeros(n)  # a ProcessRobot's reading: floats
    is_finite_reading(check)
    for a in (np.zeros(n), np.zeros(n, dtype=np.int64), np.zeros((3, n))[1, :6]):  # the loop's estimate check
        all_finite(a)
    all_finite2(np.zeros(n), np.zeros((3, n))[1, :6])  # the loop's estimate check (tensions, wrench)


def _operator(s) -> None:
    """The simulated operator (devices.simulated): one step with and without tremor."""
    c = np.zeros(KO.N_CONST)
    c[[KO.H, KO.M, KO.K, KO.B, KO.PERIOD, KO.DUTY]] = 1e-3, 0.15, 150.0, 6.0, 2.0, 0.5
    c[KO.HI:KO.HI + 3] = 1.0
    for tremor in (True, False):
        KO.operator_steps(np.zeros(9), 0.0, 0.0, 0.0, 0, 1, c, np.zeros((1, 3)), 0, tremor, np.zeros((0, 3)),
                          np.zeros((0, 2)))
    KO.script_offset(KO.POKES, 0.1, 0.01, 2.0, 0.5)


def _tap(s) -> None:
    """The recorder's tap (a reading's counts and steps as ints, inline robot, or floats, ProcessRobot) and
    teleop bench sim's log."""
    n, L = s.n, s.L
    o, w = np.arange(29, dtype=np.int64) * 16, np.full(29, 6, dtype=np.int64)
    w[[KTap.STAGES, KTap.ORIENT, KTap.CP, KTap.CV, KTap.SETPOINT, KTap.SERVO_CF]] = 7, 9, 3, 3, 3, 3
    for dt in (np.int64, np.float64):
        c6 = np.zeros(6, dtype=dt)
        tap_row(np.zeros(29 * 16), o, w, 0, 0.0, 0, 0, 0, np.zeros(7, dtype=np.int64), True, 0.0, np.zeros(3),
                np.zeros(3), np.eye(3), 1, True, True, np.zeros(6), L, True, 0.0, 0, c6, c6, L, 1, 0, True, L,
                np.zeros(6), np.zeros(6), 0.0, 0.0, 0.0, 0.0, np.zeros(3))
    logs = sim_log(np.zeros(7, dtype=np.int64), np.zeros((1, 12), dtype=np.int64), np.zeros((1, 6)),
                   np.zeros((1, n + 1)), np.zeros((1, n), dtype=np.int64))
    for j in (0, -1):  # teleop bench sim's log: a tick with a reading and one without
        sim_log_row_fixed(0, 0, logs, 0, 0, 0, 0, np.zeros(3), np.zeros(3), j, L, np.zeros(n, dtype=np.int64),
                          np.zeros(6))


def _around(s) -> None:
    """What the loop and the devices call around the ticks: length checks, the tension solver, the stylus's
    rotation, home lengths, the loop's first-engagement forward kinematics and its engage rule."""
    geom, q, L, A, P = s.geom, s.q, s.L, s.A, s.P
    f = -structure_matrix(q, geom) @ np.full(s.n, P)
    check_lengths(L, geom)
    TensionSolver(A, geom.t_min, geom.t_max, P).solve(f)
    rotation_zyx(0.0, 0.0, 0.0)
    poses2lengths(np.zeros((1, 6)), geom)
    lengths2pose(L, geom, guess=q)
    engage_count(0, 0.0, 0.0, 0.0, 0.2)
    KT.OK  # noqa: B018 - imported for the sim robot's status check


GROUPS = (("loop: mapping, estimators, rendering", _loop),
          ("simulated robot: kinematics, sheath, readings", _sim_robot),
          ("distributed cable, FSR lag", _cables),
          ("safety monitors", _safety),
          ("simulated operator", _operator),
          ("recorder tap, bench log", _tap),
          ("kinematics, tension solver, engage rule", _around))
