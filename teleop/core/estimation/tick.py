"""The compute of one loop tick: pose -> cable lengths -> wrench -> stylus force.

    tc = TickComputer(geom, "dynamic", renderer=Renderer(RenderParams.for_device(spec)))
    lengths, wrench, force = tc.compute(pose, tensions, dt, velocity)

pose (6,) [x, y, z, alpha, beta, gamma] (m, rad, Z-Y-X Euler) of the end effector target; tensions (6,)
calibrated FSR tensions [N]; dt [s]; velocity (3,) stylus velocity [m/s] in the device frame (passivity).
Returns lengths: list of 6 cable lengths [m] (inverse kinematics, eq 4-5: command these to the robot);
wrench: list of 6 filtered wrench values [N, N m] in {B}; force: tuple (3,) stylus force [N] (device frame).

The estimate is one compiled kernel call per tick (teleop.core.kernels.estimate: one kernel per estimator, built
from the shared kernels of the geometry, the friction models, the turn correction and the Kalman update);
this class holds its arrays. The rotated platform anchors R r_i are cached per orientation (the loop holds
the orientation, so R is built once). A non-finite input propagates to a renderer fault (zero force); call
`reset()` after a fault.

`LoopTick` is the whole device-excluded tick the loop runs, its MAP, ESTIMATE and RENDER stages: stylus
position -> mapping -> lengths; FSR counts -> tensions -> this estimate; rendered force. The loop calls the
stages, `teleop bench tick` times `LoopTick.compute`, the three back to back.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.errors import InputError
from teleop.core.estimation.kalman import KalmanNoise, SteadyWrenchKalman, wrench_kalman_params
from teleop.core.estimation.estimators import ESTIMATOR_NAMES, DynamicParams
from teleop.core.estimation.turn import TurnCompensation, turn_arrays
from teleop.core.geometry import Geometry
from teleop.core.kernels import estimate as K
from teleop.core.kernels import sheath as SH
from teleop.core.kernels.jit import bind, f64c
from teleop.core.kernels.safety import all_finite2
from teleop.core.mapping import Follower
from teleop.core.rendering import Renderer

# the compensation step of each estimator (everything else is shared: teleop.core.kernels.estimate)
ESTIMATE_KERNELS = {"non_compensated": K.estimate_non_compensated, "single": K.estimate_capstan,
                    "double": K.estimate_capstan, "dynamic": K.estimate_dynamic}
# the loop's estimator behind teleop.core.kernels.estimate.counts_tensions in one call (ReadingEstimator.update_arrays;
# the others make the two calls): the kernel that holds its fixed arguments together, and the one call
COUNTS_KERNELS = {"dynamic": (K.fixed_dynamic, K.counts_dynamic_fixed)}


class TickComputer:
    """One tick's compute for the loop (see module docstring). `name` is the estimator's name (docs/formats.md):
    non_compensated, single, double (needs `turn`) or dynamic (`dynamic` parameters)."""

    def __init__(self, geom: Geometry, estimator: str = "dynamic", *, turn: TurnCompensation | None = None,
                 dynamic: DynamicParams = DynamicParams(), kalman: KalmanNoise | None = KalmanNoise(),
                 renderer: Renderer | None = None, length_deadband: float = 0.0):
        if estimator not in ESTIMATOR_NAMES:
            raise InputError(f"unknown estimator '{estimator}' (expected one of: {', '.join(ESTIMATOR_NAMES)})")
        if estimator == "double" and turn is None:
            raise InputError("estimator 'double' needs a fitted turn compensation (fit_turn_compensation)")
        self.name = estimator
        self.geom = geom
        self.dyn = dynamic
        self.kernel = ESTIMATE_KERNELS[estimator]
        self.counts_kernel = COUNTS_KERNELS.get(estimator)
        n = len(geom.B)
        self.cab = np.zeros((n, 12))
        self.cab[:, 0:3], self.cab[:, 3:6] = geom.r, geom.B
        self.sheath = SH.Sheath(mu=geom.mu, theta0=geom.theta0, stick_k=dynamic.capstan_k)
        self.c = np.empty(K.N_CONST)
        self.c[:SH.N_CONST] = self.sheath.constants()
        self.c[K.VX:K.VZ + 1] = geom.v
        self.c[[K.DEADBAND, K.B_VISC, K.DAHL_FC, K.DAHL_SIGMA, K.V_SMOOTH]] = (
            length_deadband, dynamic.b, dynamic.dahl_Fc, dynamic.dahl_sigma, dynamic.v_smooth)
        self.turn, self.coefs = turn_arrays(turn if estimator == "double" else None)
        self.kalman = SteadyWrenchKalman(wrench_kalman_params(geom, kalman)) if kalman is not None else None
        self.kf = self.kalman.kf if self.kalman is not None else np.zeros((5, 0))
        self.out = np.zeros((3, max(n, 6)))
        self._pose = np.zeros(6)
        self._t = np.zeros(n)
        self.renderer = renderer if renderer is not None else Renderer()
        self.reset()

    def reset(self) -> None:
        """Forget every state (directions, friction states, turns, Kalman, renderer fault and ramp)."""
        n = self.cab.shape[0]
        self.st = np.zeros((K.N_ROWS, n))
        self.st[:SH.N_STATE] = SH.new_state(n)
        self.st[K.EXT] = math.nan
        self.turn[:, 3], self.turn[:, 4], self.turn[:, 5] = 0.0, math.nan, math.inf  # direction, extreme, tau
        if self.kalman is not None:
            self.kalman.reset()
        self.renderer.reset()

    def compute(self, pose, tensions, dt: float, velocity=(0.0, 0.0, 0.0)):
        """(lengths [6], wrench [6], force (3,)) for one tick; see the module docstring."""
        lengths, w = self.estimate(pose, tensions, dt)
        return lengths, w, self.renderer.render_xyz(w[0], w[1], w[2], dt, *velocity)

    def estimate_into(self, pose: np.ndarray, tensions: np.ndarray, dt: float) -> np.ndarray:
        """The tick without the renderer on float64 arrays: `out` (3, n) rows: lengths [m], wrench [N, N m]
        (first 6), compensated tip-side tensions [N]."""
        self.kernel(pose, tensions, dt, self.cab, self.c, self.st, self.kf, self.turn, self.coefs, self.out)
        return self.out

    def estimate(self, pose, tensions, dt: float):
        """(lengths [6], wrench [6]) as lists: the tick without the renderer (pose, tensions: any sequence)."""
        self._pose[:] = pose
        self._t[:] = tensions
        out = self.estimate_into(self._pose, self._t, float(dt))
        n = self.cab.shape[0]
        return out[0, :n].tolist(), out[1, :6].tolist()


class LoopTick:
    """The device-excluded compute of one loop tick, in three stages: MAP (stylus position -> mapping: motion
    scale, workspace clip, v_max step limit, teleop.core.mapping.Follower -> cable lengths), ESTIMATE (FSR counts
    -> tensions -> estimate with the Kalman filter, ReadingEstimator.update_arrays) and RENDER (wrench ->
    stylus force, Renderer.render_tick).

    teleop.loop.core.Teleop calls `map`, `estimate` and `render` at its MAP, ESTIMATE and RENDER stages (the
    robot I/O sits between them); `compute` runs the same three back to back on this object's mapping state,
    so `teleop bench tick`, which times `compute`, times the code the loop runs.

        lt = LoopTick(geom, MappingParams(), ReadingEstimator(geom, "dynamic"), Renderer(rp), cmd_dt=1e-3)
        lt.engage(p_stylus)                                  # anchors (the loop's ENABLED entry)
        L, t, w, F = lt.compute(p_stylus, v_stylus, counts, dt)

    Inputs are what the devices give: stylus position (3,) [m] and velocity (3,) [m/s] in the device frame,
    raw FSR counts (6,), as numpy arrays. Outputs (arrays, as the loop holds them): commanded lengths L (6,)
    [m], tensions (6,) [N] and wrench (6,) [N, N m] in {B}, force (3,) [N] in the device frame.
    """

    def __init__(self, geom: Geometry, mapping, estimator, renderer: Renderer | None = None, cmd_dt: float = 1e-3):
        self.follower = Follower(mapping, geom, cmd_dt)
        self.home = [float(v) for v in mapping.home]
        self.estimator = estimator
        self.renderer = renderer if renderer is not None else Renderer()
        self._finite = None  # kernel safety.all_finite2 bound to the estimator's buffers (estimate)
        self._home_mapping()  # the estimator and renderer keep their state (the loop may hand in its own)

    def __getstate__(self) -> dict:
        """Pickled without the bound kernel (compiled code does not pickle; bound again at the next call)."""
        return {**self.__dict__, "_finite": None}

    def _home_mapping(self) -> None:
        # compute()'s own mapping state; the loop keeps its own (Teleop.pose, L_last, anchors) and calls map()
        self._anchor = np.zeros(6)  # stylus anchor (3,), robot anchor (3,) [m]
        self._anchor[3:] = self.home[:3]
        self._pos = np.array(self.home[:3], dtype=float)
        self._L = np.zeros(len(self.estimator.geom.B))
        self._pose = np.array(self.home, dtype=float)
        self._engaged_L = False

    pos = property(lambda self: self._pos.tolist(), doc="compute()'s robot target [m] (3 floats)")
    L_last = property(lambda self: self._L.tolist() if self._engaged_L else None,
                      doc="compute()'s last commanded lengths [m] (None before the first engagement)")

    def reset(self) -> None:
        """Back at home, not engaged; estimator and renderer reset."""
        self._home_mapping()
        self.estimator.reset()
        self.renderer.reset()

    def engage(self, p_stylus, L_robot=None) -> None:
        """Anchor the incremental mapping at the stylus position (3,) [m] and the current robot target; at the
        first engagement the lengths start from L_robot (6,) [m] (where the robot is), default the target's."""
        self._anchor[:3] = p_stylus
        self._anchor[3:] = self._pos
        if not self._engaged_L:
            self._L[:] = self.follower.lengths(*self._pos) if L_robot is None else L_robot
            self._engaged_L = True

    def map(self, p_stylus, anchor: np.ndarray, pos: np.ndarray, L_prev) -> np.ndarray:
        """MAP: the commanded lengths (6,) [m] (a new array) for the stylus position p_stylus (3,) [m], from the
        anchors (6,) (stylus, robot) [m], the previous target pos (3,) [m] (updated in place: float64, contiguous)
        and lengths L_prev (6,) [m] (Follower.step_into)."""
        L = f64c(L_prev).copy()  # a new array (the loop's float64 lengths copied once)
        self.follower.step_into(f64c(p_stylus), anchor, pos, L)
        return L

    def estimate(self, counts, pose: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """ESTIMATE: (tensions (n,) [N], wrench (6,) [N, N m] in {B}), copies, from raw FSR counts (n,) at the
        commanded pose (6,) float64 (ReadingEstimator.update_arrays); ValueError if either is not finite."""
        t, w = self.estimator.update_arrays(counts, pose, dt)
        call = self._finite
        if call is None:  # bound at the first estimate (jit.bind): ReadingEstimator's (n,) and (6,) float64 buffers
            call = self._finite = bind(all_finite2, t, w) if type(t) is np.ndarray and type(w) is np.ndarray \
                else all_finite2
        if not call(t, w):
            raise ValueError("estimated tensions/wrench not finite")
        return t.copy(), w.copy()

    def render(self, fx: float, fy: float, fz: float, dt: float, vx: float, vy: float, vz: float) -> tuple:
        """RENDER: Renderer.render_tick of the force part of the wrench [N] and the stylus velocity [m/s]:
        (force (3,) [N] device frame, mapped (3 floats), ramp, tripped)."""
        return self.renderer.render_tick(fx, fy, fz, dt, vx, vy, vz)

    def compute(self, p_stylus, v_stylus, counts, dt: float):
        """One full tick (see the class docstring): map, estimate, render on this object's mapping state;
        (L (6,), tensions (6,), wrench (6,), force (3,)); p_stylus, v_stylus (3,) and counts (6,) arrays."""
        self._L = L = self.map(p_stylus, self._anchor, self._pos, self._L)
        pose = self._pose
        pose[:3] = self._pos
        t, w = self.estimate(counts, pose, dt)
        fx, fy, fz = w[:3].tolist()
        vx, vy, vz = v_stylus.tolist()
        return L, t, w, self.render(fx, fy, fz, dt, vx, vy, vz)[0]
