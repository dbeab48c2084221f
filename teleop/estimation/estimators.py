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
  the capstan with stick transitions is inverted by its play form (physics.capstan.motor2tip_transitions:
  the tip tension stays flat while the sensor tension crosses the band [t e^-mu Theta, t e^mu Theta]), so
  nothing jumps at a reversal and the estimate does not depend on how fast the cable moves.
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
from teleop.physics.capstan import capstan_band, motor2tip
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
    """

    b: float = 0.0
    dahl_sigma: float = 1e4
    dahl_Fc: float = 0.0
    v_smooth: float = 0.0


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
        self.t_tip = None

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
        lo, hi = capstan_band(t_c, self.geom.mu, theta)
        prev = t_c if self.t_tip is None else self.t_tip
        self.t_tip = np.minimum(np.maximum(prev, lo), hi)
        return self.t_tip


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
