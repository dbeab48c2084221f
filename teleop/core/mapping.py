"""Stylus pose -> robot target: motion scale, clutch re-anchoring, workspace limits, cable-length limits.

Incremental (relative) mapping as in dVRK teleoperation: when teleoperation engages (or the clutch is
released) the current stylus position and robot target are stored as anchors, and afterwards

    p_target = p_robot_anchor + s R_reg (p_stylus - p_stylus_anchor)          (s: motion scale, R_reg: (3, 3))

clamped to the robot's workspace box. Cable lengths follow from inverse kinematics at a fixed orientation and
are then limited so that no cable leaves [l_min, l_max] and no cable moves more than v_max dt in one tick
(the "sudden jump" hazard). The formulas are the kernels of teleop.core.kernels.mapping; this module is their
numpy face. The loop holds the anchors.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from teleop.core.errors import InputError
from teleop.core.geometry import Geometry, _frozen
from teleop.core.kernels import geometry as KG
from teleop.core.kernels import mapping as KM
from teleop.core.kernels.jit import bind


@dataclass(frozen=True)
class MappingParams:
    """Master -> slave mapping (SI).

    Attributes:
        motion_scale: s, robot displacement per stylus displacement [-].
        R_reg: (3, 3) rotation from the stylus frame to the robot frame {B}. Default: 180 deg about x, so
            pressing the stylus down (-z of the stylus) pokes the robot forward (+z of {B}, towards tissue),
            and the tissue's reaction (-z in {B}) pushes the hand up (+z of the stylus).
        workspace_min, workspace_max: (3,) robot target box in {B} [m] (default: +-5 mm about the home pose;
            the tensionable set of the default geometry reaches further along +z, see POKE_WORKSPACE_MAX).
        home: (6,) robot home pose [x, y, z, alpha, beta, gamma] (m, rad); its orientation is held.
        align_tol: largest stylus tilt from the registered neutral orientation that counts as aligned [rad].
    """

    motion_scale: float = 0.25
    R_reg: np.ndarray = field(default_factory=lambda: _frozen(np.diag([1.0, -1.0, -1.0])))
    workspace_min: np.ndarray = field(default_factory=lambda: _frozen([-0.005, -0.005, -0.005]))
    workspace_max: np.ndarray = field(default_factory=lambda: _frozen([0.005, 0.005, 0.005]))
    home: np.ndarray = field(default_factory=lambda: _frozen(np.zeros(6)))
    align_tol: float = np.deg2rad(20.0)

    def __post_init__(self):
        for name in ("R_reg", "workspace_min", "workspace_max", "home"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        if not (np.isfinite(self.motion_scale) and self.motion_scale > 0):
            raise InputError(f"mapping: motion_scale must be > 0, got {self.motion_scale}")
        if self.R_reg.shape != (3, 3) or not np.allclose(self.R_reg @ self.R_reg.T, np.eye(3), atol=1e-9):
            raise InputError("mapping: R_reg must be a 3x3 rotation matrix")
        if self.workspace_min.shape != (3,) or self.workspace_max.shape != (3,) or \
                not (self.workspace_min < self.workspace_max).all():
            raise InputError("mapping: need workspace_min < workspace_max, 3 numbers each")
        if self.home.shape != (6,) or not np.isfinite(self.home).all():
            raise InputError("mapping: home must be 6 finite numbers")
        if not (self.workspace_min <= self.home[:3]).all() or not (self.home[:3] <= self.workspace_max).all():
            raise InputError("mapping: home position must lie inside the workspace box")
        if not 0 < self.align_tol <= np.pi:
            raise InputError(f"mapping: align_tol must be in (0, pi], got {self.align_tol}")


# x, y within +-5 mm and z up to +12 mm stay inside the tensionable set of the default geometry at the home
# orientation (checked on a grid); the sessions use it so the tool can indent a pad 5 mm ahead by up to 7 mm.
POKE_WORKSPACE_MAX = (0.005, 0.005, 0.012)


def target_constants(params: MappingParams) -> np.ndarray:
    """(15,) the target's constants of kernel mapping.target_position: s R_reg (rows), workspace min, max [m]."""
    return np.array([*(params.motion_scale * params.R_reg).ravel(), *params.workspace_min, *params.workspace_max],
                    dtype=float)


def stylus2target(p_stylus, p_stylus_anchor, p_robot_anchor, params: MappingParams) -> np.ndarray:
    """(3,) robot target position [m]: anchor + s R_reg (p - p_anchor), clamped to the workspace box (kernel
    mapping.target_position)."""
    anchor = np.array([*p_stylus_anchor, *p_robot_anchor], dtype=float)
    return np.array(KM.target_position(np.asarray(p_stylus, dtype=float), anchor, target_constants(params)))


def platform_offsets(geom: Geometry, orientation) -> np.ndarray:
    """(6, 6) per cable (R r_i - B_i, R r_i) [m] for a fixed orientation [alpha, beta, gamma] (rad) (kernel
    geometry.platform_offsets): lengths = |p + offsets[:, :3]|."""
    a, b, g = (float(v) for v in orientation)
    return KG.platform_offsets(a, b, g, geom.r, geom.B, np.empty((len(geom.B), 6)))


def position2lengths(p, offsets: np.ndarray) -> np.ndarray:
    """(6,) cable lengths [m] of the end effector at position p (3,) with fixed-orientation `offsets` (6, 6)
    (`platform_offsets`; kernel geometry.lengths_at).

    Same as kinematics.pose2lengths for that orientation (eq 4-5), without rebuilding R every tick.
    """
    p = np.asarray(p, dtype=float)
    return KG.lengths_at(float(p[0]), float(p[1]), float(p[2]), np.ascontiguousarray(offsets, dtype=float),
                         np.empty(len(offsets)))


def limit_lengths(L_target, L_prev, geom: Geometry, dt: float) -> np.ndarray:
    """(6,) lengths inside [l_min, l_max] that move at most v_max dt from L_prev [m].

    The whole step is scaled by one factor so the cables keep moving together (the direction of motion is
    kept); then every length is clipped to its limits (kernels mapping.clip_lengths, mapping.limit_step).
    """
    L = np.array(L_target, dtype=float)
    if L_prev is None:
        KM.clip_lengths(L, L, geom.l_min, geom.l_max)
        return L
    L_prev = np.asarray(L_prev, dtype=float)
    KM.clip_lengths(L, L_prev, geom.l_min, geom.l_max)
    return KM.limit_step(L_prev, L, geom.v_max * dt, geom.l_min, geom.l_max)


def tilt_angle(orientation, R_reg_neutral=None) -> float:
    """Angle [rad] between the stylus axis (z column of `orientation` (3, 3)) and the neutral axis."""
    R = np.asarray(orientation, dtype=float)
    z = R[:, 2] if R_reg_neutral is None else (np.asarray(R_reg_neutral).T @ R)[:, 2]
    return float(np.arccos(np.clip(z[2] / max(np.linalg.norm(z), 1e-12), -1.0, 1.0)))


def is_aligned(orientation, params: MappingParams) -> bool:
    """True when the stylus points within align_tol of its registered neutral direction (robot held at home
    orientation, so that is the orientation the stylus must match before engaging)."""
    R = np.asarray(orientation, dtype=float)
    if R.shape != (3, 3) or not np.isfinite(R).all():
        return False
    return tilt_angle(R) <= params.align_tol


class Follower:
    """The per-tick mapping, one compiled call (kernel mapping.follow_step; the loop's hot path). Same numbers
    as `stylus2target`, `position2lengths` and `limit_lengths`:

        pos, L = Follower(params, geom, dt).step(p_stylus, anchor_stylus, anchor_robot, pos_prev, L_prev)

    The target anchor_robot + s R_reg (p_stylus - anchor_stylus) is clamped to the workspace box; if some cable
    would move more than v_max dt, the target moves along the straight line from pos_prev only as far as
    that allows; lengths are clipped to [l_min, l_max] and, if the line step left a (second-order) residue
    above v_max dt, hard-limited by `limit_lengths`. Positions [m] are 3 floats, lengths [m] 6 floats; the
    orientation is held at the home orientation. dt: command period [s].
    """

    def __init__(self, params: MappingParams, geom: Geometry, dt: float):
        dmax = float(geom.v_max * dt)
        self.c = np.r_[target_constants(params), dmax, geom.v_max * (dmax / geom.v_max), geom.l_min, geom.l_max]
        self.offsets = platform_offsets(geom, params.home[3:])
        self._step_call = None  # kernel mapping.follow_step bound to its argument types (step_into)
        self.dmax = dmax
        self._p, self._anchor = np.zeros(3), np.zeros(6)
        self._pos, self._L = np.zeros(3), np.zeros(len(geom.B))

    def lengths(self, x: float, y: float, z: float) -> list:
        """Cable lengths [m] at position (x, y, z) [m] (`position2lengths` with the held orientation)."""
        return KG.lengths_at(float(x), float(y), float(z), self.offsets, np.empty(len(self.offsets))).tolist()

    def __getstate__(self) -> dict:
        """Pickled without the bound kernel (compiled code does not pickle; bound again at the next call)."""
        return {**self.__dict__, "_step_call": None}

    def step_into(self, p: np.ndarray, anchor: np.ndarray, pos: np.ndarray, L: np.ndarray) -> None:
        """The step on float64 arrays: p (3,) stylus [m], anchor (6,) stylus and robot anchors [m]; pos (3,)
        and L (n,) hold the previous target and lengths [m] and are updated (kernel mapping.follow_step)."""
        call = self._step_call
        if call is None:  # bound at the first step (jit.bind): float64 arrays, as documented
            call = self._step_call = bind(KM.follow_step, p, anchor, self.c, self.offsets, pos, L)
        call(p, anchor, self.c, self.offsets, pos, L)

    def step(self, p_stylus, anchor_stylus, anchor_robot, pos_prev, L_prev) -> tuple[list, list]:
        """(target position [x, y, z] [m], commanded lengths [6] [m]) for this tick (see the class docstring)."""
        self._p[:] = p_stylus
        self._anchor[:3], self._anchor[3:] = anchor_stylus, anchor_robot
        self._pos[:] = pos_prev
        self._L[:] = L_prev
        self.step_into(self._p, self._anchor, self._pos, self._L)
        return self._pos.tolist(), self._L.tolist()
