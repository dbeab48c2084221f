"""Palpation tests of seed 000 §5.1 on the simulated robot: stiffness (Table 1), z (Fig 16a), x/y (Fig 16b,c)
and the E/P letter scan (Fig 17), with every estimator run on the same raw readings.

Each test is: a no-load back-and-forth run that fits the seed's turn compensation (step 3: 20 mm twice at
the palpation speed, along every axis the test pokes), then the pokes: the tip travels above the pad,
pokes along the test's axis to a commanded depth and back. One poke's value is the force along the poke
direction at its deepest commanded point (the seed reads its results there). Speed profiles: `uniform`
(0.5 mm/s, seed 000 test 1) or `variable` (random speeds 0.25-2 mm/s with short reversals on the way in
and out: the condition seed 000 §6 says its strategy handles badly).

The estimators share the FSR counts -> tension conversion and run the per-tick estimate at the commanded pose,
each with the same Kalman noise model (palpation_estimators.py). The pybullet scene, cable and sensor physics
live in scenes/.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, replace

import numpy as np

from scenes import pads
from scenes.fsr_lab import plant_fsr_calibration
from scenes.materials import ATTRIBUTION
from scenes.pads import SCAN_COLS, SCAN_ROWS, letter_mask
from scenes.rich_plant import RichPlant
from scenes.sim_robot import SimRobot, SimRobotParams, home_pose, with_named_plant
from scenes.world import PadWorld, WorldParams
from teleop.apps.protocols.palpation_estimators import ESTIMATORS, concat_traces, estimate, fsr_tensions, slice_trace
from teleop.apps.protocols.palpation_plots import plot_result
from teleop.apps.protocols.palpation_sensors import sensor_estimates, sensor_lines
from teleop.core.errors import InputError
from teleop.core.estimation.calibrate import fit_dynamic_params
from teleop.core.estimation.turn import TurnCompensation, fit_turn_compensation
from teleop.core.kinematics import poses2lengths
from teleop.io.progress import progress

TESTS = ("stiffness", "z", "xy", "scan")
PROFILES = ("uniform", "variable")
FIT_PAD_AWAY = 0.2  # [m] where the pad stage parks the pad during the no-load runs
AXES = {"+x": (0, 1.0), "-x": (0, -1.0), "+y": (1, 1.0), "-y": (1, -1.0), "+z": (2, 1.0)}
# seed 000 Table 1 [N], pokes 1-6 (regions black, black, red, red, yellow, yellow)
SEED_TABLE1 = {"region": ("black", "black", "red", "red", "yellow", "yellow"),
               "non_compensated": (4.72, 4.92, 4.61, 5.05, 4.40, 4.48),
               "double": (1.18, 1.21, 2.79, 2.74, 1.59, 1.50),
               "ground_truth": (1.02, 1.00, 2.32, 2.21, 1.44, 1.41)}


@dataclass(frozen=True)
class PalpationParams:
    """Protocol constants (SI).

    Attributes:
        speed: poke speed [m/s] (seed 000 §5.1 test 1: about 0.5 mm/s).
        travel_speed: speed of the moves between pokes, above the pad [m/s].
        clearance: tip height above the surface where pokes start [m].
        stiffness_loads: ((region, force [N]), ...) the load each stiffness-test poke brings its region to:
            the mean ground truth of seed 000 Table 1 (black 1.02/1.00, red 2.32/2.21, yellow 1.44/1.41 N).
            Table 1 gives no depths (its pokes were teleoperated at "an estimated 0.5 mm/s"); each poke's
            commanded depth is that load over the region's stiffness in series with the robot's
            (`load_depth`), so the estimators are compared at the seed's loads.
        depth_z, depth_scan: commanded depth past the surface [m] (scan: seed's 5 mm).
        depth_xy: commanded travel past first wall contact in the hole [m].
        repeats_z: repetitions of the 25-point z test (seed: 5).
        pokes_per_region: stiffness test pokes per region (Table 1: 2).
        pokes_xy: pokes each way in the hole (seed: 3).
        substeps: physics steps per reading (readings at 1 / (substeps physics_dt): 100 Hz).
        physics_dt: pybullet time step [s] (500 Hz: the contact is implicit and the tip's series spring
            has omega dt = 0.39, both stable; the calibration is measured at this step).
        fit_travel, fit_cycles: the turn-compensation run (seed 000 §4 step 3: 20 mm, twice; 10 mm here,
            what the default geometry can travel along z in front of the pad and still hold pretension).
        reach: largest distance from the axis the robot pokes at [m] (see `reach_scale`).
        fit_dynamic: calibrate the `dynamic` estimator's friction parameters on the same no-load runs
            (teleop.core.estimation.calibrate.fit_dynamic_params), as `double` fits its turn polynomials there.
        surface_z: z of the pad surface in {B} [m]: 1.5 mm past the home tip, so pokes span end-effector
            z from -2.5 to +4.5 mm, where the default geometry holds pretension under ~2.5 N (at +11 mm
            it does only within 1 mm of the axis).
        variable_speeds: (min, max) speeds of the variable profile [m/s].
        variable_reversal: (min, max) length of a reversal in the variable profile [m].
        turn_deadband: dead band of `double`'s turn detectors [m] (teleop.core.estimation.turn): 1 nm, far above
            the forward kinematics' round-off (along an axis the tip does not move, the pose wiggles by
            ~1e-17 m; with no dead band every wiggle was a turn, so the x and y fits fired through every z
            move) and far below one reading's travel (>= 2.5 um at 100 Hz and 0.25 mm/s).
        turn_level_tail: the last fraction of each half cycle of the no-load run whose mean is the settled
            level of `double`'s turn fit: 0.1, the wrench just before the next turn. Along y two cables'
            lengths pass an extremum at the hole's centre and reverse mid-stroke; the second half of the half
            cycle (the former level) held their transition, so the y fit never settled (a 20 s jump segment)
            and `double` read the y pokes high.
        sensor: the robot's tension sensors (teleop.core.sensors.SENSOR_KINDS): fsr (the FSR array, the four
            estimators), fbg (a distal FBG per cable) or one (the FSR array and cable 0's FBG, seed 001's
            sensor-model approach); teleop.apps.protocols.palpation_sensors.
        calibration: a `teleop calibrate fbg|one-sensor` file for the FBG kinds' estimator (None: seed 001's
            FBG constants, and for one Kp, Kr identified on the no-load runs).
    """

    speed: float = 0.5e-3
    travel_speed: float = 2e-3
    clearance: float = 1e-3
    stiffness_loads: tuple = (("black", 1.01), ("red", 2.265), ("yellow", 1.425))
    depth_z: float = 5e-3
    depth_scan: float = 5e-3
    depth_xy: float = 2.5e-3
    repeats_z: int = 5
    pokes_per_region: int = 2
    pokes_xy: int = 3
    substeps: int = 5
    physics_dt: float = 2e-3
    fit_travel: float = 0.010
    fit_cycles: int = 2
    variable_speeds: tuple = (0.25e-3, 2.0e-3)
    variable_reversal: tuple = (0.2e-3, 0.6e-3)
    reach: float = 0.006
    fit_dynamic: bool = True
    surface_z: float = 0.0235
    turn_deadband: float = 1e-9
    turn_level_tail: float = 0.1
    sensor: str = "fsr"
    calibration: str | None = None


@dataclass(frozen=True)
class PlannedPoke:
    """One poke: `label` (region, point or cell), `xy` in the pad frame [m], direction "+z", "+x", ...;
    `depth` [m] past the surface overrides the session's depth when given."""

    label: str
    xy: tuple
    direction: str = "+z"
    repeat: int = 0
    depth: float | None = None


# --------------------------------------------------------------------------------------------------------
# trajectories (tip positions in {B}; the pose is the tip minus the tool offset, no rotation)
# --------------------------------------------------------------------------------------------------------

def line(a, b, speed: float, dt: float) -> np.ndarray:
    """(n, 3) points from a (excluded) to b (included) at `speed` [m/s], one per dt [s]."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    n = max(1, int(math.ceil(np.linalg.norm(b - a) / (speed * dt))))
    s = np.arange(1, n + 1)[:, None] / n
    return a + s * (b - a)


def stroke(a, b, profile: str, p: PalpationParams, dt: float, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) a -> b along a poke: uniform at p.speed, or variable (random speeds, short reversals)."""
    if profile == "uniform":
        return line(a, b, p.speed, dt)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    total = float(np.linalg.norm(b - a))
    u = (b - a) / total
    parts, s = [], 0.0
    pos = a
    while s < total - 1e-9:
        chunk = min(total - s, rng.uniform(0.5e-3, 1.5e-3))
        nxt = a + u * (s + chunk)
        parts.append(line(pos, nxt, rng.uniform(*p.variable_speeds), dt))
        s += chunk
        pos = nxt
        if s < total - 1e-9 and rng.random() < 0.6:  # a reversal, then on again
            back = pos - u * min(s, rng.uniform(*p.variable_reversal))
            parts.append(line(pos, back, rng.uniform(*p.variable_speeds), dt))
            parts.append(line(back, pos, rng.uniform(*p.variable_speeds), dt))
    return np.vstack(parts)


@dataclass
class Plan:
    """A trajectory of tip positions (n, 3) [m] and, per poke, the index of its deepest commanded point."""

    tips: np.ndarray
    deepest: list
    pokes: list
    starts: list


def plan_pokes(pokes, surface_z: float, start_tip, p: PalpationParams, depth: float, profile: str, dt: float,
               rng: np.random.Generator, hole: dict | None = None, scale: float = 1.0) -> Plan:
    """Tip path visiting every poke from `start_tip` (3,) [m]; the tip goes to scale * poke.xy (the pad is
    slid by (scale - 1) * poke.xy, see `reach_scale`). `starts[i]` is where poke i's segment begins.

    z pokes: travel to (x, y, surface - clearance), stroke to surface + depth, stroke back. Hole pokes
    (`hole` = {"z": tip height in the hole, "contact": free travel to the wall [m]}): travel above the hole
    centre, descend into it, stroke along the direction to contact + depth, stroke back, rise out.
    """
    parts = [np.asarray(start_tip, dtype=float)[None]]
    deepest, starts = [], []
    cur = parts[0][0]
    above = surface_z - p.clearance
    for pk in pokes:
        starts.append(sum(len(q) for q in parts))
        x, y = scale * pk.xy[0], scale * pk.xy[1]
        if pk.direction == "+z":
            start = np.array([x, y, above])
            far = np.array([x, y, surface_z + (depth if pk.depth is None else pk.depth)])
        else:
            axis, sign = AXES[pk.direction]
            start = np.array([x, y, hole["z"]])
            far = start.copy()
            far[axis] += sign * (hole["contact"] + depth)
            top = np.array([x, y, above])
            if np.linalg.norm(cur - top) > 1e-9 and np.linalg.norm(cur - start) > 1e-9:
                parts.append(line(cur, top, p.travel_speed, dt))
                cur = top
        if np.linalg.norm(cur - start) > 1e-9:
            # rise to travel height first, then across, then down (never drag the tip through the pad)
            lift = np.array([cur[0], cur[1], min(cur[2], above)])
            for target in (lift, np.array([start[0], start[1], lift[2]]), start):
                if np.linalg.norm(cur - target) > 1e-9:
                    parts.append(line(cur, target, p.travel_speed, dt))
                    cur = target
        parts.append(stroke(start, far, profile, p, dt, rng))
        deepest.append(sum(len(q) for q in parts) - 1)
        parts.append(stroke(far, start, profile, p, dt, rng))
        cur = start
    tips = np.vstack(parts)
    return Plan(tips=tips, deepest=deepest, pokes=list(pokes), starts=starts)


def reach_scale(pokes, reach: float) -> float:
    """Fraction s of each poke's pad position the robot travels (the rest is slid by the pad stage):
    min(1, reach / largest poke radius). The default geometry (20 mm scaffold ring, anchors on the shaft)
    holds pretension only within about 9 mm of the axis, less under load, while the seed's pads span
    27-60 mm; sliding the pad keeps every poke inside the robot's tensionable workspace while the robot
    still visits s x the seed's layout."""
    r = max((math.hypot(*pk.xy) for pk in pokes), default=0.0)
    return 1.0 if r <= reach else reach / r


def fit_path(start_tip, axis: int, p: PalpationParams, dt: float, direction: float = -1.0) -> np.ndarray:
    """(n, 3) no-load back-and-forth run: from start, `fit_travel` along `direction` of `axis` and back,
    `fit_cycles` times, at the palpation speed (seed 000 §4 step 3)."""
    a = np.asarray(start_tip, dtype=float)
    b = a.copy()
    b[axis] += direction * p.fit_travel
    parts = []
    for _ in range(p.fit_cycles):
        parts += [line(a, b, p.speed, dt), line(b, a, p.speed, dt)]
    return np.vstack(parts)


def _num(x) -> float:
    return float(round(float(x), 6))


# --------------------------------------------------------------------------------------------------------
# the tests
# --------------------------------------------------------------------------------------------------------

@dataclass
class Session:
    """One robot run: a pad, its pokes, the commanded depth and the axes the turn compensation is fitted on."""

    name: str
    pad: object
    pokes: list
    depth: float
    fit_axes: tuple


def load_depth(pad, xy, load: float, tip_stiffness: float | None, tip_radius: float) -> float:
    """Commanded depth [m] past the surface that loads the pad at xy (2,) [m] with `load` [N]: the pad's
    target contact stiffness in series with the robot's tip stiffness [N/m] (None: rigid robot)."""
    k = pad.stiffness_at(np.asarray(xy, dtype=float), tip_radius)
    if tip_stiffness is not None:
        k = k * tip_stiffness / (k + tip_stiffness)
    return float(load / k)


def sessions_for(test: str, p: PalpationParams, limit: int | None = None, tip_stiffness: float | None = None,
                 tip_radius: float = 0.0015) -> list:
    """The robot runs of a test (scan: one per letter). `limit` keeps the first pokes of each (short runs).
    `tip_stiffness` [N/m] and `tip_radius` [m] of the simulated robot set the stiffness test's depths."""
    if test == "stiffness":
        pad = pads.three_region_pad()
        loads = dict(p.stiffness_loads)
        pokes = [PlannedPoke(lab, pad.points[lab], "+z", r, load_depth(pad, pad.points[lab], loads[lab], tip_stiffness,
                                                                 tip_radius))
                 for lab in ("black", "red", "yellow") for r in range(p.pokes_per_region)]
        out = [Session("stiffness3", pad, pokes, 0.0, (2,))]
    elif test == "z":
        pad = pads.z_test_pad()
        pokes = [PlannedPoke(lab, xy, "+z", r) for r in range(p.repeats_z) for lab, xy in pad.points.items()]
        out = [Session("z60", pad, pokes, p.depth_z, (2,))]
    elif test == "xy":
        pad = pads.hole_pad()
        pokes = [PlannedPoke(d, (0.0, 0.0), d, r) for pair in (("+x", "-x"), ("+y", "-y")) for r in range(p.pokes_xy)
                 for d in pair]
        out = [Session("hole27", pad, pokes, p.depth_xy, (0, 1, 2))]
    elif test == "scan":
        out = []
        for letter in ("E", "P"):
            pad = pads.letter_pad(letter)
            grid = pads.scan_grid()
            pokes = []
            for r in range(grid.shape[0]):
                cols = range(grid.shape[1]) if r % 2 == 0 else reversed(range(grid.shape[1]))  # serpentine
                pokes += [PlannedPoke(f"r{r}c{c}", (float(grid[r, c, 0]), float(grid[r, c, 1])), "+z", 0) for c in cols]
            out.append(Session(f"letter_{letter}", pad, pokes, p.depth_scan, (2,)))
    else:
        raise InputError(f"unknown palpation test '{test}' (expected one of: {', '.join(TESTS)})")
    if limit is not None:
        for s in out:
            s.pokes = s.pokes[:limit]
    return out


def _fit_plan(home_tip, axes, p: PalpationParams, dt: float, surface_z: float, hole: dict | None):
    """Tip path of the no-load turn-compensation runs and the (start, stop) index of each axis' run.

    Like the seed's step 3 run ("without payload"), it sweeps the region the pokes use with the pad slid
    out of the way: along z from the poke start height (clearance above the surface) forward by
    fit_travel and back; along x / y +-fit_travel/2 around the hole centre at the hole poke height.
    """
    parts = [np.asarray(home_tip, dtype=float)[None]]
    spans = {}
    cur = parts[0][0]
    for axis in axes:
        start = np.asarray(home_tip, dtype=float).copy()
        if axis == 2:
            start[2] = surface_z - p.clearance
            direction = 1.0
        else:
            start[2] = hole["z"] if hole is not None else surface_z - p.clearance
            start[axis] += p.fit_travel / 2
            direction = -1.0
        if np.linalg.norm(cur - start) > 1e-9:
            parts.append(line(cur, start, p.travel_speed, dt))
        n0 = sum(len(q) for q in parts)
        parts.append(fit_path(start, axis, p, dt, direction))
        spans[axis] = (n0, sum(len(q) for q in parts))
        cur = start
    back = np.asarray(home_tip, dtype=float).copy()
    back[2] = surface_z - p.clearance
    if np.linalg.norm(cur - back) > 1e-9:  # end above the pad centre, at the poke start height
        parts.append(line(cur, back, p.travel_speed, dt))
    return np.vstack(parts), spans


@dataclass
class PalpationResult:
    """The outcome of one test: per-poke values [N], summary per estimator, test-specific extras."""

    test: str
    profile: str
    seed: int
    params: dict
    pokes: list
    summary: dict
    extra: dict
    simulated_s: float
    wall_s: float
    cpu_s: float = 0.0

    def to_json(self) -> dict:
        """The JSON object of docs/formats.md (wall time left out: same seed, same bytes)."""
        return {"test": self.test, "speed_profile": self.profile, "seed": self.seed,
                "estimators": list(ESTIMATORS), "pokes": self.pokes, "summary": self.summary, **self.extra,
                "simulated_s": _num(self.simulated_s), "params": self.params, "attribution": ATTRIBUTION}

    def table(self) -> str:
        """Plain-text table of the pokes and the summary."""
        names = ("truth",) + ESTIMATORS
        widths = [max(len(n), 9) for n in names]
        head = f"{'#':>3} {'poke':<8} {'dir':<3} " + " ".join(f"{n:>{w}}" for n, w in zip(names, widths))
        lines = ["contact force along the poke [N]: the pad's ground truth and each estimator's", head]
        for i, pk in enumerate(self.pokes, 1):
            vals = [pk["ground_truth_N"]] + [pk[f"{n}_N"] for n in ESTIMATORS]
            lines.append(f"{i:>3} {pk['label']:<8} {pk['direction']:<3} "
                         + " ".join(f"{v:{w}.3f}" for v, w in zip(vals, widths)))
        lines.append("")
        if "plant" in self.extra:
            lines.append(f"plant: {self.extra['plant']['name']}")
        lines.append(f"{'estimator':<16} {'MAE [N]':>8} {'RMSE [N]':>9}")
        for n in ESTIMATORS:
            s = self.summary[n]
            lines.append(f"{n:<16} {s['mean_abs_error_N']:8.3f} {s['rmse_N']:9.3f}")
        if self.params.get("sensor", "fsr") != "fsr":
            lines += sensor_lines(self)
        if "ranks_correctly" in self.extra:
            lines.append("ranks the pads in their true stiffness order: " + ", ".join(
                f"{n} {'yes' if ok else 'no'}" for n, ok in self.extra["ranks_correctly"].items()))
        if "contrast" in self.extra:
            lines += ["", "scan contrast: mean force over the letters (rigid) and the silicone",
                      f"{'estimator':<16} {'rigid [N]':>9} {'silicone [N]':>12} {'ratio':>6}"]
            for n, c in self.extra["contrast"].items():
                cells = [c["rigid_mean_N"], c["silicone_mean_N"], c["ratio"]]
                shown = ["-" if v is None else f"{v:.3f}" for v in cells]
                lines.append(f"{n:<16} {shown[0]:>9} {shown[1]:>12} {shown[2]:>6}")
        if "load_response" in self.extra:
            lr, sd = self.extra["load_response"], self.extra["seed_table1_load_response"]
            lines.append("load response (estimate = offset + gain x truth): "
                         + ", ".join(f"{n} {v['offset_N']:.2f} + {v['gain']:.2f} F" for n, v in lr.items()))
            lines.append("seed 000 Table 1, same fit: "
                         + ", ".join(f"{n} {v['offset_N']:.2f} + {v['gain']:.2f} F" for n, v in sd.items()))
        rt = self.simulated_s / self.wall_s if self.wall_s > 0 else float("inf")
        rc = self.simulated_s / self.cpu_s if self.cpu_s > 0 else float("inf")
        lines.append(f"simulated {self.simulated_s:.1f} s in {self.wall_s:.1f} s wall ({rt:.1f}x real time), "
                     f"{self.cpu_s:.1f} s CPU ({rc:.1f}x)")
        return "\n".join(lines)

    def plot(self):
        """A matplotlib figure (Fig 15/16-like bars, or Fig 17-like images for the scan)."""
        return plot_result(self)


def run_test(test: str, profile: str = "uniform", seed: int = 0, params: PalpationParams = PalpationParams(),
             limit: int | None = None, progress: bool = False, plant: str = "matched",
             cable_params=None, geometry=None, no_load: bool = False) -> PalpationResult:
    """Run a palpation test on the simulated robot (see the module docstring). `plant`: "matched" (the
    robot's physics is the estimators' model), "rich" (scenes.rich_plant's effects on top, drawn from
    `seed`) or "distributed" (scenes.tendon_sheath's cable, its parameters from the TOML `cable_params`
    or its defaults). `geometry` (teleop.core.geometry.Geometry; None: the seed robot) is the simulated robot's
    and the estimators'. `no_load`: also report every estimator's wrench over the no-load runs (the robot-level
    seed 000 Fig 13, `no_load_errors`) as extra["no_load"]."""
    if profile not in PROFILES:
        raise InputError(f"unknown speed profile '{profile}' (expected one of: {', '.join(PROFILES)})")

    sim = with_named_plant(SimRobotParams(substeps=params.substeps,
                                          world=WorldParams(surface_z=params.surface_z, dt=params.physics_dt),
                                          **({} if geometry is None else {"geometry": geometry})),
                           plant, seed, cable_params)
    sessions = sessions_for(test, params, limit, sim.tip_stiffness, sim.world.tip_radius)

    sim = replace(sim, sensor=params.sensor)  # the robot's sensor kind (scenes.sim_sensors)
    # the FSR calibration the estimators convert with: on the distributed plant the one fitted on a simulated
    # calibration platform of that plant and its FSR alone (scenes.fsr_lab), else the built-in one
    fsr_cal = plant_fsr_calibration(sim)
    t_wall, t_cpu = time.perf_counter(), time.process_time()
    ss = np.random.SeedSequence(int(seed))
    seeds = ss.generate_state(2 * len(sessions))
    geom, dt = sim.geometry, sim.dt
    tool = np.asarray(geom.tip)
    home_tip = home_pose()[:3] + tool
    surface = sim.world.surface_z
    plans = []
    for i, s in enumerate(sessions):
        rng = np.random.default_rng(int(seeds[2 * i + 1]))
        hole = None
        if s.pad.hole_radius > 0:
            proxy = PadWorld(s.pad, sim.world).proxy_radius
            hole = {"z": surface + s.pad.thickness / 2 + proxy, "contact": s.pad.hole_radius - proxy}
        fit_tips, spans = _fit_plan(home_tip, s.fit_axes, params, dt, surface, hole)
        scale = reach_scale(s.pokes, params.reach)
        plan = plan_pokes(s.pokes, surface, fit_tips[-1], params, s.depth, profile, dt, rng, hole, scale)
        plans.append((fit_tips, spans, plan, scale))
    total = sum(len(f) + len(pl.tips) for f, _, pl, _ in plans)
    bar = _progress_bar(progress, 2 * total, f"palpate {test}")
    results, extra_grids, calib, extra_no_load = [], {}, {}, {}
    try:
        for i, (s, (fit_tips, spans, plan, scale)) in enumerate(zip(sessions, plans)):
            with SimRobot(s.pad, sim, seed=int(seeds[2 * i])) as robot:
                robot.set_pad_offset((FIT_PAD_AWAY, 0.0))  # no payload: the pad slid out of the way
                fit_trace = robot.run(_tips2lengths(fit_tips, tool, geom), progress=bar.update)
                bounds = plan.starts + [len(plan.tips)]
                parts = []
                for j, pk in enumerate(plan.pokes):
                    robot.set_pad_offset(((scale - 1.0) * pk.xy[0], (scale - 1.0) * pk.xy[1]))
                    seg = plan.tips[bounds[j]:bounds[j + 1]]
                    parts.append(robot.run(_tips2lengths(seg, tool, geom), progress=bar.update))
            poke_trace = concat_traces(parts)
            # the seed's step 3 fit on the no-load runs (single-compensated, unfiltered wrench)
            single = estimate(fit_trace, geom, dt, names=("single",), kalman=False, progress=bar.update,
                              cal=fsr_cal)["single"]
            fits = tuple(fit_turn_compensation(fit_trace.t[a:b], fit_trace.poses[a:b], single[a:b], axis=axis,
                                               deadband=params.turn_deadband, level_tail=params.turn_level_tail)
                         for axis, (a, b) in spans.items())
            dyn = None
            if params.fit_dynamic:  # the project's estimator calibrated on the same no-load runs
                a, b = min(v[0] for v in spans.values()), max(v[1] for v in spans.values())
                dyn = fit_dynamic_params(geom, fit_trace.poses[a:b],
                                         fsr_tensions(slice_trace(fit_trace, a, b), fsr_cal), dt)
            w = estimate(poke_trace, geom, dt, turn=TurnCompensation(axes=fits), progress=bar.update, dynamic=dyn,
                         cal=fsr_cal)
            if no_load:  # seed 000 Fig 13 at robot level: the wrench of the run the turn polynomials are fitted on
                w_fit = estimate(fit_trace, geom, dt, turn=TurnCompensation(axes=fits), dynamic=dyn, cal=fsr_cal)
                extra_no_load[s.name] = {"xyz"[axis]: no_load_errors(w_fit, fit_trace.poses, a, b, axis,
                                                                      fits[i].duration, dt)
                                         for i, (axis, (a, b)) in enumerate(spans.items())}
            calib[s.name] = {"turn_duration_s": {"xyz"[f.axis]: _num(f.duration) for f in fits},
                             "dynamic": None if dyn is None else {k: _num(v) for k, v in asdict(dyn).items()}}
            if params.sensor != "fsr":  # the FBG kinds' estimate replaces the FSR array's
                w, calib[s.name]["sensor"] = sensor_estimates(params.sensor, fit_trace, spans, poke_trace, geom, dt,
                                                              sim.fbg_cable, progress=bar.update,
                                                              calibration=params.calibration)
            offset = plan.starts[0]
            for pk, k in zip(plan.pokes, plan.deepest):
                k = k - offset
                axis, sign = AXES[pk.direction]
                u = np.zeros(3)
                u[axis] = sign
                row = {"session": s.name, "label": pk.label, "repeat": pk.repeat, "direction": pk.direction,
                       "xy_mm": [_num(pk.xy[0] * 1e3), _num(pk.xy[1] * 1e3)],
                       "depth_mm": _num((s.depth if pk.depth is None else pk.depth) * 1e3),
                       "ground_truth_N": _num(-(poke_trace.wrench_truth[k, :3] @ u))}
                for n in ESTIMATORS:
                    row[f"{n}_N"] = _num(-(w[n][k, :3] @ u))
                results.append(row)
            if test == "scan":
                extra_grids[s.name[-1]] = _grid(s, results)
    finally:
        bar.close()
    total = sum(len(f) + len(pl.tips) - pl.starts[0] for f, _, pl, _ in plans)
    wall, cpu = time.perf_counter() - t_wall, time.process_time() - t_cpu
    simulated = total * dt
    summary = summarise(results)
    extra = {}
    if test == "stiffness":
        extra = stiffness_extras(results)
    elif test == "scan":
        extra = scan_extras(extra_grids)
    extra["calibration"] = calib
    if no_load:
        extra["no_load"] = extra_no_load
    fsr_kind = {} if sim.fsr is None else {"fsr": "alone (scenes.fsr_sensor), calibrated on the plant (scenes.fsr_lab)"}
    extra["plant"] = {"name": plant, **fsr_kind, **({} if sim.plant is None else RichPlant(sim.plant).describe()),
                      **({} if sim.cable is None else {"cable": asdict(sim.cable)})}
    pdict = {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(params).items()}
    pdict.update({"reading_rate_hz": _num(1.0 / dt), "physics_dt_s": sim.world.dt, "pretension_N": sim.pretension,
                  "tip_stiffness_N_per_m": sim.tip_stiffness, "capstan_k_N_per_m": sim.capstan_k,
                  "mu": geom.mu, "theta0_deg": _num(np.rad2deg(geom.theta0)), "noise_counts": sim.noise_counts})
    return PalpationResult(test, profile, int(seed), pdict, results, summary, extra, simulated, wall, cpu)


def _tips2lengths(tips, tool, geom):
    poses = np.zeros((len(tips), 6))
    poses[:, :3] = tips - tool
    return poses2lengths(poses, geom)


class _NoBar:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def _progress_bar(enabled: bool, total: int, desc: str):
    if not enabled:
        return _NoBar()

    return progress(total, desc, unit="ticks", mininterval=0.5)


def no_load_errors(w: dict, poses: np.ndarray, a: int, b: int, axis: int, turn_window_s: float,
                   dt: float | None = None) -> dict:
    """Each estimator's wrench along `axis` over the no-load run samples a..b-1 (the truth is 0) [N]:
    {name: {"rmse_N", "max_abs_N", "peak_to_peak_N", "rmse_off_turns_N", "max_abs_near_turns_N"}} plus
    "turns" (how many) and "turn_window_s"; near a turn = within turn_window_s (the turn fit's duration, 1 s
    if it has none) after the tip reverses along the axis. dt: the sample period [s] (None: 0.01)."""
    dt = 0.01 if dt is None else dt
    x = np.asarray(poses)[a:b, axis]
    v = np.sign(np.diff(x))
    moving = np.nonzero(v)[0]
    v = v[np.maximum.accumulate(np.where(v != 0, np.arange(v.size), moving[0] if moving.size else 0))]
    turns = np.nonzero(np.diff(v))[0] + 1
    window = turn_window_s if np.isfinite(turn_window_s) and 0 < turn_window_s < 10 else 1.0
    near = np.zeros(b - a, dtype=bool)
    for k in turns:
        near[k:k + int(round(window / dt))] = True
    out = {"turns": int(turns.size), "turn_window_s": _num(window)}
    for n, wn in w.items():
        e = np.asarray(wn)[a:b, axis]
        out[n] = {"rmse_N": _num(np.sqrt(np.mean(e ** 2))), "max_abs_N": _num(np.max(np.abs(e))),
                  "peak_to_peak_N": _num(np.ptp(e)),
                  "rmse_off_turns_N": _num(np.sqrt(np.mean(e[~near] ** 2))) if (~near).any() else None,
                  "max_abs_near_turns_N": _num(np.max(np.abs(e[near]))) if near.any() else None}
    return out


def summarise(rows) -> dict:
    """{estimator: {"mean_abs_error_N", "rmse_N", "max_abs_error_N"}} over the pokes."""
    gt = np.array([r["ground_truth_N"] for r in rows])
    out = {}
    for n in ESTIMATORS:
        e = np.array([r[f"{n}_N"] for r in rows]) - gt
        out[n] = {"mean_abs_error_N": _num(np.mean(np.abs(e))), "rmse_N": _num(np.sqrt(np.mean(e ** 2))),
                  "max_abs_error_N": _num(np.max(np.abs(e)))}
    return out


def stiffness_extras(rows) -> dict:
    """Per-region means, each estimator's ranking of the regions and whether it matches the truth."""
    labels = list(dict.fromkeys(r["label"] for r in rows))
    regions = {}
    for lab in labels:
        rr = [r for r in rows if r["label"] == lab]
        regions[lab] = {k: _num(np.mean([r[k] for r in rr])) for k in ["ground_truth_N"] + [f"{n}_N" for n in ESTIMATORS]}
    truth = sorted(labels, key=lambda lab: -regions[lab]["ground_truth_N"])
    ranking = {n: sorted(labels, key=lambda lab: -regions[lab][f"{n}_N"]) for n in ESTIMATORS}
    # ranks per poke too: every poke of a harder region above every poke of a softer one
    per_poke = {}
    for n in ESTIMATORS:
        ok = True
        for hi, lo in zip(truth, truth[1:]):
            a = [r[f"{n}_N"] for r in rows if r["label"] == hi]
            b = [r[f"{n}_N"] for r in rows if r["label"] == lo]
            ok &= min(a) > max(b)
        per_poke[n] = bool(ok)
    within = {n: bool(all(abs(r[f"{n}_N"] - r["ground_truth_N"]) <= 0.3 for r in rows)) for n in ESTIMATORS}
    out = {"regions": regions, "truth_ranking": truth, "ranking": ranking,
           "ranks_correctly": {n: ranking[n] == truth for n in ESTIMATORS},
           "ranks_every_poke": per_poke, "within_0_3_N": within}
    gt = [r["ground_truth_N"] for r in rows]
    if np.ptp(gt) > 0.1:  # a line needs pokes at different loads (not a one-region run)
        out["load_response"] = {n: load_response(gt, [r[f"{n}_N"] for r in rows]) for n in ESTIMATORS}
        out["seed_table1_load_response"] = {n: load_response(SEED_TABLE1["ground_truth"], SEED_TABLE1[n])
                                            for n in ("non_compensated", "double")}
    return out


def load_response(truth, estimate) -> dict:
    """Least-squares line estimate = offset + gain * truth over the pokes: {"offset_N", "gain"}.

    What separates an estimator that ranks stiffness regions from one that cannot: a gain near 1 with a
    constant offset still ranks (the offset cancels between regions); a gain near 0 does not. Under the
    capstan law with each cable's friction direction fixed during a poke, the non-compensated gain is
    sum_i a_i m_i dt_i/dF with m_i in [exp(-mu Theta_i), exp(+mu Theta_i)] and sum_i a_i dt_i/dF = 1 (a_i the
    cable's share of the poke direction in A); when every cable's term pushes the same way (the poke loads one
    group of cables and unloads the other, as in the default robot) the gain lies between those factors:
    0.83-1.20 for the default robot (Theta = theta0 + 28-44 deg).
    """
    gain, offset = np.polyfit(np.asarray(truth, dtype=float), np.asarray(estimate, dtype=float), 1)
    return {"offset_N": _num(offset), "gain": _num(gain)}


def _grid(session: Session, rows) -> dict:
    mine = [r for r in rows if r["session"] == session.name]
    g = {"mask": letter_mask(session.name[-1]).tolist()}
    for key in ["ground_truth_N"] + [f"{n}_N" for n in ESTIMATORS]:
        a = np.full((SCAN_ROWS, SCAN_COLS), np.nan)
        for r in mine:
            i, j = (int(v) for v in r["label"][1:].split("c"))
            a[i, j] = r[key]
        g[key] = [[None if np.isnan(v) else _num(v) for v in row] for row in a]
    return g


def scan_extras(grids: dict) -> dict:
    """Raw grids per letter and, per estimator, the mean force over rigid (letter) and silicone cells."""
    contrast = {}
    for key in ["ground_truth_N"] + [f"{n}_N" for n in ESTIMATORS]:
        rig, sil = [], []
        for g in grids.values():
            m = np.array(g["mask"])
            v = np.array([[np.nan if x is None else x for x in row] for row in g[key]], dtype=float)
            rig += v[m & ~np.isnan(v)].tolist()
            sil += v[~m & ~np.isnan(v)].tolist()
        name = key[:-2]
        r_mean = float(np.mean(rig)) if rig else float("nan")
        s_mean = float(np.mean(sil)) if sil else float("nan")
        contrast[name] = {"rigid_mean_N": _num(r_mean) if rig else None, "silicone_mean_N": _num(s_mean) if sil else None,
                          "ratio": _num(r_mean / s_mean) if rig and sil and s_mean > 0 else None}
    return {"grids": grids, "contrast": contrast}
