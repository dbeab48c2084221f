"""Simulated CDPR slave (URL ``sim://robot``): the Robot protocol of devices.base over a pybullet pad scene.

One reading = `substeps` physics steps of dt. Per reading:
  cable lengths (commanded, ideal steppers) -> pose (forward kinematics, batched Newton on
  teleop.core.kinematics.poses2lengths) -> tip target p + R tip -> pybullet: the contact tip is a small mass
  held on the commanded tip through a series spring (tip_stiffness, the loop's lumped compliance) and meets
  the pad's calibrated contact -> contact wrench f (the Nano17 ground truth, moments about p with the force
  at the tool tip) -> tip tensions t = wrench2tensions(f, A(pose), pretension) (A t + f = 0, eq 8)
  -> sheath friction between the FSR and the end effector: the sheath's capstan law with stick transitions
     (teleop.core.kernels.sheath, parameters `SimRobotParams.sheath`) with Theta_i = theta_i (eq 6) + theta0,
     motor position x = -length (shortening = pulling)
  -> FSR: hysteresis as friction lag between the calibration's loading and unloading branches
     (teleop.core.sensors.FsrBranchLag), divider -> ADC counts + Gaussian noise, rounded.
With `backlash` (URL `backlash_mm=W`) each cable's motor-to-cable transmission has play: the realized
lengths are the play operator (teleop.core.physics backlash) of the commanded ones, cable by cable, and the pose
is their least-squares forward kinematics (the elastic equilibrium of six equally stiff taut cables).
With `cable` (URL `plant=distributed`) the distributed tendon-sheath cable (scenes.tendon_sheath) takes the
lumped sheath's place in every cable, and the FSRs and FBGs read its tensions where each sits (DistributedCables).
The batch path `run(lengths)` does the same with the array forms of those models (fast); `read()` uses
their per-sample Step forms; both give the same counts for the same seed (tested).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from devices.base import ContextDevice, RobotReading, RobotSpec
from scenes import pads as pads_mod
from scenes.pads import Pad, z_test_pad
from scenes.fsr_sensor import FsrSensor, FsrSensorParams
from scenes.pose_follow import PoseFollower
from scenes.pulley_transmission import PulleyTransmission, PulleyTransmissionParams
from scenes.rich_plant import PLANTS as RICH_PLANTS
from scenes.rich_plant import RichPlant, RichPlantParams, plant_params, with_plant
from scenes.sim_robot_kernels import fixed_fsr, reading_cables, reading_cables_fsr_fixed
from scenes.sim_sensors import FBG_FROM_END_M, FbgArray, fbg_cables
from scenes.tendon_sheath import SheathLoad, TendonSheath, TendonSheathParams, b_node
from scenes.tendon_sheath_kernels import O_MOTOR, O_ROWS
from scenes.world import PadWorld, WorldParams
from teleop.core.errors import InputError
from teleop.core.geometry import Geometry, default_geometry
from teleop.core.kernels import sim as KS
from teleop.core.kernels import tension as KT
from teleop.core.kernels.tension import OK
from teleop.core.kernels import sheath as SH
from teleop.core.kernels.jit import bind
from teleop.core.kernels.sensor import fsr_counts
from teleop.core.kinematics import FREE_AXIAL, check_lengths, poses2lengths
from teleop.core.physics import get_effect
from teleop.core.physics.backlash import backlash
from teleop.core.robot_status import robot_status
from teleop.core.sensors import FsrBranchLag, FsrCalibration, adc_counts, default_fsr_calibration
from teleop.core.tension import TensionSolver, wrench2tensions
from teleop.io.model_io import load_model


@dataclass(frozen=True)
class SimRobotParams:
    """Physics of the simulated slave (SI). Defaults and their sources:

    Attributes:
        geometry: CDPR geometry (teleop.core.geometry.default_geometry: seed 000 robot, mu = 0.056 fitted to
            seed 000 Fig 9, theta0 = 140 deg from seed 000 §3).
        world: pybullet constants (1 kHz, 10 g tip, 1.5 mm flat tip).
        substeps: physics steps per reading (1: readings at 1 kHz).
        sensor: the tension sensors read (teleop.core.sensors.SENSOR_KINDS): "fsr" the FSR array; "fbg" also a
            distal FBG on every cable, "one" on cable `fbg_cable` only (scenes.sim_sensors; RobotReading.fbg_pm).
        pretension: reference cable tension of the tension distribution [N] (default the seed robot's,
            teleop.core.kernels.sheath.Sheath, where its source is given).
        tip_stiffness: series stiffness between the commanded tip and the contact [N/m] (isotropic): the
            robot's own stiffness, lumped at the tip so the end effector stays at its commanded pose
            (moving the end effector instead shifts A(pose) and, in this geometry, puts ~1.6 N of
            pretension into the wrench of any estimator that only knows the commanded pose; measured).
            Physical estimate: each cable runs from its NEMA17 through the Bowden tube to the effector
            (seed 000 §2), k_c = EA / L with a 0.3 mm steel cable (E ~ 200 GPa on the full section: EA ~
            14 kN; a 7x7 strand with its fill factor and rope modulus ~ half that) over L ~ 1 m: k_c ~
            0.7-1.4e4 N/m. CDPR stiffness K = A diag(k_c) A^T + sum t_i / l_i (I - u_i u_i^T) (elastic
            plus geometric tension term; Behzadipour & Khajepour 2006, "Stiffness of cable-based parallel
            manipulators with application to stability analysis", J Mech Des 128:303). At the home pose
            every cable has u_z = +-0.6 over l_i = 25 mm, so along z: K_zz = 6 * 0.36 k_c + 6 * (2.85 N /
            0.025 m) * 0.64 = 2.16 k_c + 438 N/m ~ 1.6-3.1e4 N/m. In series with the cables sit the
            FSR press blocks, each pressing its FSR through a thin silicone film (seed 000 §2), a
            compliance the seed does not quantify; 1e4 N/m takes the low end of the cable range with
            that film in series. (The stepper's holding stiffness, ~0.4 N m x 50 rotor teeth = 20 N m/rad
            over a ~5 mm drum ~ 8e5 N/m, drops out of the series.) Two of the seed's results need a robot
            this stiff: its participants told rigid PLA from Dragon Skin 30 (6.7 kN/m under our tip),
            which a compliant robot renders alike (382 N/m, the stiffness that would make Table 1's three
            forces come from one commanded depth, puts them 5 % apart), and its letter scan separates
            rigid from silicone. Table 1 does not give its poke depths (its pokes were teleoperated at
            "an estimated 0.5 mm/s"), so palpation reproduces its loads instead (teleop.apps.protocols.palpation).
            None = rigid (the tip tracks exactly).
        ee_damping_ratio: damping ratio of the contact tip on its series spring [-].
        plant: effects the estimators do not model, switched on in every cable (scenes.rich_plant
            RichPlantParams: Stribeck, Dahl, guide pulley, FSR creep; with the motor play `backlash` the
            sheath's friction travels with the realized lengths); None: the matched plant.
        cable: the distributed tendon-sheath cable (scenes.tendon_sheath) in every cable in place of the lumped
            sheath (`DistributedCables`; URL `plant=distributed`); None: the lumped sheath.
        pulley: seed 002's cable-pulley chain (scenes.pulley_transmission) in every cable in place of the lumped
            sheath (URL `plant=pulley`); None: the lumped sheath.
        capstan_k: stick stiffness of the capstan transition at reversals [N/m] (default the seed robot's,
            Sheath.stick_k, where its source is given; the catalogue's stiffer default,
            sheath.STIFF_STICK_K, would reduce the seed's turn transitions to blips).
        noise_counts: RMS ADC noise [counts] (ATmega2560 10-bit ADC, +-2 LSB absolute accuracy).
        backlash: total play (dead band) width of each cable's motor-to-cable transmission (spool, gear)
            [m]; 0: none. The realized cable length is the play operator of the commanded (motor-side)
            length; the pose follows the six realized lengths by least squares (equally stiff cables in
            pretension pull toward their lengths; a cable with slack on one side of its play is the one
            the others move). The motor's step count still reports the commanded length.
        fsr: the FSR alone (scenes.fsr_sensor.FsrSensor: its own hysteresis, the datasheet's, on the
            calibration's loading branch; its noise_counts unused: the robot's ADC noise above) in place of
            the calibration's whole branch gap as the FSR's play (teleop.core.sensors.FsrBranchLag, which also
            holds the calibration rig's friction); with_named_plant sets it for the distributed plant, whose
            estimators use the calibration fitted on that plant (scenes.fsr_lab.plant_fsr_calibration).
    """

    geometry: Geometry = field(default_factory=default_geometry)
    world: WorldParams = WorldParams()
    substeps: int = 1
    sensor: str = "fsr"
    fbg_cable: int = 0
    pretension: float = SH.Sheath.pretension
    tip_stiffness: float | None = 1.0e4
    ee_damping_ratio: float = 0.7
    plant: RichPlantParams | None = None
    cable: TendonSheathParams | None = None
    pulley: PulleyTransmissionParams | None = None
    capstan_k: float = SH.Sheath.stick_k
    noise_counts: float = 1.0
    backlash: float = 0.0
    fsr: FsrSensorParams | None = None

    def __post_init__(self):
        g = self.geometry
        if not (math.isfinite(self.backlash) and 0 <= self.backlash < g.l_max - g.l_min):
            raise InputError(f"sim robot: backlash must be a play width in [0, {g.l_max - g.l_min:g}) m, got "
                             f"{self.backlash}")
        if self.substeps < 1 or not g.t_min < self.pretension < g.t_max:
            raise InputError(f"sim robot: need substeps >= 1 and t_min < pretension < t_max, got "
                             f"{self.substeps}, {self.pretension}")
        if self.tip_stiffness is not None and self.tip_stiffness <= 0:
            raise InputError("sim robot: tip_stiffness must be > 0 (or None for a rigid tip)")
        fbg_cables(self.sensor, len(g.B), self.fbg_cable)  # a known kind and cable (one-line InputError)
        if self.pulley is not None and (self.cable is not None or self.plant is not None):
            raise InputError("sim robot: the pulley chain (pulley) is a plant of its own; drop cable and plant")
        if self.cable is not None and self.plant is not None:
            raise InputError("sim robot: the distributed cable (cable) and the rich plant (plant) are two plants; "
                             "choose one")

    @property
    def dt(self) -> float:
        """Time between readings [s]."""
        return self.world.dt * self.substeps

    @property
    def sheath(self) -> SH.Sheath:
        """The sheaths of this robot: the geometry's mu and theta0, capstan_k, the pretension."""
        g = self.geometry
        return SH.Sheath(mu=g.mu, theta0=g.theta0, stick_k=self.capstan_k, pretension=self.pretension)

    @property
    def fk_residual(self) -> float:
        """Largest length residual [m] the forward kinematics accepts: 1 um, plus, with play, the 2-norm of a
        full width on every cable (realized lengths that no pose has exactly)."""
        return 1e-6 + math.sqrt(6.0) * self.backlash


HOME_POSE = np.zeros(6)
_STATUS = {s: robot_status(homed=True, stopped=s) for s in (False, True)}  # the status byte, by the STOP latch


def home_pose() -> np.ndarray:
    """(6,) home pose: the shaft on the scaffold axis, its tip 5 mm before the pad surface."""
    return HOME_POSE.copy()


# --------------------------------------------------------------------------------------------------------
# pure helpers (batched over samples)
# --------------------------------------------------------------------------------------------------------

def lengths2poses(L, geom: Geometry, guess=None, iters: int = 12, tol: float = 1e-12,
                  max_residual: float = 1e-6) -> np.ndarray:
    """(n, 6) poses for (n, 6) cable lengths [m] (axial geometry, alpha = 0): each sample by the forward
    kinematics kernel from the previous one (the first from `guess`), least squares; raises InputError if
    any sample misses by more than max_residual [m]."""
    L = np.ascontiguousarray(np.atleast_2d(np.asarray(L, dtype=float)))
    q0 = np.zeros(6) if guess is None else np.array(guess, dtype=float).reshape(6)
    out = np.empty((len(L), 6))
    worst = KS.forward_kinematics_batch(L, q0, FREE_AXIAL, geom.r, geom.B, tol, iters, out)
    if not worst <= max_residual:
        raise InputError(f"sim robot: no pose reproduces the commanded lengths (residual {worst:.3g} m)")
    return out


def pose_terms_batch(poses, geom: Geometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """((n, 6, 6) structure matrices A (eq 8), (n, 6) wraps Theta = theta (eq 6) + theta0 [rad], (n, 3) tool
    offsets R tip [m]) for (n, 6) poses (kernel sim.pose_terms_loop over sim.pose_terms)."""
    q = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, dtype=float)))
    m, c = len(q), len(geom.B)
    A, theta, tip = np.empty((m, 6, c)), np.empty((m, c)), np.empty((m, 3))
    KS.pose_terms_loop(q, geom.r, geom.B, np.asarray(geom.v, dtype=float), float(geom.theta0),
                       np.asarray(geom.tip, dtype=float), A, theta, tip)
    return A, theta, tip


def capstan_angles_batch(poses, geom: Geometry) -> np.ndarray:
    """(n, 6) total wrap Theta = theta (eq 6) + theta0 [rad] between each FSR and the end effector."""
    return pose_terms_batch(poses, geom)[1]


def structure_matrices(poses, geom: Geometry) -> np.ndarray:
    """(n, 6, 6) structure matrices A of eq 8 (as teleop.core.kinematics.structure_matrix, batched)."""
    return pose_terms_batch(poses, geom)[0]


def wrenches2tensions(f, A, t_min: float, t_max: float, t_ref: float) -> np.ndarray:
    """(n, 6) tensions for wrenches f (n, 6) and structure matrices A (n, 6, 6): teleop.core.tension's
    distribution (A t + f = 0, the one-dimensional null space n > 0, closest to t_ref, clipped to the
    feasible interval; kernel tension.null1_tensions per sample). Samples it cannot decide (rank != 5,
    infeasible) go to wrench2tensions (which raises with the reason, or solves a wider null space)."""
    f = np.ascontiguousarray(f, dtype=float)
    A = np.ascontiguousarray(A, dtype=float)
    t = np.empty(f.shape)
    status = np.empty(len(f), dtype=np.int64)
    KT.tensions_batch(f, A, float(t_min), float(t_max), float(t_ref), t, status)
    for k in np.flatnonzero(status != KT.OK):  # the reference implementation decides (and raises if infeasible)
        t[k] = wrench2tensions(f[k], A[k], t_min, t_max, t_ref)
    return t


def fsr_conductance(u, cal: FsrCalibration) -> np.ndarray:
    """Conductance [S] of FSRs at equivalent tension u [N] (teleop.core.sensors.FsrBranchLag): the calibration's
    loading branch (= cal.reading(u, LOADING): its power series, clipped at 0; kernel linalg.horner)."""
    u = np.asarray(u, dtype=float)
    flat = np.ascontiguousarray(u.reshape(-1))
    return KS.conductance_loop(flat, np.asarray(cal.loading, dtype=float), np.empty(flat.shape[0])).reshape(u.shape)


def counts_from(g, cal: FsrCalibration, noise) -> np.ndarray:
    """Rounded, clipped ADC counts (int64) for conductance g [S] plus noise [counts]."""
    return adc_counts(cal.conductance2counts(g) + noise, cal.adc_max)


@dataclass
class SimTrace:
    """What `SimRobot.run` produced, one row per reading.

    Attributes:
        t: (n,) time [s]; lengths: (n, 6) commanded lengths [m]; poses: (n, 6) commanded poses;
        tip: (n, 3) actual tip [m]; wrench_truth: (n, 6) contact wrench on the end effector [N, N m];
        t_tip: (n, 6) cable tensions at the end effector [N]; t_fsr: (n, 6) tensions at the FSRs [N];
        counts: (n, 6) raw FSR counts; theta: (n, 6) capstan wrap [rad]; fbg_pm: (n, 2, 6) Bragg shifts of
        the distal FBGs [pm] (RobotReading.fbg_pm; (n, 0, 6) for sensor "fsr").
    """

    t: np.ndarray
    lengths: np.ndarray
    poses: np.ndarray
    tip: np.ndarray
    wrench_truth: np.ndarray
    t_tip: np.ndarray
    t_fsr: np.ndarray
    counts: np.ndarray
    theta: np.ndarray
    fbg_pm: np.ndarray | None = None


# --------------------------------------------------------------------------------------------------------
# the device
# --------------------------------------------------------------------------------------------------------

class SimRobot(ContextDevice):
    """The simulated slave. `command_lengths` sets the target; each `read()` advances one reading period.

    Args:
        pad: the pad in the scene (default: the 60 mm z-test pad).
        params: physics (SimRobotParams).
        seed: seeds the ADC noise.
        calibration: FSR calibration shared with the estimator side (default teleop.core.sensors').
    """

    def __init__(self, pad: Pad | None = None, params: SimRobotParams = SimRobotParams(), seed: int = 0,
                 calibration: FsrCalibration | None = None, model=None):
        self.model = model   # an identified link model (teleop.io.model_io): its findings switched on
        self.pad = pad if pad is not None else z_test_pad()
        self.params = params
        self.seed = int(seed)
        self.cal = calibration if calibration is not None else default_fsr_calibration()
        self.spec = RobotSpec(l_min=params.geometry.l_min, l_max=params.geometry.l_max, v_max=params.geometry.v_max)
        self.is_open = False

    # lifecycle -------------------------------------------------------------------------------------
    def open(self) -> None:
        if self.is_open:
            return
        p = self.params
        self.geom = p.geometry
        self.rng = np.random.default_rng(self.seed)
        self._nbuf, self._nbuf_i = np.empty((0, len(self.geom.B))), 0  # ADC noise rows drawn ahead (_noise_rows)
        K = C = None
        if p.tip_stiffness is not None:
            K = np.eye(3) * p.tip_stiffness
            C = np.eye(3) * 2.0 * p.ee_damping_ratio * math.sqrt(p.world.indenter_mass * p.tip_stiffness)
        self.world = PadWorld(self.pad, p.world, stiffness=K, damping=C)
        self.world.open()
        self.L_home = poses2lengths(HOME_POSE, self.geom)[0]
        self.L_cmd = self.L_home.copy()
        self.pose = HOME_POSE.copy()
        self._fk = PoseFollower(self.geom, self.pose, max_residual=p.fk_residual)
        # per-cable play (physics backlash Steps), starting centred on the home lengths
        self._play = [get_effect("backlash").make_step({"width": p.backlash}) for _ in self.L_home] \
            if p.backlash > 0 else None
        if self._play is not None:
            self._L_real = np.array([st.step(x=float(v)) for st, v in zip(self._play, self.L_home)])
        self._terms = None
        self.t = 0.0
        self.seq = 0
        self.boot_id = (self.seed * 2654435761) % 2 ** 31
        self.stopped = False
        n = len(self.geom.B)
        self._cap = SH.new_state(n)  # the sheath's state per cable (teleop.core.kernels.sheath)
        self._A, self._theta, self._tip_off, self._target = np.empty((6, n)), np.empty(n), np.empty(3), np.empty(3)
        self._off = np.empty((n, 6))
        self._v, self._tip = np.asarray(self.geom.v, dtype=float), np.asarray(self.geom.tip, dtype=float)
        self._term_out = (self._v, float(self.geom.theta0), self._tip, self._off, self._A, self._theta, self._tip_off,
                          self._target)  # where PoseFollower.follow writes a new pose's terms
        self._terms_at = (self._tip_off, self._target)  # _terms once the commanded pose's terms are written
        kc = np.empty(KS.N_READING_CONST)  # the constants of kernel sim.reading: the sheath's first
        kc[:SH.N_CONST] = p.sheath.constants()
        kc[[KS.T_MIN, KS.T_MAX, KS.STEPS_PER_M]] = self.geom.t_min, self.geom.t_max, self.spec.steps_per_m
        self._kc = kc
        self._fbg = FbgArray(p.sensor, n, self.seed, cable=p.fbg_cable) if p.sensor != "fsr" else None
        self._lag = FsrBranchLag(self.cal, n)
        self._lag_args = self._lag.kernel_args()  # its state (written in place) and constants, for kernel reading_counts
        self._fsr = None if p.fsr is None else FsrSensor(n, self.seed, p.fsr, self.cal)  # the FSR alone (params.fsr)
        self._no_noise = np.zeros((1, n))
        self._added = _AddedEffects(self.model, n) if self.model is not None else None
        self._rich = RichPlant(p.plant, n) if p.plant is not None else None
        self._cables = None if p.cable is None else DistributedCables(p.cable, n, p.pretension, p.dt, self.L_home,
                                                                      float(self.geom.theta0))
        if p.pulley is not None:  # the same interface as DistributedCables
            self._cables = PulleyTransmission(p.pulley, n, self.L_home, float(self.geom.mu))
        # the distributed cable with nothing between it and its FSR: one kernel call a reading (reading_cables)
        self._fused = self._cables.kernel_args() if isinstance(self._cables, DistributedCables) and \
            self._added is None else None
        # ... and its FSR alone with nothing in between (no rich plant): the counts in that call (reading_cables_fsr)
        self._fused_fsr = (self._tip_off, self._A, self._theta, self.L_home, self._kc, *self._fused[:4], TAP_FSR,
                           *self._fsr.kernel_args()) if self._fused is not None and self._fsr is not None and \
            self._rich is None else None  # reading_cables_fsr's arguments that stay the same objects
        # ... held together, one argument of the reading's call (reading_cables_fsr_fixed)
        self._fixed_fsr = None if self._fused_fsr is None else fixed_fsr(*self._fused_fsr)
        self._out_shape = None if self._fused is None else (self._fused[-1], n)  # a tick's cable output (read)
        self._sheath = None if self._fused is None else self._cables.sheath  # its clock advances each reading
        self._bound_fsr = self._bound_cables = self._bound_counts = None  # read's kernel, bound at the first reading
        self._dt = p.dt  # [s] a reading's period (read's: a property call less)
        self._noisy = p.noise_counts > 0  # ADC noise drawn (read's: _noise_row's test)
        self._n, self._substeps = n, p.substeps  # cables, physics steps a reading (read's: lookups less)
        self.is_open = True

    def close(self) -> None:
        if self.is_open:
            self.world.close()
            self.is_open = False

    def _require_open(self) -> None:
        if not self.is_open:
            raise InputError("sim robot: not open (use it as a context manager)")

    # Robot protocol --------------------------------------------------------------------------------
    def command_lengths(self, lengths) -> None:
        """Command cable lengths (6,) [m] (checked against the geometry's limits)."""
        if not self.is_open:
            self._require_open()
        L = np.array(lengths, dtype=float)  # the robot's own copy (the caller may change its array)
        if self.stopped or self._play is not None or L.shape != (6,):
            L = check_lengths(L, self.geom)
            if self.stopped:
                return
        # the limits (unless checked above), forward kinematics and, if the pose moved, its terms (A, wraps,
        # tool offset, tip target): one kernel call (PoseFollower.follow raises as check_lengths)
        pose = self._fk.follow(L if self._play is None else self._realize(L), self._term_out)
        if pose is not None:
            self.pose, self._terms = pose.copy(), self._terms_at
        self.L_cmd = L

    def _realize(self, L: np.ndarray) -> np.ndarray:
        """Realized cable lengths (6,) [m]: each cable's play operator stepped to its commanded length."""
        out = self._L_real
        for i, st in enumerate(self._play):
            out[i] = st.step(x=float(L[i]))
        return out

    def set_pad_offset(self, xy) -> None:
        """Move the pad so its centre sits at xy (2,) [m] in {B} (a positioning stage; pads wider than the
        robot's reach are slid under it)."""
        self._require_open()
        self.world.set_offset(xy)

    def stop(self) -> None:
        """Hold the current lengths; further commands are ignored until `open` again."""
        self.stopped = True

    def _pose_terms(self) -> tuple:
        """(tool offset R tip (3,) [m], tip target (3,) [m]) of the commanded pose, computed once per pose
        with its structure matrix and capstan wraps (kernel sim.pose_terms, held in _A, _theta)."""
        if self._terms is None:
            g = self.geom
            KS.pose_target(self.pose, g.r, g.B, self._v, float(g.theta0), self._tip, self._off, self._A,
                           self._theta, self._tip_off, self._target)
            self._terms = self._terms_at
        return self._terms

    def read(self) -> RobotReading:
        """Advance one reading period and return the raw reading."""
        if not self.is_open:
            self._require_open()
        # `substeps` physics steps toward the commanded pose: tip (3,) [m], contact force (fx, fy, fz) [N] on the tip
        tip, F = self.world.advance(self._target if self._terms is not None else self._pose_terms()[1],
                                    self._substeps)
        n = self._n
        t_tip, f, steps, counts = np.empty(n), np.empty(6), np.empty(n, np.int64), np.empty(n, np.int64)
        noise, k = self._nbuf, self._nbuf_i  # this reading's ADC noise [counts]: noise[k] (_noise_row written out)
        if self._noisy and k < len(noise):
            self._nbuf_i = k + 1
        else:
            noise, k = self._noise_row()
        fused = self._fused
        if fused is not None:  # the distributed cable and its FSRs in the same call (kernel reading_cables)
            out = np.empty(self._out_shape)  # the tick's cable output: motor force, taps (O_ROWS, TAP_*)
            # the kernel bound to this robot's argument types at its first reading (jit.bind: the arrays are the
            # robot's own; F the world's tuple of floats, anything else goes through numba's dispatch)
            if self._fused_fsr is not None:  # the FSR alone (params.fsr): its counts in the call
                L = self.L_cmd
                call = self._bound_fsr if type(F) is tuple else reading_cables_fsr_fixed
                if call is None:
                    call = self._bound_fsr = bind(reading_cables_fsr_fixed, self._fixed_fsr, F, L, L, noise, k, f,
                                                  t_tip, steps, out, counts)
                status = call(self._fixed_fsr, F, L, L if self._play is None else self._L_real, noise, k, f, t_tip,
                              steps, out, counts)
                done = status == OK
            else:
                args = (self._tip_off, F, self._A, self._theta, self.L_home, self.L_cmd, self._kc, f, t_tip, steps,
                        self.L_cmd if self._play is None else self._L_real, *fused[:4], out, TAP_FSR, *self._lag_args,
                        noise, k, counts)
                call = self._bound_cables if type(F) is tuple else reading_cables
                if call is None:
                    call = self._bound_cables = bind(reading_cables, *args)
                status = call(*args)
                done = status == OK and self._rich is None and self._fsr is None
            if done:  # the usual case: no motor position, no lumped sheath, the FSRs' counts from the call
                self._sheath.t += self._dt
                return self._reading(counts, steps, f, tip, t_tip, out[TAP_FSR],
                                     None if self._fbg is None else out[TAP_FBG], out[O_MOTOR])
        p, g = self.params, self.geom
        x = -self.L_cmd  # motor position: hauling in (shortening) is +
        if self._rich is not None and self._play is not None:  # the cable moves with its realized length
            x = -self._L_real
        t_fsr = np.empty(n)
        direct = self._added is None and self._rich is None and self._cables is None  # nothing between sheath and FSR
        if fused is None:
            # one kernel call: the wrench f (force at the tool tip, moments about p), the motor steps, the cable
            # chain and, when direct, the FSRs (lag, conductance, ADC: FsrBranchLag.counts)
            call = self._bound_counts if type(F) is tuple else KS.reading_counts  # bound as reading_cables_fsr
            if call is None:
                call = self._bound_counts = bind(KS.reading_counts, self._tip_off, F, self._A, self._theta, x,
                                                 self.L_home, self.L_cmd, self._kc, self._cap, f, t_tip, t_fsr, steps,
                                                 direct, *self._lag_args, noise, k, counts)
            status = call(self._tip_off, F, self._A, self._theta, x, self.L_home, self.L_cmd, self._kc, self._cap, f,
                          t_tip, t_fsr, steps, direct, *self._lag_args, noise, k, counts)
        if status != OK:
            # not the one-dimensional null space, or infeasible: teleop.core.tension decides (raises with the reason)
            t_tip = TensionSolver(self._A, g.t_min, g.t_max, p.pretension).solve(f)
            SH.motor_forces(self._cap, x, t_tip, self._theta, self._kc, t_fsr)
        t_fbg, t_motor = t_tip, None
        # the FSRs' counts came with the kernel call (not those of the FSR alone, params.fsr)
        counted = status == OK and (direct or fused is not None) and self._fsr is None
        if fused is not None and status == OK:  # the cable's tick was in the call: its output rows
            self._sheath.t += self._dt
            t_fsr, t_fbg, t_motor = out[TAP_FSR], out[TAP_FBG], out[O_MOTOR]
        elif self._cables is not None:  # the distributed cable in place of the lumped sheath
            t_fsr, t_fbg, t_motor = self._cables.step(self.L_cmd if self._play is None else self._L_real, t_tip,
                                                      self._theta)
        if self._added is not None:
            t_fsr = self._added.forces(t_fsr, x, self.t + self._dt)
        if self._rich is not None:
            t_fsr = self._rich.forces(t_fsr[None], x[None], [self.t + self._dt])[0]
        if self._fsr is not None:  # the FSR alone: its hysteresis on ln G, then the divider and ADC (as run())
            self._fsr.counts_into(t_fsr[None], noise[k:k + 1], counts[None])
        elif not counted:  # lag, conductance, ADC (FsrBranchLag.counts' kernel, = counts_from(..))
            fsr_counts(t_fsr, *self._lag_args, noise[k], counts)
        return self._reading(counts, steps, f, tip, t_tip, t_fsr, t_fbg, t_motor)

    def _reading(self, counts, steps, f, tip, t_tip, t_fsr, t_fbg, t_motor) -> RobotReading:
        """The reading's record (read's end): the distal FBGs' wavelengths from t_fbg (unused without FBGs), the
        cable's tension at the motor t_motor (extras "t_motor"; None: a plant without one), the clock and
        sequence advanced one reading."""
        t = self.t + self._dt
        fbg = None if self._fbg is None else self._fbg.read(t_fbg, t)  # distal FBGs (sim_sensors)
        self.t = t
        self.seq = seq = self.seq + 1
        # the pose and the commanded lengths as they are, no copies: the robot replaces those arrays (a new array
        # each command, each pose that moved) and never writes one in place
        extras = {"t_tip": t_tip, "t_fsr": t_fsr, "tip": tip, "pose": self.pose}
        if t_motor is not None:
            extras["t_motor"] = t_motor
        return RobotReading(t, seq, counts, steps, self.L_cmd, _STATUS[self.stopped], self.boot_id, f, extras, fbg)

    def _noise_row(self) -> tuple:
        """(block, k): the next row of ADC noise [counts] is block[k] (the row _noise_rows(1)[0] would be, without
        making the views; zeros without noise)."""
        if self.params.noise_counts <= 0:
            return self._no_noise, 0
        k = self._nbuf_i
        if k < len(self._nbuf):
            self._nbuf_i = k + 1
            return self._nbuf, k
        self._noise_rows(1)  # the next block: its row 0
        return self._nbuf, 0

    def _noise_rows(self, m: int) -> np.ndarray:
        """(m, n) ADC noise [counts], N(0, noise_counts): the next m rows of the seeded stream, drawn 1024 rows
        at a time (Generator.normal fills element by element: the numbers of drawing m rows when needed; a
        draw has a fixed cost whatever its size). The rows are views of a block that is replaced, never written."""
        buf, i = self._nbuf, self._nbuf_i
        if i + m > len(buf):
            fresh = self.rng.normal(0.0, self.params.noise_counts, (max(m, 1024), buf.shape[1]))
            buf, i = (np.concatenate([buf[i:], fresh]) if i < len(buf) else fresh), 0
            self._nbuf = buf
        self._nbuf_i = i + m
        return buf[i:i + m]

    # batch path ------------------------------------------------------------------------------------
    def run(self, lengths, progress=None) -> SimTrace:
        """Command each row of `lengths` (n, 6) [m] and read once after each; array physics after the
        pybullet pass. `progress(k)` is called every 1000 readings if given."""
        self._require_open()
        p, g = self.params, self.geom
        L = np.asarray(lengths, dtype=float)
        for row in (L[0], L[-1], L.min(axis=0), L.max(axis=0)):
            check_lengths(row, g)
        n = len(L)
        if self._play is None:
            poses = lengths2poses(L, g, guess=self.pose)
        else:  # the play operator along each cable from its current state (physics backlash, array form)
            Lr = np.column_stack([backlash(L[:, i], p.backlash, y0=self._play[i].y) for i in range(L.shape[1])])
            for i, st in enumerate(self._play):
                st.y = self._L_real[i] = float(Lr[-1, i])
            poses = lengths2poses(Lr, g, guess=self.pose, max_residual=p.fk_residual)
        tips = np.empty((n, 3))
        F = np.empty((n, 3))
        w = self.world
        A, theta, R_tip = pose_terms_batch(poses, g)
        targets = poses[:, :3] + R_tip
        sub = p.substeps
        for k in range(n):
            tk = targets[k]
            for _ in range(sub):
                w.step(tk)
            F[k] = w.contact_force()
            tips[k] = w.tip()
            if progress is not None and k % 1000 == 999:
                progress(1000)
        f = np.concatenate([F, np.cross(R_tip, F)], axis=1)
        t_tip = wrenches2tensions(f, A, g.t_min, g.t_max, p.pretension)
        x = -L  # motor positions: hauling in (shortening) is +
        if self._rich is not None and self._play is not None:  # the cable moves with its realized length
            x = -Lr
        t_fsr, t_fbg = np.empty((n, 6)), t_tip
        if self._cables is not None:  # the distributed cable in place of the lumped sheath (as read())
            t_fsr, t_fbg, _ = self._cables.run(np.ascontiguousarray(L if self._play is None else Lr), t_tip, theta)
        for i in range(6 if self._cables is None else 0):  # each lumped sheath along the run, from its state
            SH.motor_force_run(np.ascontiguousarray(x[:, i]), np.ascontiguousarray(t_tip[:, i]),
                               np.ascontiguousarray(theta[:, i]), self._kc, self._cap, i, t_fsr[:, i])
        if self._rich is not None:
            t_fsr = self._rich.forces(t_fsr, x, self.t + p.dt * np.arange(1, n + 1))
        noise = self._noise_rows(n) if p.noise_counts > 0 else np.zeros((n, 6))
        if self._fsr is not None:  # the FSR alone (params.fsr): its hysteresis on ln G, the divider and ADC
            counts = np.empty(t_fsr.shape, dtype=np.int64)
            self._fsr.counts_into(np.ascontiguousarray(t_fsr), np.ascontiguousarray(noise), counts)
        else:  # the calibration's branch gap as the FSR's play
            counts = counts_from(fsr_conductance(self._lag.run(t_fsr), self.cal), self.cal, noise)
        t = self.t + p.dt * np.arange(1, n + 1)
        fbg = np.empty((n, 0, 6)) if self._fbg is None else self._fbg.run(t_fbg, t)
        self.t = float(t[-1])
        self.seq += n
        self.L_cmd = L[-1].copy()
        self.pose, self._terms = poses[-1].copy(), None
        self._fk.q = self.pose
        return SimTrace(t=t, lengths=L, poses=poses, tip=tips, wrench_truth=f, t_tip=t_tip, t_fsr=t_fsr,
                        counts=counts, theta=theta, fbg_pm=fbg)


TAP_FBG, TAP_FSR = O_ROWS, O_ROWS + 1  # rows of a DistributedCables tick's output: the FBG's element, the FSR's node


class DistributedCables:
    """The robot's cables as distributed tendon-sheath cables (scenes.tendon_sheath, `SimRobotParams.cable`).

    Coupling: the motor drives each cable's proximal end by its haul-in from the home lengths, x = L_home - L
    (L the commanded length, the realized one with play); the distal end carries the tension at the end
    effector as a force load, t_tip of the tension distribution (A t + f = 0), the end effector held at its
    commanded pose with the robot's compliance lumped at the tip (tip_stiffness), as in the lumped plant. (A
    prescribed tip travel from the end effector's lengths would leave the cable's stretch, and with it the
    contact, out of the tensions: those lengths follow the commanded ones exactly.) The kinematic bend theta
    (eq 6) sits on the sheath's kinematic span, the scaffold and route bends are the cable's own.
    Sensors read the cable's tensions: the FSR the tension at B, the node where the scaffold bend begins
    (scenes.tendon_sheath.b_node, the tension between its two elements as tension_at_b reads it); the FBG the
    element FBG_FROM_END_M before the sheath's end.
    `step` (one reading) and `run` (m readings) call the same compiled step.
    """

    def __init__(self, params: TendonSheathParams, n: int, pretension: float, tick: float, L_home=0.0,
                 theta0: float = 0.0):
        self.params = params
        self.j_fsr = b_node(params)  # a node
        self.j_fbg = self.element_at(params.length - FBG_FROM_END_M)
        self.sheath = TendonSheath(params, SheathLoad("force"), pretension=pretension, n_cables=n, tick=tick,
                                   taps=(self.j_fbg,), node_taps=(self.j_fsr,), motor_ref=L_home, motor_sign=-1.0,
                                   theta_offset=theta0)
        self._rows = self.sheath.out_rows
        self._step_into = self.sheath.step_into

    def kernel_args(self) -> tuple:
        """(S, cab, p, T, rows): the cables' state, parameters and element tensions as kernel
        tendon_sheath_kernels.step takes them (written in place), and the rows of a tick's output, for a caller
        that fuses the step into its own kernel (scenes.sim_robot_kernels.reading_cables); it advances
        sheath.t itself."""
        s = self.sheath
        return s._S, s._cab, s._p, s.tensions, self._rows

    def element_at(self, s: float) -> int:
        """Index of the element holding arc length s [m] from the motor (TendonSheath.tension_at's rule)."""
        p = self.params
        return min(max(int(s / p.element_length), 0), p.n_elements - 1)

    def step(self, L, t_tip, wrap) -> tuple:
        """One reading: cable lengths L (n,) [m] (the motor hauls in L_home - L), tip tensions t_tip (n,) [N],
        capstan wraps wrap = theta + theta0 (n,) [rad] -> (tension at the FSR, at the FBG, at the motor) (n,) each
        [N] (rows of one new array). One compiled call (TendonSheath.step_into)."""
        out = np.empty((self._rows, len(L)))
        self._step_into(L, t_tip, wrap, out)  # the robot's own (n,) float arrays: no checks
        return out[TAP_FSR], out[TAP_FBG], out[O_MOTOR]

    def run(self, X, T_tip, TH) -> tuple:
        """`step` over m readings, (m, n) lengths, tip tensions and wraps -> (m, n) tensions at the FSR, the FBG
        and the motor [N]."""
        r = self.sheath.run(X, T_tip, TH)
        return tuple(np.ascontiguousarray(a) for a in (r.tapped[:, TAP_FSR - O_ROWS], r.tapped[:, TAP_FBG - O_ROWS],
                                                        r.f_motor))


class _AddedEffects:
    """The findings of an identified link model (teleop diagnose --save-model) switched on in every cable,
    per sample (the physics Steps of teleop.core.physics, the same models the diagnosis fitted):

    - force link and sensor effects: the tension at the FSR -> with the added friction or sensor effect,
      along the motor position x = -length (hauling in is +).
    Position-link effects are refused: per-cable play would give six lengths that no pose has.
    Baseline effects of the model (the sheath's capstan friction) are not added: the robot has its own.
    Gains and offsets of the model are those of the rig it was identified on and are not applied.
    """

    def __init__(self, model, n: int):
        if "position" in model.links and model.links["position"].effects[model.links["position"].base:]:
            raise InputError("sim://robot: position-link effects (play, stretch) cannot be switched on in the "
                             "6-cable robot: its six lengths must stay those of one pose (rank-5 structure); "
                             "switch them on in the single-cable bench (scenes.cable_rig)")

        def steps(kind):
            if kind not in model.links:
                return [[] for _ in range(n)]
            m = model.links[kind]
            return [[(get_effect(name), get_effect(name).make_step(p)) for name, p in m.effects[m.base:]]
                    for _ in range(n)]
        self.force = steps("force")
        self.x_prev = None
        self.t_prev = None

    def forces(self, t_fsr: np.ndarray, x: np.ndarray, t: float) -> np.ndarray:
        if not any(self.force):
            return t_fsr
        dt = (t - self.t_prev) if self.t_prev is not None else 0.0
        v = (x - self.x_prev) / dt if self.x_prev is not None and dt > 0 else np.zeros_like(x)
        self.x_prev, self.t_prev = x.copy(), t
        out = t_fsr.copy()
        for i, chain in enumerate(self.force):
            F = float(t_fsr[i])
            for eff, st in chain:
                ch = {"x": float(x[i]), "v": float(v[i]), "load": F, "force": F, "t": t, "temperature": 25.0}
                F = st.step(**{c: ch[c] for c in eff.inputs + eff.optional if c in ch})
            out[i] = F
        return out


#: the simulated robot's plants: matched (its physics is the estimators' model), rich (scenes.rich_plant's effects
#: on top), distributed (scenes.tendon_sheath's cable in place of the lumped sheath), pulley (seed 002's chain there)
PLANTS = RICH_PLANTS + ("distributed", "pulley")


def with_named_plant(sim: SimRobotParams, plant: str, seed: int, cable_params=None) -> SimRobotParams:
    """`sim` with the plant named `plant` (PLANTS): matched; rich (drawn from `seed`, its play the robot's);
    distributed (TendonSheathParams from the [tendon_sheath] table of the TOML file `cable_params`, or its
    defaults; docs/formats.md); pulley (PulleyTransmissionParams from the [pulley_transmission] table of
    `cable_params`, or its defaults)."""
    if plant not in PLANTS:
        raise InputError(f"unknown plant '{plant}' (expected one of: {', '.join(PLANTS)})")
    if plant == "pulley":
        pulley = PulleyTransmissionParams.from_toml(cable_params) if cable_params else PulleyTransmissionParams()
        return replace(with_plant(sim, None), cable=None, pulley=pulley, fsr=None)
    if plant != "distributed":
        if cable_params is not None:
            raise InputError("cable parameters (cable_params) belong to the distributed plant")
        return replace(with_plant(sim, plant_params(plant, seed)), cable=None, pulley=None, fsr=None)
    cable = TendonSheathParams() if cable_params is None else TendonSheathParams.from_toml(cable_params)
    return replace(with_plant(sim, None), cable=cable, pulley=None, fsr=FsrSensorParams())


def from_url(parsed, options: dict) -> SimRobot:
    """`sim://robot?pad=z60&seed=3&substeps=1&model=M.json&backlash_mm=0.5`: build (not open) a SimRobot;
    `model`: an identified link model (teleop diagnose --save-model) whose findings are switched on in every
    cable; `backlash_mm`: each cable's play width [mm] (SimRobotParams.backlash); `plant=rich`: effects the
    estimators do not model (scenes.rich_plant, drawn from `seed`; `matched`, the default: none);
    `plant=distributed`: the distributed tendon-sheath cable (DistributedCables), `cable_params=F.toml` its
    parameters (docs/formats.md); `plant=pulley`: seed 002's pulley chain (scenes.pulley_transmission),
    `cable_params=F.toml` its [pulley_transmission] table."""
    known = {"pad", "seed", "substeps", "letter", "model", "backlash_mm", "sensor", "cable", "plant", "cable_params"}
    for k in options:
        if k not in known:
            raise InputError(f"sim://robot: unknown option '{k}' (expected one of: {', '.join(sorted(known))})")
    makers = {"z60": pads_mod.z_test_pad, "stiffness3": pads_mod.three_region_pad, "hole27": pads_mod.hole_pad,
              "letter_E": lambda: pads_mod.letter_pad("E"), "letter_P": lambda: pads_mod.letter_pad("P"),
              "blind4": pads_mod.blind_test_pad}
    name = str(options.get("pad", "z60"))
    if name not in makers:
        raise InputError(f"sim://robot: unknown pad '{name}' (expected one of: {', '.join(makers)})")
    try:
        seed = int(options.get("seed", 0))
        substeps = int(options.get("substeps", 1))
    except ValueError:
        raise InputError("sim://robot: seed and substeps must be integers") from None
    try:
        play_w = float(options.get("backlash_mm", 0.0)) * 1e-3
    except ValueError:
        raise InputError(f"sim://robot: backlash_mm must be a play width in mm, got {options['backlash_mm']!r}") from None
    try:  # sensor=fsr|fbg|one, cable=I: the FBG of sensor=one (scenes.sim_sensors)
        sensing = {"sensor": str(options.get("sensor", "fsr")), "fbg_cable": int(options.get("cable", 0))}
    except ValueError:
        hint = " (the distributed cable is plant=distributed)" if options.get("cable") == "distributed" else ""
        raise InputError(f"sim://robot: cable must be the FBG's cable index of sensor=one, got "
                         f"{options['cable']!r}{hint}") from None
    model = None
    if "model" in options:
        model = load_model(str(options["model"]))
    params = SimRobotParams(substeps=substeps, backlash=play_w, **sensing)
    if "plant" in options or "cable_params" in options:  # the rich plant's cables drawn from the seed; backlash_mm wins
        cable_params = None if "cable_params" not in options else str(options["cable_params"])
        params = with_named_plant(params, str(options.get("plant", "matched")), seed, cable_params)
        if "backlash_mm" in options:
            params = replace(params, backlash=play_w)
    return SimRobot(makers[name](), params, seed=seed, model=model)
