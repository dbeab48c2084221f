"""Calibration CSVs: the recordings the calibration fits read, the FSR calibration data file, the examples.

- FSR calibration data (`load_fsr_calibration_csv`, `write_fsr_calibration_csv`, `load_fsr_calibration`): one
  row per hold, `tension_N`, `conductance_uS`, `branch` (loading|unloading or +1|-1); what `teleop session
  --fsr-calibration` loads.
- The calibration recordings (`teleop calibrate`): the FSR step protocol (`read_fsr_steps`, branch optional:
  the rows' order tells it), the FBG load steps (`read_fbg_steps`) and one cable's motor and tip force
  (`read_one_sensor`, interchange CSV or a column map); the fits are teleop.core.calibration.
- `write_examples`: the three calibration recordings made from the sensor physics with known parameters
  (teleop.core.calibration.generate); `python -m teleop.io.calibration_csv DIR [SEED]` writes them.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

from teleop.core.calibration.fbg import BRANCH_WORDS as FBG_BRANCH_WORDS
from teleop.core.calibration.fbg import FbgData, loading_state
from teleop.core.calibration.fsr import BRANCH_WORDS as FSR_BRANCH_WORDS
from teleop.core.calibration.fsr import BRANCHES, branches_from_order
from teleop.core.calibration.generate import fbg_load_steps, fsr_step_protocol, one_cable_cycles
from teleop.core.errors import InputError
from teleop.core.sensors import (LOADING, UNLOADING, FsrCalibration, FsrCalibrationData, default_fsr_calibration,
                                 fit_fsr_calibration)
from teleop.io.outputs import atomic_write
from teleop.io.recording_io import MAX_INPUT_MB, read_recording
from teleop.io.table import read_table

_CSV_COLUMNS = ("tension_N", "conductance_uS", "branch")


def load_fsr_calibration_csv(path: str | Path) -> FsrCalibrationData:
    """Read a calibration CSV: columns `tension_N`, `conductance_uS`, `branch` (loading|unloading or +1|-1).

    `#` lines are comments. Missing columns or bad values raise a one-line InputError naming file and column.
    """
    path = Path(path)
    try:
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip() and not ln.startswith("#")]
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    if not lines:
        raise InputError(f"{path}: empty calibration file (expected columns {', '.join(_CSV_COLUMNS)})")
    rows = list(csv.reader(lines))
    header = [h.strip() for h in rows[0]]
    for col in _CSV_COLUMNS:
        if col not in header:
            raise InputError(f"{path}: missing column '{col}' (expected columns {', '.join(_CSV_COLUMNS)})")
    idx = {c: header.index(c) for c in _CSV_COLUMNS}
    tension, reading, branch = [], [], []
    for lineno, row in enumerate(rows[1:], start=2):
        try:
            t = float(row[idx["tension_N"]])
            g = float(row[idx["conductance_uS"]]) * 1e-6
        except (ValueError, IndexError):
            raise InputError(f"{path}: data row {lineno}: tension_N and conductance_uS must be numbers") from None
        raw = row[idx["branch"]].strip().lower() if idx["branch"] < len(row) else ""
        b = {"loading": LOADING, "unloading": UNLOADING, "+1": LOADING, "1": LOADING, "-1": UNLOADING}.get(raw)
        if b is None or not (np.isfinite(t) and np.isfinite(g)):
            raise InputError(f"{path}: data row {lineno}: column 'branch' must be loading or unloading "
                             f"and values finite, got {row}")
        tension.append(t)
        reading.append(g)
        branch.append(b)
    data = FsrCalibrationData(np.array(tension), np.array(reading), np.array(branch), source=str(path))
    for b, name in ((LOADING, "loading"), (UNLOADING, "unloading")):
        if np.count_nonzero(data.branch == b) < 6:
            raise InputError(f"{path}: column 'branch' needs at least 6 {name} rows for a quintic fit")
    return data


def write_fsr_calibration_csv(path: str | Path, data: FsrCalibrationData) -> Path:
    """Write calibration data in the format `load_fsr_calibration_csv` reads (atomically)."""
    lines = [f"# source = {data.source}", ",".join(_CSV_COLUMNS)]
    for t, g, b in zip(data.tension, data.reading, data.branch):
        lines.append(f"{t:.6f},{g * 1e6:.6f},{'loading' if b == LOADING else 'unloading'}")
    text = "\n".join(lines) + "\n"
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def load_fsr_calibration(path: str | Path, **kwargs) -> FsrCalibration:
    """Read a calibration CSV (`load_fsr_calibration_csv`) and fit its two quintics."""
    return fit_fsr_calibration(load_fsr_calibration_csv(path), **kwargs)


def read_fsr_steps(path: str | Path) -> FsrCalibrationData:
    """The step protocol CSV at `path` (module docstring); >= 6 rows per branch."""
    cols, meta = read_table(path, ("tension_N", "conductance_uS"), ("branch",), {"branch": FSR_BRANCH_WORDS},
                            min_rows=12)
    t, g = cols["tension_N"], cols["conductance_uS"] * 1e-6
    b = cols["branch"] if "branch" in cols else branches_from_order(t)
    for br, name in BRANCHES:
        if np.count_nonzero(b == br) < 6:
            raise InputError(f"{path}: {np.count_nonzero(b == br)} {name} rows, expected at least 6 "
                             f"(a quintic per branch)")
    return FsrCalibrationData(t, g, b.astype(int), source=meta.get("source", str(path)))


def read_fbg_steps(path: str | Path) -> FbgData:
    """The load-step CSV at `path` (module docstring)."""
    cols, meta = read_table(path, ("force_N", "temperature_C", "dl1_pm", "dl2_pm"), ("branch",),
                            {"branch": FBG_BRANCH_WORDS}, min_rows=8)
    s = cols["branch"] if "branch" in cols else loading_state(cols["force_N"])
    return FbgData(cols["force_N"], cols["temperature_C"], cols["dl1_pm"], cols["dl2_pm"], s,
                   source=meta.get("source", str(path)))


def read_one_sensor(path: str | Path, column_map: str | None = None,
                    max_mb: float | None = MAX_INPUT_MB) -> tuple[np.ndarray, np.ndarray, str, str]:
    """(Fp, Fd, unit, source) from a recording with motor and tip force (interchange CSV or `column_map`;
    larger than `max_mb` [MB] refused, None: no limit)."""
    rec = read_recording(path, column_map, max_mb)
    for name in ("motor_force", "tip_force"):
        if name not in rec.channels:
            raise InputError(f"{path}: no {name} column (expected {name}_N or {name}_Nm: one cable's "
                             f"proximal and distal force)")
    unit = rec.units.get("motor_force", "N")
    return rec.channels["motor_force"], rec.channels["tip_force"], unit, rec.metadata.get("source", str(path))


def write_examples(directory, seed: int = 0) -> list:
    """Write fsr_steps.csv (truth: the built-in FSR calibration), fbg_steps.csv (truth: seed 001's constants,
    h = 0.48 N) and one_cable.csv (truth: mu 0.08 over 2 pi) into `directory`; returns the paths."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    texts = {"fsr_steps.csv": fsr_step_protocol(default_fsr_calibration(), seed=seed),
             "fbg_steps.csv": fbg_load_steps(seed=seed),
             "one_cable.csv": one_cable_cycles(seed=seed)[0]}
    return [atomic_write(d / name, lambda tmp, text=text: tmp.write_text(text, encoding="utf-8"))
            for name, text in texts.items()]


if __name__ == "__main__":  # pragma: no cover - `python -m teleop.io.calibration_csv DIR [SEED]`
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: python -m teleop.io.calibration_csv DIR [SEED]")
    for path in write_examples(sys.argv[1], int(sys.argv[2]) if len(sys.argv) == 3 else 0):
        print(path)
