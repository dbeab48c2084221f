"""Stylus pose -> robot target: motion scale, clutch re-anchoring, workspace limits, cable-length limits.

Incremental (relative) mapping as in dVRK teleoperation: when teleoperation engages (or the clutch is
released) the current stylus position and robot target are stored as anchors, and afterwards

    p_target = p_robot_anchor + s R_reg (p_stylus - p_stylus_anchor)          (s: motion scale, R_reg: (3, 3))

clamped to the robot's workspace box. Cable lengths follow from inverse kinematics at a fixed orientation and
are then limited so that no cable leaves [l_min, l_max] and no cable moves more than v_max dt in one tick
(the "sudden jump" hazard). Pure numpy; the loop holds the anchors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from teleop.errors import InputError
from teleop.geometry import Geometry, _frozen
from teleop.kinematics import rotation_zyx


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


def stylus2target(p_stylus, p_stylus_anchor, p_robot_anchor, params: MappingParams) -> np.ndarray:
    """(3,) robot target position [m]: anchor + s R_reg (p - p_anchor), clamped to the workspace box."""
    d = np.asarray(p_stylus, dtype=float) - p_stylus_anchor
    p = p_robot_anchor + params.motion_scale * (params.R_reg @ d)
    return np.minimum(np.maximum(p, params.workspace_min), params.workspace_max)


def platform_offsets(geom: Geometry, orientation) -> np.ndarray:
    """(6, 3) R r_i - B_i for a fixed orientation [alpha, beta, gamma] (rad): lengths = |p + offsets|."""
    a, b, g = np.asarray(orientation, dtype=float)
    return geom.r @ rotation_zyx(a, b, g).T - geom.B


def position2lengths(p, offsets: np.ndarray) -> np.ndarray:
    """(6,) cable lengths [m] of the end effector at position p (3,) with fixed-orientation `offsets` (6, 3).

    Same as kinematics.pose2lengths for that orientation (eq 4-5), without rebuilding R every tick.
    """
    v = offsets + p
    return np.sqrt(np.einsum("ij,ij->i", v, v))


def limit_lengths(L_target, L_prev, geom: Geometry, dt: float) -> np.ndarray:
    """(6,) lengths inside [l_min, l_max] that move at most v_max dt from L_prev [m].

    The whole step is scaled by one factor so the cables keep moving together (the direction of motion is
    kept); then every length is clipped to its limits.
    """
    L = np.minimum(np.maximum(np.asarray(L_target, dtype=float), geom.l_min), geom.l_max)
    if L_prev is None:
        return L
    dL = L - L_prev
    step = float(np.max(np.abs(dL)))
    dmax = geom.v_max * dt
    if step > dmax:
        dL = dL * (dmax / step)
    return np.minimum(np.maximum(L_prev + dL, geom.l_min), geom.l_max)


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
    """The per-tick mapping on plain floats (the loop's hot path; at six cables numpy's per-call overhead
    would dominate). Same numbers as `stylus2target`, `position2lengths` and `limit_lengths`:

        pos, L = Follower(params, geom, dt).step(p_stylus, anchor_stylus, anchor_robot, pos_prev, L_prev)

    The target anchor_robot + s R_reg (p_stylus - anchor_stylus) is clamped to the workspace box; if some cable
    would move more than v_max dt, the target moves along the straight line from pos_prev only as far as
    that allows; lengths are clipped to [l_min, l_max] and, if the line step left a (second-order) residue
    above v_max dt, hard-limited by `limit_lengths`. Positions [m] are 3 floats, lengths [m] 6 floats; the
    orientation is held at the home orientation. dt: command period [s].
    """

    def __init__(self, params: MappingParams, geom: Geometry, dt: float):
        sR = (params.motion_scale * params.R_reg).tolist()
        self.sR = tuple(v for row in sR for v in row)
        self.lo = tuple(params.workspace_min.tolist())
        self.hi = tuple(params.workspace_max.tolist())
        self.offsets = tuple(tuple(row) for row in platform_offsets(geom, params.home[3:]).tolist())
        self.dmax = float(geom.v_max * dt)
        self.dmax_hard = float(geom.v_max * (self.dmax / geom.v_max))  # limit_lengths(..., dt=dmax / v_max)
        self.l_min, self.l_max = float(geom.l_min), float(geom.l_max)

    def lengths(self, x: float, y: float, z: float) -> list:
        """Cable lengths [m] at position (x, y, z) [m] (`position2lengths` with the held orientation)."""
        sqrt = math.sqrt
        return [sqrt((ox + x) ** 2 + (oy + y) ** 2 + (oz + z) ** 2) for ox, oy, oz in self.offsets]

    def step(self, p_stylus, anchor_stylus, anchor_robot, pos_prev, L_prev) -> tuple[list, list]:
        """(target position [x, y, z] [m], commanded lengths [6] [m]) for this tick (see the class docstring)."""
        s00, s01, s02, s10, s11, s12, s20, s21, s22 = self.sR
        dx = p_stylus[0] - anchor_stylus[0]
        dy = p_stylus[1] - anchor_stylus[1]
        dz = p_stylus[2] - anchor_stylus[2]
        lo, hi = self.lo, self.hi
        x = anchor_robot[0] + (s00 * dx + s01 * dy + s02 * dz)
        y = anchor_robot[1] + (s10 * dx + s11 * dy + s12 * dz)
        z = anchor_robot[2] + (s20 * dx + s21 * dy + s22 * dz)
        x = hi[0] if x > hi[0] else (lo[0] if x < lo[0] else x)  # np.minimum(np.maximum(p, lo), hi)
        y = hi[1] if y > hi[1] else (lo[1] if y < lo[1] else y)
        z = hi[2] if z > hi[2] else (lo[2] if z < lo[2] else z)
        dmax, l_min, l_max, sqrt = self.dmax, self.l_min, self.l_max, math.sqrt
        # one pass: lengths (position2lengths), their largest step, the clipped lengths and their largest step
        L, step, step_c = [], 0.0, 0.0
        for (ox, oy, oz), lp in zip(self.offsets, L_prev):
            vx, vy, vz = ox + x, oy + y, oz + z
            v = sqrt(vx * vx + vy * vy + vz * vz)
            d = v - lp if v > lp else lp - v
            if d > step:
                step = d
            v = l_max if v > l_max else (l_min if v < l_min else v)
            d = v - lp if v > lp else lp - v
            if d > step_c:
                step_c = d
            L.append(v)
        if step > dmax:  # move along the straight line as far as the cable speed allows this tick
            f = dmax / step
            x0, y0, z0 = pos_prev[0], pos_prev[1], pos_prev[2]
            x, y, z = x0 + (x - x0) * f, y0 + (y - y0) * f, z0 + (z - z0) * f
            L = [l_max if v > l_max else (l_min if v < l_min else v) for v in self.lengths(x, y, z)]
            step_c = max([abs(a - b) for a, b in zip(L, L_prev)])
        if step_c > dmax:  # second-order residue of the line step: limit_lengths' hard limit
            f = self.dmax_hard / step_c if step_c > self.dmax_hard else 1.0
            L = [b + (a - b) * f for a, b in zip(L, L_prev)]
            L = [l_max if v > l_max else (l_min if v < l_min else v) for v in L]
        return [x, y, z], L
