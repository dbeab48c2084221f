"""Silicone catalogue for the pad scenes: the modulus each pad material uses [Pa], its source and mode.

Indentation compresses the pad under the tip, so every silicone here carries a *compression-equivalent*
Young's modulus (compression moduli are 2-3x the small-strain tension moduli of the same silicone;
tension would make every pad 2-3x too soft):

- Ecoflex 00-10, 00-30, 00-50: measured uniaxial compression moduli (0 % thinner) from
  `ecoflex_compression_moduli.csv` (abubakardawood/phantom-material-database, CC BY 4.0).
- Dragon Skin 10, 20, 30: no compression data exists; the small-strain slope of their tensile curves
  (`tensile_*.csv`, LucMarechal/Soft-Robotics-Materials-Database, ODbL 1.0), fitted here at load time, is
  scaled by the compression/tension ratio measured on the three Ecoflex grades that have both (mean 2.79).
- Ecoflex 00-20: neither file has it; its modulus is interpolated log-linearly in Shore 00 hardness between
  the measured 00-10 and 00-30 compression moduli. (The Smooth-On datasheet lists the same 100 % modulus,
  8 psi, for 00-10 and 00-20, which would make 00-20 as soft as 00-10; the hardness scale says otherwise.)
- Rigid PLA: 3.5 GPa (typical printed PLA, NatureWorks Ingeo 4043D datasheet 3.6 GPa). Its contact in the
  simulation is capped (see `contact_stiffness`): no pybullet contact at 1 kHz is as stiff as PLA.

Contact stiffness of a flat-ended cylindrical tip of radius a on a layer of thickness h bonded to a rigid
base (the pad on its holder / the Nano17): half-space k0 = 2 a E / (1 - nu^2) (Sneddon), corrected for the
finite layer with the bonded-layer flat-punch factor f(a/h) = 1 + 1.33 (a/h) + 1.33 (a/h)^3 for nu = 0.5
(Shull 2002, Mater. Sci. Eng. R 36, 1-45, from Hayes et al. 1972). A flat punch gives a linear
force-indentation law, the same law as pybullet's contact spring, so the calibrated slope is the whole model.

Data attribution: "Contains data from the Soft-Robotics-Materials-Database (LucMarechal, Univ. Savoie Mont
Blanc, SYMME Lab), ODbL 1.0" and "phantom-material-database (abubakardawood), CC BY 4.0".
"""

from __future__ import annotations

import csv
import functools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from teleop.core.errors import InputError

ATTRIBUTION = ("Material moduli: Soft-Robotics-Materials-Database (LucMarechal, Univ. Savoie Mont Blanc, "
               "SYMME Lab), ODbL 1.0; phantom-material-database (abubakardawood), CC BY 4.0; Smooth-On datasheets.")

PAD_THICKNESS = 0.006        # [m] every pad of seed 000 Fig 14 is 6 mm thick
NU_SILICONE = 0.5            # [-] silicones are nearly incompressible
NU_PLA = 0.36                # [-] PLA
E_PLA = 3.5e9                # [Pa] NatureWorks Ingeo 4043D datasheet (3.6 GPa), printed parts a little lower
TIP_RADIUS = 0.0015          # [m] flat tip of the end effector (3 mm shaft end; seed 000 Fig 3 scale)
RIGID_CONTACT_STIFFNESS = 1.0e5  # [N/m] cap for rigid contact: 15x Dragon Skin 30, far stiffer than the robot
SMALL_STRAIN = (0.05, 0.25)  # [-] engineering-strain window of the tensile small-strain fit (past the toe)

# Smooth-On datasheet 100 % moduli [psi], kept for the record and the report.
DATASHEET_100PCT_PSI = {"ecoflex_00_10": 8.0, "ecoflex_00_20": 8.0, "ecoflex_00_30": 10.0,
                        "ecoflex_00_50": 12.0, "dragon_skin_10": 22.0, "dragon_skin_20": 49.0,
                        "dragon_skin_30": 86.0}

_TENSILE_FILES = {"ecoflex_00_10": "tensile_ecoflex_00-10.csv", "ecoflex_00_30": "tensile_ecoflex_00-30.csv",
                  "ecoflex_00_50": "tensile_ecoflex_00-50.csv",
                  "dragon_skin_10": "tensile_dragon_skin_10_medium.csv",
                  "dragon_skin_20": "tensile_dragon_skin_20.csv", "dragon_skin_30": "tensile_dragon_skin_30.csv"}
_COMPRESSION_LABELS = {"ecoflex_00_10": "EF10_0T", "ecoflex_00_30": "EF30_0T", "ecoflex_00_50": "EF50_0T"}
_LABELS = {"ecoflex_00_10": "Ecoflex 00-10", "ecoflex_00_20": "Ecoflex 00-20", "ecoflex_00_30": "Ecoflex 00-30",
           "ecoflex_00_50": "Ecoflex 00-50", "dragon_skin_10": "Dragon Skin 10",
           "dragon_skin_20": "Dragon Skin 20", "dragon_skin_30": "Dragon Skin 30", "pla": "rigid PLA"}


@dataclass(frozen=True)
class Material:
    """A pad material.

    Attributes:
        name: catalogue key (e.g. "ecoflex_00_30").
        label: display name ("Ecoflex 00-30").
        E: Young's modulus used [Pa] (compression-equivalent for silicones).
        nu: Poisson's ratio [-].
        mode: loading mode the modulus represents ("compression", "tension x compression ratio",
            "interpolated compression", "rigid").
        source: where the number comes from.
    """

    name: str
    label: str
    E: float
    nu: float
    mode: str
    source: str

    @property
    def is_rigid(self) -> bool:
        return self.mode == "rigid"


def data_dir() -> Path:
    """The materials data folder: $TELEOP_DATA_DIR/materials, else the copy shipped in scenes/data/materials
    (the shared data's files with their licences, so that a plain clone builds the pads)."""
    root = os.environ.get("TELEOP_DATA_DIR")
    return Path(root) / "materials" if root else Path(__file__).resolve().parent / "data" / "materials"


def read_tensile(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(engineering strain (n,) [-], engineering stress (n,) [Pa]) of a Marechal tensile CSV."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        raise InputError(f"{path}: file not found (TELEOP_DATA_DIR names a data folder holding materials/)") from None
    start = next((i for i, line in enumerate(lines) if line.startswith("Time (s)")), None)
    if start is None:
        raise InputError(f"{path}: no header row 'Time (s);True Strain;...' found")
    rows = []
    for k, line in enumerate(lines[start + 1:], start=start + 2):
        cells = line.split(";")
        if not cells[0].strip():
            continue
        try:
            rows.append((float(cells[3]), float(cells[4])))
        except (IndexError, ValueError):
            raise InputError(f"{path}:{k}: expected 5 numbers separated by ';'") from None
    a = np.array(rows)
    return a[:, 0], a[:, 1] * 1e6


def small_strain_modulus(strain: np.ndarray, stress: np.ndarray, window=SMALL_STRAIN) -> float:
    """Least-squares slope [Pa] of stress vs strain inside the engineering-strain window."""
    m = (strain >= window[0]) & (strain <= window[1])
    if m.sum() < 3:
        raise InputError(f"tensile curve: fewer than 3 samples in strain window {window}")
    return float(np.polyfit(strain[m], stress[m], 1)[0])


def read_compression(path: Path) -> dict[str, float]:
    """{sample_label: mean compression modulus [Pa]} from the phantom-material-database CSV."""
    try:
        with path.open(encoding="utf-8", newline="") as fh:
            out = {}
            for k, row in enumerate(csv.DictReader(fh), start=2):
                try:
                    out[row["sample_label"]] = float(row["elastic_modulus_mean_kPa"]) * 1e3
                except (KeyError, TypeError, ValueError):
                    raise InputError(f"{path}:{k}: expected sample_label and elastic_modulus_mean_kPa") from None
            return out
    except FileNotFoundError:
        raise InputError(f"{path}: file not found (TELEOP_DATA_DIR names a data folder holding materials/)") from None


@functools.lru_cache(maxsize=4)
def _catalogue(folder: str) -> dict[str, Material]:
    folder_p = Path(folder)
    tension = {k: small_strain_modulus(*read_tensile(folder_p / f)) for k, f in _TENSILE_FILES.items()}
    comp_all = read_compression(folder_p / "ecoflex_compression_moduli.csv")
    comp = {}
    for k, label in _COMPRESSION_LABELS.items():
        if label not in comp_all:
            raise InputError(f"{folder_p / 'ecoflex_compression_moduli.csv'}: missing sample {label}")
        comp[k] = comp_all[label]
    ratio = float(np.mean([comp[k] / tension[k] for k in comp]))  # compression / tension, Ecoflex grades
    cat: dict[str, Material] = {}
    src_c = "compression modulus, ecoflex_compression_moduli.csv (phantom-material-database, CC BY 4.0)"
    for k in comp:
        cat[k] = Material(k, _LABELS[k], comp[k], NU_SILICONE, "compression", src_c)
    # Ecoflex 00-20: log-linear in Shore 00 hardness between 00-10 and 00-30
    E20 = float(np.exp(0.5 * (np.log(comp["ecoflex_00_10"]) + np.log(comp["ecoflex_00_30"]))))
    cat["ecoflex_00_20"] = Material("ecoflex_00_20", _LABELS["ecoflex_00_20"], E20, NU_SILICONE,
                                    "interpolated compression",
                                    "Shore 00 log-linear interpolation of the 00-10 and 00-30 compression moduli")
    for k in ("dragon_skin_10", "dragon_skin_20", "dragon_skin_30"):
        cat[k] = Material(k, _LABELS[k], tension[k] * ratio, NU_SILICONE, "tension x compression ratio",
                          f"small-strain tensile slope {tension[k] / 1e3:.1f} kPa ({_TENSILE_FILES[k]}, "
                          f"Soft-Robotics-Materials-Database, ODbL 1.0) x Ecoflex compression/tension ratio "
                          f"{ratio:.2f}")
    cat["pla"] = Material("pla", _LABELS["pla"], E_PLA, NU_PLA, "rigid", "NatureWorks Ingeo 4043D datasheet")
    order = ["ecoflex_00_10", "ecoflex_00_20", "ecoflex_00_30", "ecoflex_00_50", "dragon_skin_10",
             "dragon_skin_20", "dragon_skin_30", "pla"]
    return {k: cat[k] for k in order}


def catalogue() -> dict[str, Material]:
    """All materials by key, softest silicone first, rigid PLA last (fitted from the CSVs, cached)."""
    return dict(_catalogue(str(data_dir())))


def get_material(name: str) -> Material:
    """The material called `name` (catalogue key); InputError for an unknown one."""
    cat = catalogue()
    if name not in cat:
        raise InputError(f"unknown material '{name}' (expected one of: {', '.join(cat)})")
    return cat[name]


def layer_factor(a: float, h: float) -> float:
    """Bonded thin-layer flat-punch correction f(a/h) = 1 + 1.33 (a/h) + 1.33 (a/h)^3 (nu = 0.5; Shull 2002)."""
    x = a / h
    return 1.0 + 1.33 * x + 1.33 * x ** 3


def contact_stiffness(material: Material, thickness: float = PAD_THICKNESS, tip_radius: float = TIP_RADIUS) -> float:
    """Target force-indentation slope [N/m] of a flat tip of radius a on a bonded layer of thickness h.

    k = 2 a E / (1 - nu^2) * f(a/h); rigid materials return RIGID_CONTACT_STIFFNESS (simulation cap).
    """
    if thickness <= 0 or tip_radius <= 0:
        raise InputError(f"contact stiffness: need thickness > 0 and tip radius > 0, got {thickness}, {tip_radius}")
    if material.is_rigid:
        return RIGID_CONTACT_STIFFNESS
    k = 2.0 * tip_radius * material.E / (1.0 - material.nu ** 2) * layer_factor(tip_radius, thickness)
    return float(min(k, RIGID_CONTACT_STIFFNESS))
