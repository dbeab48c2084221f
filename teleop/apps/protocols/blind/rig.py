"""The blind-test rig: the four-area pad of seed 000 Fig 14g and the whole chain the participants feel it
through. This is wiring: it picks the concrete devices (the simulated stylus and robot, or a session's).

Chain of one tick (teleop.loop.Teleop, unpaced on a manual clock: simulated time, no sleeping):
    sim stylus (operator model pushing toward the participant's target, feeling the commanded force)
    -> mapping (motion scale, registration, workspace) -> kinematics (cable lengths) -> sim://robot
    (pybullet pad, cable compliance, sheath friction, FSR) -> FSR counts -> calibrated tensions ->
    estimator (friction compensation + Kalman, or the raw FSR wrench for the ablation) -> rendering
    (force scale, -z zeroed, ramp-in, clamp to the device limit) -> stylus.servo_cf.

The CDPR reaches only a few millimetres sideways (wrench-feasible tensions), while the seed's pad puts its
areas 16 mm from the centre. So the coordinator's "move the effector over the next area" is done with the
simulated robot's pad stage (SimRobot.set_pad_offset): the pad slides until the zone's area is centred
under the effector, whose tip hovers 0.5 mm above the surface at the home pose (the coordinator brought
the effector just over the pad).

What limits transparency (what the participants can feel). A transparent chain shows on the stylus
force_scale * motion_scale * k_tip k / (k_tip + k) (`expected_stiffness`): the pad k in series with the
simulated robot's own stiffness k_tip (scenes.sim_robot tip_stiffness, 1e4 N/m). `teleop blind-test
--transparency` presses each area at 10, 20 and 30 mm/s and fits the same loading slope to three forces
against the stylus displacement: the robot's ground-truth contact force (x force scale), the transparent
chain's and the rendered force. The robot's compliance is all in `expected_stiffness`, and the device does
not limit (455 N/m on rigid is under a Touch's 1.02 N/mm). What departs from it is the estimate: the
rendered force lags the contact (the FSR chain and friction compensation, then the Kalman filter), so on
rigid, whose press is short, the force goes on rising while the stylus stops and the slope reads high; and
at slow presses the friction compensation, which holds its tip-tension estimate while a cable creeps
through the capstan's stick transition, makes the two Ecoflex areas read high. With a slower Kalman filter
its lag dominates instead: see RigOptions.kalman_bandwidth.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from dataclasses import dataclass

import numpy as np

from devices.base import DeviceError
from devices.simulated import Script, SimulatedStylus
from scenes.fsr_lab import plant_fsr_calibration
from scenes.materials import ATTRIBUTION, contact_stiffness, get_material
from scenes.pads import BLIND_LABELS, BLIND_MATERIALS, blind_area_centres, blind_test_pad
from scenes.sensor_identification import identify_one_sensor_on
from scenes.sim_robot import PLANTS, SimRobot, SimRobotParams, with_named_plant
from scenes.world import WorldParams
from teleop.apps.protocols.blind.probe import Poke, PokeRequest, PressAborted
from teleop.apps.protocols.blind.stats import loading_slope
from teleop.apps.protocols.blind.study import Area
from teleop.core.errors import InputError
from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.sensor_reading import make_estimator
from teleop.core.geometry import default_geometry, load_geometry
from teleop.core.mapping import MappingParams
from teleop.loop import LoopParams, State, Teleop
from teleop.loop.devices_by_url import open_device
from teleop.loop.params import LOOP_RENDER


def blind_areas() -> tuple:
    """The four areas hardest first with their target contact stiffness [N/m] (scenes.materials)."""
    return tuple(Area(name, BLIND_LABELS[name], contact_stiffness(get_material(name))) for name in BLIND_MATERIALS)


@dataclass(frozen=True)
class RigOptions:
    """How the chain is set up for the study (SI).

    Attributes:
        compensation: render the friction-compensated, Kalman-filtered wrench (the project's `dynamic`
            estimator); False renders the raw FSR wrench f = -A t (ablation).
        estimator: estimator name (docs/formats.md) used when compensation is on.
        force_scale: stylus force per newton of estimated tip force [-]. 0.1 keeps the stiffest area
            stable in the hand: rigid PLA renders 0.1 * 0.5 * 9.1e3 = 455 N/m, and with the chain's ~7 ms
            lag (see kalman_bandwidth) that feeds the hand a negative damping K tau = 3.2 N s/m, half the
            operator model's 6 N s/m (devices.simulated OperatorParams.b; 6.45 N s/m measured for an arm
            holding a haptic handle in a typical trial of van Beek et al. 2015, "Haptic perception of
            force magnitude and its relation to postural arm dynamics in 3D", Sci Rep 5:18004). It is
            also well inside a Geomagic Touch's z stiffness (>= 1.02 N/mm, 3D Systems specifications).
            At 0.2 (rigid 909 N/m, K tau 6.4 N s/m: past the hand's damping) the hand bounces on rigid
            and the ranking suffers (`teleop blind-test --force-scale 0.2`).
        motion_scale: robot displacement per stylus displacement [-].
        gap: pad surface distance ahead of the tip at the home pose [m] (effector brought just over it).
        robot_substeps: physics steps (1 ms) per robot-link exchange: the robot link runs at 1 kHz / this.
            1: the loop's own default (LoopParams.robot_rate_hz None: a robot exchange every 1 kHz tick)
            and the simulated robot's reading rate, so the estimator sees every FSR sample. The rendering
            lag is hardly the link's, so a slower link (`--robot-substeps 4`: 250 Hz) ranks as well, in
            less wall time.
        settle: time the chain runs before a participant's first poke (engage + force ramp-in) [s].
        hold: time the participant holds at the deepest point [s].
        release_speed: stylus speed back to rest after a poke [m/s].
        rest: time at rest after a poke [s].
        seed: seeds the stylus tremor and the FSR noise of the chain (mixed with the arrangement number;
            fixed by default, so studies with different --seed share the chain's noise draws).
        tip_stiffness: series stiffness between the commanded tip and the pad [N/m] in the simulated
            robot; None keeps scenes.sim_robot's default (1e4 N/m, derived there from the cables).
        kalman_bandwidth: -3 dB bandwidth of the estimator's steady-state Kalman filter [Hz] (passed as
            teleop.core.estimation.kalman.KalmanNoise.bandwidth_hz). The filter's delay adds to the chain's own
            (~6 ms from the FSR chain and friction compensation, measured against the ground-truth contact
            force), and a spring rendered with a delay tau feeds the hand a negative damping K tau. At
            80 Hz the filter adds ~1 ms: rigid's 455 N/m x 7 ms = 3.2 N s/m, half the hand's 6 N s/m
            (see force_scale), and a press on rigid, over in ~40 ms of contact, renders about what the
            unfiltered estimate shows (`teleop blind-test --transparency`). What it lets through is
            small: the FSR noise (0.02 N per cable, ~0.03 N on the tip unfiltered) is under a sixth of
            what the stylus detection threshold (0.02 N) means at the tip (0.2 N at force scale 0.1).
            The loop's 8 Hz default lags far more; at 20 Hz the slope rendered on rigid spreads with the
            participants' speed and the ranking suffers (`--transparency --kalman-bandwidth 20`).
        sensor: the robot's tension sensors (teleop.core.sensors.SENSOR_KINDS: fsr, fbg, one; scenes.sim_sensors).
        plant: the simulated robot's plant (scenes.sim_robot.PLANTS): matched, rich (drawn from the robot's
            seed) or distributed (the distributed tendon-sheath cable at its default parameters). Listed in
            `rig_dict` only when not matched.
        geometry: the robot's geometry TOML (teleop.core.geometry.load_geometry, `--geometry`; None: the seed
            robot), read by each station for its simulated robot and estimator. Listed in `rig_dict` only when
            given.
        cable_params: with plant distributed, the cable's TOML ([tendon_sheath] table, docs/formats.md; None: its
            defaults), read by each station's simulated robot. Listed in `rig_dict` only when given.
    """

    compensation: bool = True
    estimator: str = "dynamic"
    force_scale: float = 0.1
    motion_scale: float = 0.5
    gap: float = 0.0005
    robot_substeps: int = 1
    settle: float = 0.3
    hold: float = 0.03
    release_speed: float = 0.08
    rest: float = 0.05
    seed: int = 0
    tip_stiffness: float | None = None
    kalman_bandwidth: float = 80.0
    sensor: str = "fsr"
    plant: str = "matched"
    geometry: str | None = None
    cable_params: str | None = None

    def __post_init__(self):
        if self.plant not in PLANTS:
            raise InputError(f"blind-test rig: plant must be one of {', '.join(PLANTS)}, got {self.plant!r}")
        if self.cable_params is not None and self.plant != "distributed":
            raise InputError(f"blind-test rig: cable_params ({self.cable_params}) belong to plant distributed, "
                             f"got plant {self.plant!r}")
        for name in ("force_scale", "motion_scale", "gap", "release_speed"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"blind-test rig: {name} must be a finite number > 0, got {v!r}")
        for name in ("settle", "hold", "rest"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"blind-test rig: {name} must be >= 0, got {v!r}")
        if self.tip_stiffness is not None and not (np.isfinite(self.tip_stiffness) and self.tip_stiffness > 0):
            raise InputError(f"blind-test rig: tip_stiffness must be > 0 N/m, got {self.tip_stiffness!r}")
        if not (np.isfinite(self.kalman_bandwidth) and self.kalman_bandwidth > 0):
            raise InputError(f"blind-test rig: kalman_bandwidth must be > 0 Hz, got {self.kalman_bandwidth!r}")
        if int(self.robot_substeps) < 1:
            raise InputError(f"blind-test rig: robot_substeps must be >= 1, got {self.robot_substeps}")


def rig_dict(options: RigOptions) -> dict:
    """The options as a dict, `plant` only when not matched and `geometry` only when given (a matched rig's dict
    on the seed robot, its results' config and a campaign task's identity, are what they were before either
    could be chosen)."""
    d = dataclasses.asdict(options)
    if d["plant"] == "matched":
        del d["plant"]
    if d["geometry"] is None:
        del d["geometry"]
    if d["cable_params"] is None:
        del d["cable_params"]
    return d


def _sensor_estimator(geom, o, robot_params, name: str, noise):
    """The estimator of the rig's sensor kind (teleop.core.estimation.sensor_reading.make_estimator); for "one" the
    eq 7 model is identified once on the simulated robot (scenes.sensor_identification.identify_one_sensor_on)."""
    kw = {"cal": plant_fsr_calibration(robot_params)}  # the FSR calibration of the robot's plant (scenes.fsr_lab)
    if o.sensor == "one":
        kw.update(model=identify_one_sensor_on(robot_params, 0, 0), cable=0)
    return make_estimator(geom, o.sensor, name, kalman=noise, **kw)


class _ManualClock:
    """Simulated time for the stylus: the rig advances it tick by tick (unpaced, never sleeps)."""

    def __init__(self):
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


class Station:
    """One participant's rig: the simulated robot over the arranged pad, the stylus and the loop."""

    def __init__(self, pad, options: RigOptions, seed: tuple):
        o = options
        geom = default_geometry() if o.geometry is None else load_geometry(o.geometry)
        self.options = o
        ss = np.random.SeedSequence(seed)
        robot_seed, stylus_seed = (int(s) for s in ss.generate_state(2) % (2 ** 31))
        home_tip_z = WorldParams().surface_z - 0.005  # the sim robot's home: tip 5 mm before the surface
        world = WorldParams(surface_z=home_tip_z + o.gap)
        robot_params = with_named_plant(SimRobotParams(world=world, substeps=int(o.robot_substeps), sensor=o.sensor,
                                                       geometry=geom),
                                        o.plant, robot_seed, o.cable_params)
        if o.tip_stiffness is not None:
            robot_params = dataclasses.replace(robot_params, tip_stiffness=float(o.tip_stiffness))
        self.robot = SimRobot(pad, robot_params, seed=robot_seed)
        self.clock = _ManualClock()
        self.stylus = SimulatedStylus(Script(kind="hold"), clock=self.clock, seed=stylus_seed)
        # stylus -z (pushing down on the handle) drives the robot +z, into the pad; the pad's reaction (-z in
        # {B}) comes back as +z on the stylus, and the renderer zeroes -z device-frame forces as in the seed
        R_reg = np.diag([1.0, -1.0, -1.0])
        mapping = MappingParams(motion_scale=o.motion_scale, R_reg=R_reg)
        render = dataclasses.replace(LOOP_RENDER, scale=o.force_scale, zero_negative_z=True)
        self.params = LoopParams(rate_hz=1000.0, robot_rate_hz=1000.0 / int(o.robot_substeps), render=render,
                                 mapping=mapping)
        if o.compensation:  # the Kalman gain is designed for the period the estimator actually runs at
            noise = KalmanNoise(dt=self.params.dt * self.params.robot_every, bandwidth_hz=float(o.kalman_bandwidth))
            self.estimator = _sensor_estimator(geom, o, robot_params, o.estimator, noise)
        else:  # the raw sensor wrench: no friction compensation, no Kalman filter
            self.estimator = _sensor_estimator(geom, o, robot_params, "non_compensated", None)
        self.geom = geom
        self.tp = None
        self.rest = None
        self.slot = None
        self.monitor = None  # optional callable(TickData) after every tick (diagnostics, never the participant)

    def open(self) -> None:
        self.robot.open()
        self.stylus.open()
        self.tp = Teleop(self.stylus, self.robot, self.params, self.geom, estimator=self.estimator)
        self.tp.start(0.0)
        self.rest = self.stylus.p.copy()

    def close(self) -> None:
        if self.tp is not None:
            self.stylus.close()
            self.robot.close()
            self.tp = None

    def _run(self, seconds: float, record: bool):
        dt = self.params.dt
        n = int(round(seconds / dt))
        t = np.empty(n)
        z = np.empty(n)
        f = np.empty(n)
        tp, clock, stylus = self.tp, self.clock, self.stylus
        monitor = self.monitor
        for k in range(n):
            clock.t += dt
            x = tp.tick(clock.t)
            if monitor is not None:
                monitor(x)
            if record:
                t[k] = clock.t
                z[k] = stylus.p[2]
                f[k] = x.F[2]
        if tp.state == State.FAULT:
            raise DeviceError(f"blind-test rig: the loop faulted ({tp.fault_reason})")
        return t, z, f

    def settle(self) -> None:
        """Run until teleoperation is engaged and the force ramp-in is over."""
        self.stylus.script = Script(kind="hold", center=tuple(self.rest))
        self._run(self.options.settle, record=False)

    def move_to(self, slot: int, centre) -> None:
        """The coordinator brings slot `slot` (area centre (2,) [m] in the pad frame) under the effector:
        the pad stage slides the pad while the tip hovers above it."""
        if slot != self.slot:
            self.robot.set_pad_offset((-float(centre[0]), -float(centre[1])))
            self.slot = slot

    def poke(self, request: PokeRequest) -> Poke:
        """The participant's hand target goes along -z at `speed` until the stylus force reaches
        `request.force` (if given) or the target is `depth` deep, holds there, and returns to rest.

        A press stopped by the force holds that force: the hand's target is put where the operator model's
        spring (stiffness k) pushes the stylus with `force` from where the stylus is, force / k beyond it.
        Holding the target where it had run to instead keeps pressing on by the distance the target ran
        while the lagging force built up (~0.6 N more on rigid's tip at 20 mm/s and ~7 ms; with a 12 ms
        lag a 0.37 N press that held its target faulted the loop with 6 N on the tip)."""
        o = self.options
        t0 = self.clock.t
        c = self.rest
        down = c - np.array([0.0, 0.0, request.depth])
        t1 = t0 + request.depth / request.speed
        t2 = t1 + o.hold
        t3 = t2 + request.depth / o.release_speed
        self.stylus.script = Script(kind="recorded", points=np.array([[t0, *c], [t1, *down], [t2, *down], [t3, *c]]))
        if request.force is None:
            t, z, f = self._run(t3 + o.rest - t0, record=True)
            return Poke(t=t - t0, x=-(z - z[0]), f=f)
        # descend until the felt force reaches the comfortable level, then hold and release from there
        t_a, z_a, f_a, reached = self._run_until(t1 - t0, request.force)
        tc = self.clock.t
        if reached:
            # hold the force aimed at: the hand's target goes to where its spring pushes the stylus with
            # `force` from where the stylus is now (not where the target had run to by the time the lagging
            # force was felt: holding that would keep pressing on)
            at = self.stylus.p - np.array([0.0, 0.0, request.force / self.stylus.operator.k])
        else:  # the push depth came first: hold there
            at = c - np.array([0.0, 0.0, request.depth])
        d = float(c[2] - at[2])
        t3 = tc + o.hold + max(d, 0.0) / o.release_speed
        self.stylus.script = Script(kind="recorded", points=np.array([[tc, *at], [tc + o.hold, *at], [t3, *c]]))
        t_b, z_b, f_b = self._run(t3 + o.rest - tc, record=True)
        t, z, f = np.concatenate([t_a, t_b]), np.concatenate([z_a, z_b]), np.concatenate([f_a, f_b])
        return Poke(t=t - t0, x=-(z - z[0]), f=f)

    def _run_until(self, seconds: float, force: float):
        """Like _run(seconds, record=True) but stops after the tick whose stylus force (+z) reaches `force`.
        Returns (t, z, f, reached)."""
        dt = self.params.dt
        n = int(round(seconds / dt))
        t, z, f = np.empty(n), np.empty(n), np.empty(n)
        tp, clock, stylus = self.tp, self.clock, self.stylus
        k, reached = 0, False
        monitor = self.monitor
        while k < n:
            clock.t += dt
            x = tp.tick(clock.t)
            if monitor is not None:
                monitor(x)
            t[k], z[k], f[k] = clock.t, stylus.p[2], x.F[2]
            k += 1
            if f[k - 1] >= force:
                reached = True
                break
        if tp.state == State.FAULT:
            raise DeviceError(f"blind-test rig: the loop faulted ({tp.fault_reason})")
        return t[:k], z[:k], f[:k], reached


class SimRig:
    """The simulated rig (study.Rig): the four-area pad laid out for each participant, poked through the chain.

    Each participant gets a fresh robot over the pad as laid out for them and a fresh loop (engaged once,
    then kept running between pokes); the pad stage moves from zone to zone.
    """

    def __init__(self, options: RigOptions = RigOptions()):
        self.options = options
        self.areas = blind_areas()
        self.station = None
        self.layout = None
        self.n_arranged = 0
        self.n_faults = 0  # presses the robot stopped (PressAborted)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def open(self) -> None:
        """The station opens on the first poke after `arrange` (kept for symmetry with devices)."""

    def close(self) -> None:
        if self.station is not None:
            self.station.close()
            self.station = None

    def arrange(self, layout) -> None:
        """Lay out the pad: area name per slot (a permutation of the four areas)."""
        self.close()
        self.pad = blind_test_pad(tuple(layout))  # validates the layout
        self.layout = tuple(layout)
        self.n_arranged += 1

    def poke(self, slot: int, request: PokeRequest) -> Poke:
        if self.layout is None:
            raise InputError("blind-test rig: arrange(layout) before poking")

        self._open_station(slot)
        self.station.move_to(int(slot), blind_area_centres()[int(slot)])
        try:
            return self.station.poke(request)
        except DeviceError as exc:  # the coordinator resets the robot; the next poke starts on a fresh loop
            self.close()
            self.n_faults += 1
            raise PressAborted(str(exc)) from None

    def _open_station(self, slot: int) -> None:
        """The participant's station, opened over `slot` and settled, on the first poke after `arrange`."""
        if self.station is None:
            self.station = Station(self.pad, self.options, (self.options.seed, self.n_arranged))
            self.station.open()
            self.station.move_to(int(slot), blind_area_centres()[int(slot)])
            self.station.settle()

    def poke_traced(self, slot: int, request: PokeRequest) -> tuple:
        """A poke as `poke`, plus what the chain had to render, for diagnostics (never for a participant):
        (Poke, contact, unfiltered), both (n,) forces along the push scaled to the stylus [N] at the Poke's
        samples: force_scale x the robot's ground-truth contact force (what a transparent chain renders),
        and force_scale x the estimator's wrench without its Kalman filter (same friction compensation;
        None when the chain renders the raw FSR wrench, which has no filter anyway)."""
        if self.layout is None:
            raise InputError("blind-test rig: arrange(layout) before poking")
        self._open_station(slot)
        st = self.station
        raw = _sensor_estimator(st.geom, self.options, st.robot.params, st.estimator.name, None) \
            if self.options.compensation else None  # the chain's sensor kind and estimator, unfiltered
        contact, unfiltered, last = [], [], [0.0, 0.0]

        def monitor(x):
            r = x.reading
            if r is not None:
                last[0] = -float(r.wrench_truth[2])
                if raw is not None:
                    last[1] = -float(raw.update(r, st.tp.pose, st.params.dt * st.params.robot_every)[1][2])
            contact.append(last[0])
            unfiltered.append(last[1])

        if raw is not None:  # bring the unfiltered estimator to the chain's state: it follows the same readings
            raw.update(st.tp.last_reading, st.tp.pose, st.params.dt * st.params.robot_every)
        st.monitor = monitor
        try:
            p = self.poke(slot, request)
        finally:
            st.monitor = None
        n, g = len(p.t), self.options.force_scale
        un = g * np.array(unfiltered[-n:]) if raw is not None else None
        return p, g * np.array(contact[-n:]), un

    def describe(self) -> dict:
        """The chain's settings for the results' config."""
        d = rig_dict(self.options)
        d["tip_stiffness_used"] = self.tip_stiffness()
        return d

    def tip_stiffness(self) -> float | None:
        """The simulated robot's series compliance [N/m] (None: rigid tip)."""
        o = self.options
        return float(o.tip_stiffness) if o.tip_stiffness is not None else SimRobotParams().tip_stiffness

    def expected_stiffness(self) -> dict:
        """area name -> the stiffness a transparent chain renders on the stylus [N/m]:
        force_scale * motion_scale * (k_tip k / (k_tip + k)), the pad in series with the robot's compliance
        (the most any estimator can show; the device limits and filtering come on top)."""
        o = self.options
        kt = self.tip_stiffness()
        gain = o.force_scale * o.motion_scale
        return {a.name: gain * (a.stiffness if kt is None else kt * a.stiffness / (kt + a.stiffness))
                for a in self.areas}

    @property
    def attribution(self) -> str:
        return ATTRIBUTION


def transparency(options: RigOptions, speeds, repeats: int = 3, force: float = 0.3, depth: float = 0.008) -> list:
    """What limits the rendered stiffness: each area (laid out hardest first) pressed `repeats` times at
    each stylus speed [m/s] to `force` [N] or `depth` [m], and the loading slope (stats.loading_slope)
    [N/m] of, against the stylus displacement: the force rendered on the stylus, the unfiltered estimate
    and the ground-truth contact force (both x force_scale; see SimRig.poke_traced).

    Returns [{"speed", "area", "rendered", "unfiltered", "contact", "expected"}] with per-poke lists."""
    out = []
    for v in speeds:
        with SimRig(options) as rig:
            rig.arrange(tuple(a.name for a in rig.areas))
            expected = rig.expected_stiffness()
            rows = {a.name: {"speed": float(v), "area": a.name, "rendered": [], "unfiltered": [], "contact": [],
                             "expected": expected[a.name]} for a in rig.areas}
            for _ in range(int(repeats)):
                for slot, a in enumerate(rig.areas):
                    p, contact, unfiltered = rig.poke_traced(slot, PokeRequest(depth, float(v), force))
                    row = rows[a.name]
                    row["rendered"].append(loading_slope(p.x, p.f))
                    row["contact"].append(loading_slope(p.x, contact))
                    row["unfiltered"].append(None if unfiltered is None else loading_slope(p.x, unfiltered))
            out.extend(rows.values())
    return out


class RehearsalStation:
    """`--operator human` on the simulated stylus: each time the coordinator is told to let the participant
    push on a zone, a simulated participant's push is run through the whole chain and what the stylus felt
    is printed, so the coordinator can rehearse the protocol."""

    def __init__(self, options: RigOptions, params):
        self.rig = SimRig(options)
        self.areas = self.rig.areas
        self.params = params

    def open(self) -> None:
        self.rig.open()

    def close(self) -> None:
        self.rig.close()

    def poke_and_describe(self, layout, slot: int) -> str:
        if self.rig.layout != tuple(layout):
            self.rig.arrange(layout)
        try:
            p = self.rig.poke(slot, PokeRequest(self.params.depth, self.params.speed, self.params.force))
        except PressAborted as exc:
            return f"the robot stopped ({exc}); it was reset: press more gently"
        k = loading_slope(p.x, p.f, self.params.force_threshold)
        return (f"pushed {p.x.max() * 1e3:.1f} mm, peak force {p.f.max():.2f} N, "
                f"loading stiffness {k:.0f} N/m on the stylus")


class BackgroundSession:
    """`--operator human` at a real stylus: `teleop session` runs the loop (with -z zeroed, as in the seed)
    in a child process for as long as the study takes; its output goes to `log_path`."""

    def __init__(self, haptic_url: str, robot_url: str, options: RigOptions,
                 log_path: str = "blind_test_session.log"):
        self.argv = ["session", "--haptic", haptic_url, "--robot", robot_url, "--seconds", "86400", "--zero-neg-z",
                     "--force-scale", repr(options.force_scale), "--motion-scale", repr(options.motion_scale)]
        if options.geometry is not None:
            self.argv += ["--geometry", str(options.geometry)]
        self.log_path = log_path
        self.proc = None
        self.startup_check = 3.0  # [s] the session must still be running after this long

    def open(self) -> None:
        for url in (self.argv[2], self.argv[4]):  # a bad URL or a missing SDK fails here with one clear line
            device = open_device(url)
            device.open()
            device.close()
        self.log = open(self.log_path, "ab")
        start = self.log.tell()
        self.proc = subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", *self.argv], stdout=self.log,
                                     stderr=subprocess.STDOUT)
        try:  # a session that cannot start (SDK missing, port busy) ends within moments: say why
            self.proc.wait(timeout=self.startup_check)
        except subprocess.TimeoutExpired:
            return
        self.proc = None
        self.log.close()
        with open(self.log_path, "rb") as fh:
            fh.seek(start)
            lines = fh.read().decode(errors="replace").strip().splitlines()

        raise InputError(f"teleop session stopped at once: {lines[-1] if lines else 'no output'} "
                         f"(log: {self.log_path})")

    def close(self) -> None:
        if self.proc is not None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except Exception:  # noqa: BLE001 - it did not stop in time: stop it hard
                self.proc.kill()
                self.proc.wait()
            self.proc = None
            self.log.close()
