"""The blind-test rig: the four-area pad of seed 000 Fig 14g and the whole chain the participants feel it
through. This is wiring (it picks concrete devices), so scenes and devices are imported inside functions.

Chain of one tick (teleop.loop.Teleop, unpaced on a manual clock: simulated time, no sleeping):
    sim stylus (operator model pushing toward the participant's target, feeling the commanded force)
    -> mapping (motion scale, registration, workspace) -> kinematics (cable lengths) -> sim://robot
    (pybullet pad, cable compliance, sheath friction, FSR) -> FSR counts -> calibrated tensions ->
    estimator (friction compensation + Kalman, or the raw FSR wrench for the ablation) -> rendering
    (force scale, -z zeroed, ramp-in, clamp to the device limit) -> stylus.servo_cf.

The CDPR reaches only a few millimetres sideways (wrench-feasible tensions), while the seed's pad puts its
areas 16 mm from the centre. So the coordinator's "move the effector over the next area" is done with a
pad stage: for each slot the pad is the seed layout slid so that the slot's area is centred under the
effector, 0.5 mm below the tip at the home pose (the coordinator brought the effector just over the
pad). Each slot gets its own simulated robot and loop for the participant.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from teleop.protocols.blind.probe import Poke, PokeRequest
from teleop.protocols.blind.study import Area


def blind_areas() -> tuple:
    """The four areas hardest first with their target contact stiffness [N/m] (scenes.materials)."""
    from scenes.materials import contact_stiffness, get_material
    from scenes.pads import BLIND_LABELS, BLIND_MATERIALS

    return tuple(Area(name, BLIND_LABELS[name], contact_stiffness(get_material(name))) for name in BLIND_MATERIALS)


@dataclass(frozen=True)
class RigOptions:
    """How the chain is set up for the study (SI).

    Attributes:
        compensation: render the friction-compensated, Kalman-filtered wrench (the project's `dynamic`
            estimator); False renders the raw FSR wrench f = -A t (ablation).
        estimator: DESIGN.md estimator name used when compensation is on.
        force_scale: stylus force per newton of estimated tip force [-].
        motion_scale: robot displacement per stylus displacement [-].
        gap: pad surface distance ahead of the tip at the home pose [m] (effector brought just over it).
        robot_substeps: physics steps (1 ms) per robot-link exchange: the robot link runs at 1 kHz / this.
        settle: time the chain runs before the first poke of a slot (engage + force ramp-in) [s].
        hold: time the participant holds at the deepest point [s].
        release_speed: stylus speed back to rest after a poke [m/s].
        rest: time at rest after a poke [s].
        seed: seeds the stylus tremor and the FSR noise (mixed with the slot and participant).
    """

    compensation: bool = True
    estimator: str = "dynamic"
    force_scale: float = 1.0
    motion_scale: float = 0.5
    gap: float = 0.0005
    robot_substeps: int = 4
    settle: float = 0.35
    hold: float = 0.05
    release_speed: float = 0.05
    rest: float = 0.08
    seed: int = 0

    def __post_init__(self):
        from teleop.errors import InputError

        for name in ("force_scale", "motion_scale", "gap", "release_speed"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"blind-test rig: {name} must be a finite number > 0, got {v!r}")
        for name in ("settle", "hold", "rest"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"blind-test rig: {name} must be >= 0, got {v!r}")
        if int(self.robot_substeps) < 1:
            raise InputError(f"blind-test rig: robot_substeps must be >= 1, got {self.robot_substeps}")


class FsrChainEstimator:
    """The loop's Estimator protocol over the estimation package: FSR counts -> tensions (teleop.sensors,
    loading/unloading branch) -> `teleop.estimation` estimator (compensation, f = -A t, Kalman)."""

    def __init__(self, geom, name: str, kalman: bool = True):
        from teleop.estimation.estimators import make_estimator
        from teleop.sensors import FsrConverter, default_fsr_calibration

        self.name = name
        self.cal = default_fsr_calibration()
        self.converter = FsrConverter(self.cal, n=len(geom.B))
        self.estimator = make_estimator(name, geom) if kalman else make_estimator(name, geom, kalman=None)

    def reset(self) -> None:
        self.converter.reset()
        self.estimator.reset()

    def update(self, reading, pose, dt: float):
        t = np.asarray(self.converter.update(reading.fsr_counts), dtype=float)
        f = np.asarray(self.estimator.update(t, reading.commanded_lengths, pose, dt), dtype=float)
        return t, f

    def describe(self) -> dict:
        return {"estimator": self.name, "kalman": self.estimator.kalman is not None}


class _ManualClock:
    """Simulated time for the stylus: the rig advances it tick by tick (unpaced, never sleeps)."""

    def __init__(self):
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def _slid_pad(pad, centre):
    """The pad slid by -centre (2,) [m]: the area at `centre` comes under the effector."""
    regions = tuple(dataclasses.replace(r, centre=(float(r.centre[0] - centre[0]), float(r.centre[1] - centre[1])))
                    for r in pad.regions)
    return dataclasses.replace(pad, regions=regions)


class _Station:
    """One slot: its simulated robot (pad slid under the effector), stylus and loop."""

    def __init__(self, pad, options: RigOptions, seed: tuple):
        from devices.simulated import Script, SimulatedStylus
        from scenes.sim_robot import SimRobot, SimRobotParams
        from scenes.world import WorldParams
        from teleop.geometry import default_geometry
        from teleop.loop import LoopParams, Teleop
        from teleop.mapping import MappingParams

        o = options
        geom = default_geometry()
        self.options = o
        ss = np.random.SeedSequence(seed)
        robot_seed, stylus_seed = (int(s) for s in ss.generate_state(2) % (2 ** 31))
        home_tip_z = WorldParams().surface_z - 0.005  # the sim robot's home: tip 5 mm before the surface
        world = WorldParams(surface_z=home_tip_z + o.gap)
        self.robot = SimRobot(pad, SimRobotParams(world=world, substeps=int(o.robot_substeps)), seed=robot_seed)
        self.clock = _ManualClock()
        self.stylus = SimulatedStylus(Script(kind="hold"), clock=self.clock, seed=stylus_seed)
        # stylus -z (pushing down on the handle) drives the robot +z, into the pad
        R_reg = np.diag([1.0, -1.0, -1.0])
        mapping = MappingParams(motion_scale=o.motion_scale, R_reg=R_reg)
        self.params = LoopParams(rate_hz=1000.0, robot_rate_hz=1000.0 / int(o.robot_substeps),
                                 force_scale=o.force_scale, zero_neg_z=True, mapping=mapping)
        name = o.estimator if o.compensation else "non_compensated"
        self.estimator = FsrChainEstimator(geom, name, kalman=o.compensation)
        self.geom = geom
        self.tp = None
        self.rest = None

    def open(self) -> None:
        from teleop.loop import Teleop

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
        from teleop.loop import State

        dt = self.params.dt
        n = int(round(seconds / dt))
        t = np.empty(n)
        z = np.empty(n)
        f = np.empty(n)
        tp, clock, stylus = self.tp, self.clock, self.stylus
        for k in range(n):
            clock.t += dt
            x = tp.tick(clock.t)
            if record:
                t[k] = clock.t
                z[k] = stylus.p[2]
                f[k] = x.F[2]
        if tp.state == State.FAULT:
            from devices.base import DeviceError

            raise DeviceError(f"blind-test rig: the loop faulted ({tp.fault_reason})")
        return t, z, f

    def settle(self) -> None:
        """Run until teleoperation is engaged and the force ramp-in is over."""
        from devices.simulated import Script

        self.stylus.script = Script(kind="hold", center=tuple(self.rest))
        self._run(self.options.settle, record=False)

    def poke(self, request: PokeRequest) -> Poke:
        """The participant's hand target goes `depth` along -z at `speed`, holds, and returns to rest."""
        from devices.simulated import Script

        o = self.options
        t0 = self.clock.t
        c = self.rest
        down = c - np.array([0.0, 0.0, request.depth])
        t1 = t0 + request.depth / request.speed
        t2 = t1 + o.hold
        t3 = t2 + request.depth / o.release_speed
        pts = np.array([[t0, *c], [t1, *down], [t2, *down], [t3, *c]])
        self.stylus.script = Script(kind="recorded", points=pts)
        t, z, f = self._run(t3 + o.rest - t0, record=True)
        return Poke(t=t - t0, x=-(z - z[0]), f=f)


class SimRig:
    """The simulated rig (study.Rig): four areas, rearranged per participant, poked through the chain."""

    def __init__(self, options: RigOptions = RigOptions()):
        self.options = options
        self.areas = blind_areas()
        self.stations: list = []
        self.layout = None
        self.n_arranged = 0

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def open(self) -> None:
        """Nothing to open until a layout is arranged (kept for symmetry with devices)."""

    def close(self) -> None:
        for s in self.stations:
            s.close()
        self.stations = []

    def arrange(self, layout) -> None:
        """Lay out the pad (area name per slot) and set up one station per slot."""
        from scenes.pads import blind_area_centres, blind_test_pad

        self.close()
        self.layout = tuple(layout)
        pad = blind_test_pad(self.layout)
        centres = blind_area_centres()
        self.n_arranged += 1
        self.stations = [None] * len(self.layout)
        self._pad, self._centres = pad, centres

    def _station(self, slot: int) -> _Station:
        st = self.stations[slot]
        if st is None:
            st = _Station(_slid_pad(self._pad, self._centres[slot]), self.options,
                          (self.options.seed, self.n_arranged, slot))
            st.open()
            st.settle()
            self.stations[slot] = st
        return st

    def poke(self, slot: int, request: PokeRequest) -> Poke:
        return self._station(int(slot)).poke(request)

    def describe(self) -> dict:
        """The chain's settings for the results' config."""
        return dataclasses.asdict(self.options)

    @property
    def attribution(self) -> str:
        from scenes.materials import ATTRIBUTION

        return ATTRIBUTION
