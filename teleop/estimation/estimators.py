"""The four wrench estimators (DESIGN.md names) behind one interface.

    est.update(tensions, lengths, pose, dt) -> (6,) wrench f [N, N m] in {B}

tensions: (6,) calibrated FSR tensions [N] (sensor side of the scaffold bend); lengths: (6,) cable lengths
[m] (their change decides loading vs unloading, seed 000 eq 7); pose: (6,) end-effector pose; dt [s].

- non_compensated: f = -A t_fsr.
- single: capstan compensation per cable (eq 7), Theta_i = theta_i (eq 6) + theta0, direction from the
  cable length change: shortening = pulling, t_tip = t_fsr exp(-mu Theta); lengthening: exp(+mu Theta).
- double: single + the turn compensation of step 3 (`turn.py`), the seed's strategy.
- dynamic: velocity- and reversal-aware. Per cable, the sheath friction the physics library models is
  removed in order: viscous b v and the Dahl pre-sliding state (both along the cable's own motion), then
  the capstan with stick transitions (physics.capstan tip2motor_transitions, stick stiffness k) is
  inverted through its friction state phi in [-1, 1], the sensor tension being t e^(phi mu Theta): phi
  follows the cable's own travel, d phi = k dx / (mu Theta t_sensor) (the sensor tension moves by k dx
  while the cable sticks), clipped at +-1 where it slips (phi = +1 hauling, -1 paying out: the seed's
  direction rule). So nothing jumps at a reversal, the transition lasts the cable travel the physics says,
  and a paid-out cable whose tension rises is still followed (the direction-free play form held it flat).
Every estimator ends with the same Kalman filter (kalman.py) unless built with kalman=None; its gain is the
steady state for the noise model's nominal dt, whatever dt is passed.

These classes are the readable form, written with the library functions. The loop and long studies use
`tick.TickComputer.estimate` (or `reading.ReadingEstimator`), which computes the same numbers on plain
floats about ten times faster (tests compare them sample by sample).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from teleop.errors import InputError
from teleop.estimation.direction import DirectionTracker
from teleop.estimation.kalman import KalmanNoise, SteadyWrenchKalman, WrenchKalmanParams, wrench_kalman_params
from teleop.estimation.turn import TurnCompensation, TurnCompensator
from teleop.geometry import Geometry
from teleop.kinematics import bending_angles, pose2cables, structure_matrix
from teleop.physics.capstan import motor2tip
from teleop.physics.friction import DahlStep, viscous
from teleop.tension import tensions2wrench

ESTIMATOR_NAMES = ("non_compensated", "single", "double", "dynamic")


def capstan_angles(pose, geom: Geometry) -> np.ndarray:
    """(6,) total wrap Theta_i = theta_i (eq 6) + theta0 [rad] between the FSR and the end effector."""
    return bending_angles(pose2cables(pose, geom), geom) + geom.theta0


@dataclass(frozen=True)
class DynamicParams:
    """Sheath friction removed by the `dynamic` estimator, per cable (physics-library parameters).

    Attributes:
        b: viscous coefficient [N s/m] (viscous_friction).
        dahl_sigma: Dahl rest stiffness [N/m]; dahl_Fc: Dahl sliding force [N] (dahl_hysteresis; 0 = off).
        v_smooth: time constant of the cable-velocity estimate [s].
        capstan_k: stick stiffness of the capstan transitions [N/m] (physics.capstan `k`; the simulated
            robot's 5e3 N/m, scenes.sim_robot, derived there from the seed's Fig 13 turn segments).
    """

    b: float = 0.0
    dahl_sigma: float = 1e4
    dahl_Fc: float = 0.0
    v_smooth: float = 0.0
    capstan_k: float = 5e3


class Estimator:
    """Base: compensation (override `compensate`), f = -A t, optional correction, Kalman."""

    name = ""

    def __init__(self, geom: Geometry, kalman: WrenchKalmanParams | None = None, length_deadband: float = 0.0):
        self.geom = geom
        self.kalman_params = kalman
        self.kalman = SteadyWrenchKalman(kalman) if kalman is not None else None
        self.cables = DirectionTracker(6, length_deadband)
        self.reset()

    def reset(self) -> None:
        self.cables.reset()
        if self.kalman is not None:
            self.kalman.reset()

    def compensate(self, t: np.ndarray, lengths: np.ndarray, theta: np.ndarray, dt: float) -> np.ndarray:
        """(6,) tip-side tensions [N] from sensor tensions t."""
        return t

    def correct(self, f: np.ndarray, pose: np.ndarray, dt: float) -> np.ndarray:
        """The wrench after any wrench-level correction."""
        return f

    def raw(self, tensions, lengths, pose, dt: float) -> np.ndarray:
        """(6,) unfiltered wrench (compensated, corrected)."""
        t = np.asarray(tensions, dtype=float)
        L = np.asarray(lengths, dtype=float)
        q = np.asarray(pose, dtype=float)
        self.cables.update(L)
        t_tip = self.compensate(t, L, capstan_angles(q, self.geom), dt)
        f = tensions2wrench(t_tip, structure_matrix(q, self.geom))  # f = -A t (eq 8)
        return self.correct(f, q, dt)

    def update(self, tensions, lengths, pose, dt: float) -> np.ndarray:
        """(6,) estimated external wrench [N, N m]."""
        f = self.raw(tensions, lengths, pose, dt)
        return np.asarray(self.kalman.update(f)) if self.kalman is not None else f


class NonCompensated(Estimator):
    name = "non_compensated"


class Single(Estimator):
    """Capstan compensation with loading/unloading from the cable length change (seed 000 eq 7)."""

    name = "single"

    def compensate(self, t, lengths, theta, dt):
        pulling = self.cables.direction <= 0  # shortening (or not yet moved) = the motor pulls
        return motor2tip(t, self.geom.mu, theta, pulling)


class Double(Single):
    """The seed's strategy: capstan compensation, then the turn compensation of step 3."""

    name = "double"

    def __init__(self, geom: Geometry, turn: TurnCompensation, kalman: WrenchKalmanParams | None = None,
                 length_deadband: float = 0.0):
        self.turn = TurnCompensator(turn)
        super().__init__(geom, kalman, length_deadband)

    def reset(self) -> None:
        super().reset()
        self.turn.reset()

    def correct(self, f, pose, dt):
        return f - self.turn.update(pose[:3], dt)


class Dynamic(Estimator):
    """Velocity- and reversal-aware: viscous and Dahl friction removed, capstan inverted with stick transitions."""

    name = "dynamic"

    def __init__(self, geom: Geometry, params: DynamicParams = DynamicParams(),
                 kalman: WrenchKalmanParams | None = None, length_deadband: float = 0.0):
        self.params = params
        super().__init__(geom, kalman, length_deadband)

    def reset(self) -> None:
        super().reset()
        self.L_prev = None
        self.v = np.zeros(6)
        self.dahl = [DahlStep({"sigma": self.params.dahl_sigma, "Fc": self.params.dahl_Fc})
                     for _ in range(6)] if self.params.dahl_Fc > 0 else None
        self.phi = np.zeros(6)

    def compensate(self, t, lengths, theta, dt):
        p = self.params
        dx = np.zeros(6) if self.L_prev is None else -(lengths - self.L_prev)  # motor travel, + pulling
        self.L_prev = lengths.copy()
        v = dx / dt if dt > 0 else np.zeros(6)
        a = dt / (p.v_smooth + dt) if dt > 0 else 0.0
        self.v = self.v + a * (v - self.v)
        t_c = t - viscous(self.v, p.b)
        if self.dahl is not None:  # Dahl friction along the motor position x = -length
            t_c = t_c - np.array([d.step(x=-Li, load=0.0) for d, Li in zip(self.dahl, lengths)])
        mT = self.geom.mu * np.asarray(theta, dtype=float)
        self.phi = capstan_state(self.phi, dx, t_c, mT, p.capstan_k)
        return t_c * np.exp(-self.phi * mT)


def capstan_state(phi, dx, t_sensor, mu_theta, k: float):
    """Friction state(s) phi in [-1, 1] after a motor travel dx [m] (+ hauling): the sensor tension
    t_sensor [N] = t_tip e^(phi mu_theta) moves by k dx [N] while the cable sticks (d phi = k dx / (mu_theta
    t_sensor)) and phi stays at +-1 while it slips. A slack cable (t_sensor <= 1e-6 N) slips at once."""
    dphi = k * np.asarray(dx, dtype=float) / np.maximum(mu_theta * np.maximum(t_sensor, 1e-6), 1e-12)
    return np.clip(phi + dphi, -1.0, 1.0)


def make_estimator(name: str, geom: Geometry, *, turn: TurnCompensation | None = None,
                   dynamic: DynamicParams = DynamicParams(), kalman: KalmanNoise | None = KalmanNoise(),
                   length_deadband: float = 0.0) -> Estimator:
    """An estimator by its DESIGN.md name; kalman=None leaves the wrench unfiltered."""
    kp = wrench_kalman_params(geom, kalman) if kalman is not None else None
    if name == "non_compensated":
        return NonCompensated(geom, kp, length_deadband)
    if name == "single":
        return Single(geom, kp, length_deadband)
    if name == "double":
        if turn is None:
            raise InputError("estimator 'double' needs a fitted turn compensation (fit_turn_compensation)")
        return Double(geom, turn, kp, length_deadband)
    if name == "dynamic":
        return Dynamic(geom, dynamic, kp, length_deadband)
    raise InputError(f"unknown estimator '{name}' (expected one of: {', '.join(ESTIMATOR_NAMES)})")
