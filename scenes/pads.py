"""Pad layouts of seed 000 (§5, Fig 14): geometry, materials and the points each palpation test pokes.

Frame: the pad's own frame, x/y in its top surface, origin at the pad centre [m]. A pad is a background
material (6 mm Ecoflex 00-20 in Fig 14b-f) with regions that override it (last region wins): inclusions
of another silicone through the full thickness, or a rigid pattern under a thin silicone cover (the E and P
letters), expressed as a silicone layer of reduced thickness bonded to a rigid base. A pad may have a
central hole (Fig 14d), whose wall the tip presses sideways.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from scenes.materials import PAD_THICKNESS, contact_stiffness, get_material
from teleop.core.errors import InputError

# Footprint quadrature of a flat tip (unit disc): 3 equal-area rings x 8 angles, equal weights.
_RING_R = np.sqrt((np.arange(3) + 0.5) / 3.0)
_ANG = np.arange(8) * np.pi / 4 + np.pi / 8
@functools.lru_cache(maxsize=256)
def _layer_k(material: str, thickness: float, tip_radius: float) -> float:
    return contact_stiffness(get_material(material), thickness, tip_radius)


def _pt(v) -> tuple:
    return (float(v[0]), float(v[1]))


FOOTPRINT = np.array([[r * np.cos(a), r * np.sin(a)] for r in _RING_R for a in _ANG])  # (24, 2)


@dataclass(frozen=True)
class Region:
    """A patch of a pad: `shape` "disc" (centre, radius) or "rect" (centre, half-size (hx, hy)) [m].

    Attributes:
        material: catalogue key of the silicone (or "pla") under the tip in this patch.
        thickness: silicone layer thickness above a rigid base here [m] (6 mm through-inclusions; a rigid
            letter under a cover leaves only the cover).
        label: name used in results ("black", "E", ...).
    """

    material: str
    shape: str
    centre: tuple
    size: tuple
    thickness: float = PAD_THICKNESS
    label: str = ""

    def contains(self, xy: np.ndarray) -> np.ndarray:
        """(n,) bool: which points (n, 2) [m] lie in the region."""
        d = np.asarray(xy, dtype=float) - np.asarray(self.centre)
        if self.shape == "disc":
            return np.hypot(d[:, 0], d[:, 1]) <= self.size[0]
        return (np.abs(d[:, 0]) <= self.size[0]) & (np.abs(d[:, 1]) <= self.size[1])


@dataclass(frozen=True)
class Pad:
    """A silicone pad.

    Attributes:
        name: pad name ("stiffness3", "z60", "hole27", "letter_E", "letter_P", "blind4").
        outline: "disc" (size = diameter) or "square" (size = side) [m].
        size: outer size [m].
        background: material key of the bulk.
        regions: patches overriding the background (later ones win).
        hole_radius: radius of a central through hole [m] (0: none).
        thickness: pad thickness [m].
        points: named poke points {label: (x, y)} [m] in the pad frame.
    """

    name: str
    outline: str
    size: float
    background: str
    regions: tuple = ()
    hole_radius: float = 0.0
    thickness: float = PAD_THICKNESS
    points: dict = field(default_factory=dict)

    def __post_init__(self):
        for m in [self.background] + [r.material for r in self.regions]:
            get_material(m)
        if self.outline not in ("disc", "square") or self.size <= 0:
            raise InputError(f"pad {self.name}: outline must be disc or square with size > 0")

    @property
    def half_extent(self) -> float:
        return self.size / 2

    def layer_at(self, xy) -> tuple[list[str], np.ndarray]:
        """Material keys and layer thicknesses [m] at points (n, 2): (list of n keys, (n,) thickness)."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        mats = [self.background] * len(xy)
        h = np.full(len(xy), self.thickness)
        for reg in self.regions:
            inside = reg.contains(xy)
            for i in np.flatnonzero(inside):
                mats[i] = reg.material
                h[i] = reg.thickness
        return mats, h

    def stiffness_at(self, xy, tip_radius: float) -> float:
        """Target contact stiffness [N/m] of a flat tip centred at xy (2,) [m]: the tip footprint's springs
        in parallel, i.e. the area-average of the local k over the disc (exact inside one region)."""
        pts = np.asarray(xy, dtype=float)[None, :] + tip_radius * FOOTPRINT
        mats, h = self.layer_at(pts)
        return float(np.mean([_layer_k(m, float(hh), tip_radius) for m, hh in zip(mats, h)]))

    def wall_stiffness(self, tip_radius: float) -> float:
        """Target lateral stiffness [N/m] of the hole wall: the flat-punch law on a layer as thick as the
        wall (outer radius - hole radius)."""
        if self.hole_radius <= 0:
            raise InputError(f"pad {self.name} has no hole")
        return contact_stiffness(get_material(self.background), self.size / 2 - self.hole_radius, tip_radius)

    def probe_points(self, tip_radius: float = 0.0015) -> dict:
        """{label: (x, y)} one point per distinct region plus one in the background whose whole tip
        footprint lies in that region (the calibration test indents each)."""
        out = {}
        for reg in self.regions:
            key = reg.label or reg.material
            if key not in out:
                out[key] = tuple(reg.centre)
        if self.hole_radius <= 0:
            g = np.linspace(-0.8, 0.8, 17) * self.half_extent
            for x in g:
                for y in g:
                    pts = np.array([x, y]) + tip_radius * 1.01 * np.vstack([FOOTPRINT, [[0.0, 0.0]]])
                    if self.outline == "disc" and np.hypot(x, y) > 0.8 * self.half_extent:
                        continue
                    if not any(r.contains(pts).any() for r in self.regions):
                        out["background"] = (float(x), float(y))
                        return out
        return out


def three_region_pad() -> Pad:
    """Fig 14b / Table 1: a 27 mm Ecoflex 00-20 disc with three 7 mm inclusions on a 14 mm circle:
    black Ecoflex 00-10, red Dragon Skin 30, yellow Ecoflex 00-30 (the order of Table 1's columns)."""
    r, rad = 0.007, 0.0035
    specs = [("black", "ecoflex_00_10", 90.0), ("red", "dragon_skin_30", 210.0), ("yellow", "ecoflex_00_30", 330.0)]
    regions, points = [], {}
    for label, mat, ang in specs:
        c = (r * np.cos(np.deg2rad(ang)), r * np.sin(np.deg2rad(ang)))
        regions.append(Region(mat, "disc", _pt(c), (rad,), label=label))
        points[label] = _pt(c)
    return Pad("stiffness3", "disc", 0.027, "ecoflex_00_20", tuple(regions), points=points)


def z_test_pad() -> Pad:
    """Fig 14c / Fig 16a: 60 mm Ecoflex 00-20 disc; 25 poke points: 1 origin, 2-9 on the 8 mm circle,
    10-17 on the 16 mm circle, 18-25 on the 24 mm circle (8 points each, 45 deg apart)."""
    pts = {"1": (0.0, 0.0)}
    k = 2
    for dia in (0.008, 0.016, 0.024):
        for j in range(8):
            a = j * np.pi / 4
            pts[str(k)] = _pt((dia / 2 * np.cos(a), dia / 2 * np.sin(a)))
            k += 1
    return Pad("z60", "disc", 0.060, "ecoflex_00_20", (), points=pts)


def hole_pad() -> Pad:
    """Fig 14d / Fig 16b,c: 27 mm Ecoflex 00-20 disc with an 8 mm central hole; the tip pokes its wall
    along +x, -x, +y, -y."""
    r = 0.004
    pts = {"+x": (r, 0.0), "-x": (-r, 0.0), "+y": (0.0, r), "-y": (0.0, -r)}
    return Pad("hole27", "disc", 0.027, "ecoflex_00_20", (), hole_radius=r, points=pts)


# Letter scan grid (Fig 17): 6 columns x 7 rows over the 30 x 30 mm pad; letters drawn on that grid.
SCAN_COLS, SCAN_ROWS = 6, 7
# [m] Ecoflex 00-20 above the rigid letter. Seed 000 gives neither the letter's height nor the cover ("the rigid
# letter pattern is covered with silicone", poked 5 mm deep); its measured forces span 0-4 N (Table 2). With
# the robot's 1e4 N/m in series (scenes.sim_robot), a 1.75 mm cover loads a rigid cell with 4.0 N at the
# seed's 5 mm poke (flat punch on the bonded layer, scenes.materials), the top of that range; a 1 mm cover
# would need 8.9 N, more than the cables can hold off the axis.
LETTER_COVER = 0.00175
_LETTER_CELLS = {
    # (col, row) cells of each letter, row 0 at the bottom (-y), col 0 at -x
    "E": [(1, r) for r in range(7)] + [(c, r) for r in (0, 3, 6) for c in (2, 3, 4)],
    "P": [(1, r) for r in range(7)] + [(c, r) for r in (3, 6) for c in (2, 3)] + [(4, r) for r in (3, 4, 5, 6)],
}


def scan_grid(side: float = 0.030) -> np.ndarray:
    """(7, 6, 2) poke points [m] of the 6 x 7 scan, [row, col] with row 0 at -y."""
    cw, ch = side / SCAN_COLS, side / SCAN_ROWS
    xs = -side / 2 + cw * (np.arange(SCAN_COLS) + 0.5)
    ys = -side / 2 + ch * (np.arange(SCAN_ROWS) + 0.5)
    X, Y = np.meshgrid(xs, ys)
    return np.stack([X, Y], axis=-1)


def letter_mask(letter: str) -> np.ndarray:
    """(7, 6) bool: True where the scan cell lies on the rigid letter."""
    if letter not in _LETTER_CELLS:
        raise InputError(f"unknown letter '{letter}' (expected one of: {', '.join(_LETTER_CELLS)})")
    m = np.zeros((SCAN_ROWS, SCAN_COLS), dtype=bool)
    for c, r in _LETTER_CELLS[letter]:
        m[r, c] = True
    return m


def letter_pad(letter: str, side: float = 0.030) -> Pad:
    """Fig 14e,f: a 30 x 30 mm Ecoflex 00-20 pad over a rigid PLA letter; the letter's strokes are the
    scan-grid cells of `letter_mask`, each a rect region with LETTER_COVER of silicone above rigid."""
    mask = letter_mask(letter)
    cw, ch = side / SCAN_COLS, side / SCAN_ROWS
    grid = scan_grid(side)
    regions = tuple(Region("ecoflex_00_20", "rect", _pt(grid[r, c]), (cw / 2, ch / 2), LETTER_COVER, label=letter)
                    for r, c in zip(*np.nonzero(mask)))
    pts = {f"r{r}c{c}": _pt(grid[r, c]) for r in range(SCAN_ROWS) for c in range(SCAN_COLS)}
    return Pad(f"letter_{letter}", "square", side, "ecoflex_00_20", regions, points=pts)


BLIND_MATERIALS = ("pla", "dragon_skin_30", "ecoflex_00_50", "ecoflex_00_20")  # stiffest first (seed §5.2)
BLIND_LABELS = {"pla": "rigid", "dragon_skin_30": "Dragon Skin 30", "ecoflex_00_50": "Ecoflex 00-50",
                "ecoflex_00_20": "Ecoflex 00-20"}


def blind_test_order(seed: int) -> tuple:
    """A seeded random arrangement of the four blind-test materials over the four areas (Fig 14g)."""
    rng = np.random.default_rng(seed)
    return tuple(BLIND_MATERIALS[i] for i in rng.permutation(len(BLIND_MATERIALS)))


def blind_area_centres(diameter: float = 0.060) -> np.ndarray:
    """(4, 2) centres [m] of the blind-test areas 0..3 (quadrants +x+y, -x+y, -x-y, +x-y)."""
    r = diameter / 4 * np.sqrt(2) * 0.75
    ang = np.deg2rad([45.0, 135.0, 225.0, 315.0])
    return np.column_stack([r * np.cos(ang), r * np.sin(ang)])


def blind_test_pad(order=BLIND_MATERIALS, diameter: float = 0.060) -> Pad:
    """Fig 14g: a 60 mm pad of four quadrant areas; `order[i]` is the material of area i (see
    `blind_area_centres`). Areas are 9 mm discs around the centres inside an Ecoflex 00-20 disc, so each
    area is well separated from its neighbours."""
    order = tuple(order)
    if sorted(order) != sorted(BLIND_MATERIALS):
        raise InputError(f"blind-test order must be a permutation of {list(BLIND_MATERIALS)}, got {list(order)}")
    centres = blind_area_centres(diameter)
    regions = tuple(Region(m, "disc", _pt(c), (0.009,), label=f"area{i}") for i, (m, c) in
                    enumerate(zip(order, centres)))
    pts = {f"area{i}": _pt(c) for i, c in enumerate(centres)}
    return Pad("blind4", "disc", diameter, "ecoflex_00_20", regions, points=pts)


def all_pads() -> list[Pad]:
    """Every pad of the seed's tests (the scene catalogue the calibration test sweeps)."""
    return [three_region_pad(), z_test_pad(), hole_pad(), letter_pad("E"), letter_pad("P"), blind_test_pad()]
