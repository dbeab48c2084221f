"""Export the project's own session recordings (MCAP, teleop.io.recording) to the interchange CSV.

A column spec names, for each interchange column, the session topic, field, element and scale:
{"motor_pos_mm": (TOPIC_ROBOT, "commanded_lengths", cable, 1e3), ...}. Every topic carries the
session time `t`; columns from other topics are interpolated onto the first column's times.
`cable_columns(i)` is the default for cable i: commanded length at the motor, estimated tension.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from teleop.io.recording_io import Recording, split_column, UNITS, write_interchange
from teleop.core.errors import InputError
from teleop.io.recording import TOPIC_ROBOT, read_session


def cable_columns(cable: int) -> dict:
    """Default spec for cable `cable` (0-5): motor-side length [mm] and the estimated tension [N]."""
    if not 0 <= cable < 6:
        raise InputError(f"cable must be 0..5, got {cable}")
    return {"motor_pos_mm": (TOPIC_ROBOT, "commanded_lengths", cable, 1e3),
            "motor_force_N": ("/estimation", "tensions", cable, 1.0)}


def session2recording(path: str | Path, columns: dict, metadata: dict | None = None) -> Recording:
    """A Recording from session file `path` through `columns` (see the module docstring)."""
    s = read_session(path)
    if not columns:
        raise InputError(f"{path}: no columns to export")
    t_ref = None
    chans, units = {}, {}
    for col, (topic, field, element, scale) in columns.items():
        parts = split_column(col)
        if parts is None or parts[1] not in UNITS:
            raise InputError(f"export column '{col}': not an interchange column name (quantity_unit)")
        msgs = s.messages(topic)
        if not msgs or field not in msgs[0]:
            raise InputError(f"{path}: topic '{topic}' has no field '{field}' ({len(msgs)} messages)")
        t = np.array([m["t"] for m in msgs], dtype=float)
        v = np.array([m[field] if element is None else m[field][element] for m in msgs], dtype=float) * scale
        keep = np.concatenate(([True], np.diff(t) > 0))
        t, v = t[keep], v[keep]
        if t_ref is None:
            t_ref = t
        else:
            v = np.interp(t_ref, t, v)
        quantity, unit = parts
        si, factor = UNITS[unit]
        chans[quantity] = v * factor
        units[quantity] = si
    meta = {"source": f"session {Path(path).name}", **(metadata or {})}
    if s.damage:
        meta["damage"] = s.damage
    return Recording(str(path), t_ref, chans, units, meta)


def export_session(path: str | Path, out: str | Path, columns: dict, metadata: dict | None = None) -> Path:
    """Write session `path` as interchange CSV `out` (atomically)."""
    return write_interchange(out, session2recording(path, columns, metadata))
