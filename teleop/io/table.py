"""Calibration CSVs: `#` comment lines, one header row, numbers; read strictly.

Every problem is one InputError line naming the file, the line number in the file (1-based, comments
counted) and the column: a missing column, a cell that is not a finite number, too few rows.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from teleop.core.config import check_input
from teleop.core.errors import InputError
from teleop.io.recording_io import sniff


def read_table(path: str | Path, required: tuple[str, ...], optional: tuple[str, ...] = (),
               words: dict[str, dict[str, float]] | None = None, min_rows: int = 2) -> tuple[dict, dict]:
    """Columns of `path` as float arrays, and the `# key = value` metadata.

    required: columns that must be present; optional: read when present; words: per column, the words a
    cell may hold instead of a number and their value (e.g. {"branch": {"loading": 1, "unloading": -1}}).
    Returns ({column: (n,) float}, {key: text}); columns absent from the file are left out.
    """
    path = check_input(path)
    sniff(path, max_mb=None)  # binary or an MCAP session: refused before it is read (its size: the caller's)
    words = words or {}
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not UTF-8 text ({exc.reason})") from None
    meta: dict[str, str] = {}
    body: list[tuple[int, str]] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            key, eq, value = s[1:].partition("=")
            if eq:
                meta[key.strip()] = value.strip()
            continue
        body.append((lineno, line))
    expected = ", ".join(required + tuple(f"[{c}]" for c in optional))
    if not body:
        raise InputError(f"{path}: no header row (expected columns {expected})")
    header_line, header_text = body[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
    for col in required:
        if col not in header:
            raise InputError(f"{path}: line {header_line}: missing column '{col}' (expected columns {expected})")
    wanted = [c for c in required + optional if c in header]
    idx = {c: header.index(c) for c in wanted}
    out: dict[str, list[float]] = {c: [] for c in wanted}
    for lineno, line in body[1:]:
        row = next(csv.reader([line]))
        for c in wanted:
            cell = row[idx[c]].strip() if idx[c] < len(row) else ""
            value = words.get(c, {}).get(cell.lower())
            if value is None:
                try:
                    value = float(cell)
                except ValueError:
                    value = float("nan")
                if not np.isfinite(value):
                    allowed = " or ".join(["a finite number"] + sorted(words.get(c, {})))
                    raise InputError(f"{path}: line {lineno}: column '{c}': expected {allowed}, got '{cell}'")
            out[c].append(value)
    n = len(body) - 1
    if n < min_rows:
        raise InputError(f"{path}: {n} data rows, expected at least {min_rows}")
    return {c: np.array(v) for c, v in out.items()}, meta
