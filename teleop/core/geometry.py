"""CDPR geometry (seed 000 §4, Fig 12): base anchors B_i on the scaffold ring, platform anchors r_i.

The default models the seed's endoscopic robot (a Cyclops-type CDPR): six sheaths end on one circle of the
scaffold (frame {B}, z along the scaffold axis, the poking direction). The end effector is a shaft along its
own z axis; three cables attach at its rear point (behind the ring plane, so they pull it forward, +z) and
three at its front point (ahead of the plane, pulling it back, -z). Cables can therefore both push and pull
the end effector along z. Because every cable line meets the shaft axis, the cables exert no moment about
that axis: the robot has five controlled degrees of freedom (position and the shaft's pointing direction),
the structure matrix A has rank 5 and its one-dimensional null space is what holds the cables in
pretension. The roll about the shaft belongs to the instrument, not to the cables; poses carry it as 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from teleop.core.config import check_keys, get_number, get_vectors, load_toml
from teleop.core.errors import InputError
from teleop.core.kernels.sheath import Sheath

N_CABLES = 6


def _ring(radius: float, angles_rad: np.ndarray, z: float) -> np.ndarray:
    return np.column_stack([radius * np.cos(angles_rad), radius * np.sin(angles_rad), np.full(len(angles_rad), z)])


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Geometry:
    """Geometry and transmission constants of the CDPR (SI units).

    Attributes:
        B: (6, 3) base (scaffold) anchors in {B} [m]; all on one circle in the plane z = 0.
        r: (6, 3) platform anchors in {P} [m].
        theta0: scaffold bend of every cable, segment BC of seed Fig 8a [rad] (default the seed robot's sheath,
            teleop.core.kernels.sheath.Sheath, which gathers it with mu, the stick stiffness and the pretension).
        mu: sheath friction coefficient of the capstan law T_load = T_hold exp(mu (theta + theta0)) [-] (default
            the seed robot's sheath).
        t_min, t_max: cable tension bounds [N].
        tip: (3,) tool tip in {P} [m] (the point that touches tissue).
        l_min, l_max: admissible cable lengths [m].
        v_max: maximum cable speed [m/s] (limits the per-tick length change).
    """

    B: np.ndarray
    r: np.ndarray
    theta0: float = Sheath.theta0
    mu: float = Sheath.mu
    t_min: float = 0.2
    t_max: float = 5.5
    tip: np.ndarray = field(default_factory=lambda: _frozen([0.0, 0.0, 0.025]))
    l_min: float = 0.005
    l_max: float = 0.060
    v_max: float = 0.020

    def __post_init__(self):
        object.__setattr__(self, "B", _frozen(self.B))
        object.__setattr__(self, "r", _frozen(self.r))
        object.__setattr__(self, "tip", _frozen(self.tip))
        if self.B.shape != (N_CABLES, 3) or self.r.shape != (N_CABLES, 3):
            raise InputError(f"geometry: B and r must be {N_CABLES}x3 arrays, got {self.B.shape} and {self.r.shape}")
        if not (np.isfinite(self.B).all() and np.isfinite(self.r).all() and np.isfinite(self.tip).all()):
            raise InputError("geometry: anchors must be finite numbers")
        if not 0 <= self.t_min < self.t_max:
            raise InputError(f"geometry: need 0 <= t_min < t_max, got t_min={self.t_min}, t_max={self.t_max}")
        if not 0 < self.l_min < self.l_max:
            raise InputError(f"geometry: need 0 < l_min < l_max, got l_min={self.l_min}, l_max={self.l_max}")
        if self.mu < 0 or self.theta0 < 0 or self.v_max <= 0:
            raise InputError("geometry: mu and theta0 must be >= 0 and v_max > 0")
        # base anchors on one circle in a plane: the plane normal v of eq 6
        centred = self.B - self.B.mean(axis=0)
        radii = np.linalg.norm(centred, axis=1)
        if np.ptp(radii) > 1e-9 + 1e-6 * radii.max() or np.linalg.svd(centred)[1][-1] > 1e-9:
            raise InputError("geometry: base anchors B must lie on one circle in one plane")

    @cached_property
    def v(self) -> np.ndarray:
        """(3,) unit normal of the base-anchor plane (eq 6), oriented towards +z of {B} (computed once)."""
        centred = self.B - self.B.mean(axis=0)
        n = np.linalg.svd(centred)[2][-1]
        return _frozen(n if n[2] >= 0 else -n)

    @property
    def base_radius(self) -> float:
        """Radius of the base-anchor circle [m]."""
        return float(np.linalg.norm(self.B - self.B.mean(axis=0), axis=1).mean())

    def replace(self, **changes) -> "Geometry":
        """A copy with some fields changed (the dataclass is frozen)."""
        return replace(self, **changes)


def geometry_dict(g: Geometry) -> dict:
    """The geometry's fields in SI as JSON values (what a session's metadata records; Geometry(**d) with the
    lists as arrays rebuilds it)."""
    return {"B": g.B.tolist(), "r": g.r.tolist(), "theta0": g.theta0, "mu": g.mu, "t_min": g.t_min,
            "t_max": g.t_max, "tip": g.tip.tolist(), "l_min": g.l_min, "l_max": g.l_max, "v_max": g.v_max}


def default_geometry() -> Geometry:
    """The seed robot: scaffold ring radius 20 mm, shaft anchors 15 mm behind and ahead of the centre.

    Rear anchors (cables 1, 3, 5) sit at z = -15 mm of {P}, front anchors (2, 4, 6) at z = +15 mm; base
    anchors alternate rear/front every 60 deg. mu = 0.056 is fitted to seed 000 Fig 9 (distal FSR swing
    2.25/1.71 N at theta = 0 and 3.32/2.39 N at theta = 30 deg, both give exp(2 mu (theta + theta0))).
    Tension bounds follow the FSR's 5-600 g range (seed 000 §2.1).
    """
    angles = np.deg2rad(np.arange(N_CABLES) * 60.0)
    B = _ring(0.020, angles, 0.0)
    h = 0.015
    r = np.array([[0.0, 0.0, -h if i % 2 == 0 else h] for i in range(N_CABLES)])
    return Geometry(B=B, r=r)


_KEYS = {"base_anchors_mm", "platform_anchors_mm", "theta0_deg", "mu", "t_min_N", "t_max_N", "tip_mm",
         "l_min_mm", "l_max_mm", "v_max_mm_s"}


def load_geometry(path: str | Path) -> Geometry:
    """Load a geometry TOML (table `[geometry]`, lengths in mm, angles in deg); unknown keys raise.

    Example::

        [geometry]
        base_anchors_mm = [[20, 0, 0], ...]      # 6 x 3
        platform_anchors_mm = [[0, 0, -15], ...] # 6 x 3
        theta0_deg = 140
        mu = 0.056
    """
    path = Path(path)
    doc = load_toml(path)
    check_keys(doc, {"geometry"}, f"{path}")
    if "geometry" not in doc or not isinstance(doc["geometry"], dict):
        raise InputError(f"{path}: missing table [geometry]")
    g = doc["geometry"]
    where = f"{path} [geometry]"
    check_keys(g, _KEYS, where)
    d = default_geometry()
    mm = 1e-3
    B = np.array(get_vectors(g, "base_anchors_mm", where, N_CABLES)) * mm
    r = np.array(get_vectors(g, "platform_anchors_mm", where, N_CABLES)) * mm
    tip = np.array(get_vectors({"tip": [g["tip_mm"]]}, "tip", f"{where} tip_mm", 1)[0]) * mm if "tip_mm" in g \
        else d.tip
    values = dict(  # each error names `where` (the path and table) itself
        theta0=np.deg2rad(get_number(g, "theta0_deg", where, np.rad2deg(d.theta0), nonnegative=True)),
        mu=get_number(g, "mu", where, d.mu, nonnegative=True),
        t_min=get_number(g, "t_min_N", where, d.t_min, nonnegative=True),
        t_max=get_number(g, "t_max_N", where, d.t_max, positive=True),
        l_min=get_number(g, "l_min_mm", where, d.l_min / mm, positive=True) * mm,
        l_max=get_number(g, "l_max_mm", where, d.l_max / mm, positive=True) * mm,
        v_max=get_number(g, "v_max_mm_s", where, d.v_max / mm, positive=True) * mm,
    )
    try:
        return Geometry(B=B, r=r, tip=tip, **values)
    except InputError as exc:  # the geometry's own checks do not know the file
        raise InputError(f"{path}: {exc}") from None
