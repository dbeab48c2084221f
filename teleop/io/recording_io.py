"""Recordings in and out: the interchange CSV (docs/formats.md) and other layouts through a TOML column map.

A `Recording` holds time `t` (n,) [s] and named channels in SI units (m, rad, N, N m; temperature in C).
Canonical channel names: motor_pos, tip_pos, actuator_pos, motor_force, tip_force, bend_angle,
temperature, indentation, force (actuator_pos: the actuator's own position where motor_pos is measured past a
gearbox or coupling). Columns of other quantities are kept in `extra` (raw numbers) and ignored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from teleop.core.config import check_keys, load_toml
from teleop.core.errors import InputError
from teleop.io.outputs import atomic_write
from teleop.io.recording import MAGIC as MCAP_MAGIC

# unit suffix -> (SI unit, factor to SI); angles go to rad, lengths to m, torques to N m
UNITS = {
    "s": ("s", 1.0), "ms": ("s", 1e-3),
    "m": ("m", 1.0), "mm": ("m", 1e-3), "um": ("m", 1e-6),
    "rad": ("rad", 1.0), "deg": ("rad", math.pi / 180.0),
    "N": ("N", 1.0), "mN": ("N", 1e-3),
    "Nm": ("N m", 1.0), "mNm": ("N m", 1e-3),
    "C": ("C", 1.0),
}
# quantity -> SI units it may carry
QUANTITIES = {
    "t": ("s",),
    "motor_pos": ("m", "rad"), "tip_pos": ("m", "rad"), "actuator_pos": ("m", "rad"),
    "motor_force": ("N", "N m"), "tip_force": ("N", "N m"),
    "bend_angle": ("rad",), "temperature": ("C",),
    "indentation": ("m",), "force": ("N",),
}
MAX_NAN_GAP = 3  # isolated gaps up to this many samples are interpolated; longer NaN runs are an error
# A text recording larger than this [MB] is refused before it is read (its numbers take several times the
# file's size in memory); the commands that read recordings lift it with --max-input-mb.
MAX_INPUT_MB = 512.0
SNIFF_BYTES = 4096  # the first block, looked at before a file is read


@dataclass(frozen=True)
class Recording:
    """One recording: t (n,) [s]; channels name -> (n,) SI; units name -> SI unit; metadata key -> text."""

    path: str
    t: np.ndarray
    channels: dict
    units: dict
    metadata: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    @property
    def dt(self) -> float:
        return float(np.median(np.diff(self.t)))

    def has(self, *names: str) -> bool:
        return all(name in self.channels for name in names)


def split_column(name: str) -> tuple[str, str] | None:
    """'motor_pos_mm' -> ('motor_pos', 'mm'); None when the quantity is not a recognised one."""
    for quantity in sorted(QUANTITIES, key=len, reverse=True):
        if name.startswith(quantity + "_"):
            return quantity, name[len(quantity) + 1:]
    return None


def _to_float(text: str, where: str) -> float:
    text = text.strip()
    if text == "" or text.lower() in ("nan", "na", "null"):
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{where}: '{text}' is not a number") from None


def _parse_rows(path: Path, lines: list[tuple[int, str]], delimiter: str, ncol: int,
                names: list[str]) -> np.ndarray:
    """Numbers (rows, ncol) from (line number, text) pairs; errors name file, line and column."""
    data = np.empty((len(lines), ncol))
    for r, (lineno, text) in enumerate(lines):
        cells = text.split(delimiter) if delimiter else text.split()
        if len(cells) != ncol:
            raise InputError(f"{path}:{lineno}: expected {ncol} fields, found {len(cells)}")
        for c, cell in enumerate(cells):
            data[r, c] = _to_float(cell, f"{path}:{lineno}: column '{names[c]}'")
    return data


def _fill_nans(path: Path, name: str, x: np.ndarray, linenos: list[int]) -> np.ndarray:
    """Interpolate NaN gaps of <= MAX_NAN_GAP samples; longer runs raise naming column and line."""
    bad = np.isnan(x)
    if not bad.any():
        return x
    if bad.all():
        raise InputError(f"{path}: column '{name}' holds no numbers")
    edges = np.diff(np.concatenate(([0], bad.astype(np.int8), [0])))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    for a, b in zip(starts, stops):
        if b - a > MAX_NAN_GAP or a == 0 or b == x.shape[0]:
            raise InputError(f"{path}:{linenos[a]}: column '{name}' has a run of {b - a} missing/NaN "
                             f"values (at most {MAX_NAN_GAP} inside the record are interpolated)")
    idx = np.arange(x.shape[0])
    y = x.copy()
    y[bad] = np.interp(idx[bad], idx[~bad], x[~bad])
    return y


def _check_time(path: Path, t: np.ndarray, linenos: list[int]) -> None:
    if np.isnan(t).any():
        k = int(np.flatnonzero(np.isnan(t))[0])
        raise InputError(f"{path}:{linenos[k]}: time 't_s' is missing or NaN")
    dt = np.diff(t)
    if (dt <= 0).any():
        k = int(np.flatnonzero(dt <= 0)[0]) + 1
        raise InputError(f"{path}:{linenos[k]}: time is not increasing ({t[k - 1]:g} then {t[k]:g} s)")


def _build(path: Path, t: np.ndarray, chans: dict, units: dict, meta: dict, extra: dict,
           linenos: list[int]) -> Recording:
    if t.shape[0] < 20:
        raise InputError(f"{path}: only {t.shape[0]} samples (need at least 20)")
    _check_time(path, t, linenos)
    chans = {k: _fill_nans(path, k, v, linenos) for k, v in chans.items()}
    if len(chans) < 2:
        found = ", ".join(chans) or "none"
        raise InputError(f"{path}: needs at least two recognised channels (an input and an output), found "
                         f"{found}; recognised: {', '.join(q for q in QUANTITIES if q != 't')}")
    load = meta.get("load")
    if load is not None and load not in ("spring", "external"):
        raise InputError(f"{path}: metadata 'load' must be 'spring' or 'external', got '{load}'")
    return Recording(str(path), t, chans, units, meta, extra)


def sniff(path: str | Path, max_mb: float | None = MAX_INPUT_MB) -> None:
    """Refuse `path` before it is read, with one line that shows none of its bytes: larger than `max_mb`
    [MB] (None: no limit), an MCAP session recording (`teleop export` turns one into the interchange CSV),
    or binary (a NUL byte, or not UTF-8, in the first SNIFF_BYTES)."""
    path = Path(path)
    try:
        size = path.stat().st_size
        with path.open("rb") as fh:
            head = fh.read(SNIFF_BYTES)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    if max_mb is not None and size > max_mb * 1e6:
        raise InputError(f"{path}: {size / 1e6:.0f} MB, larger than the {max_mb:g} MB a recording may have "
                         f"(lift the limit with --max-input-mb)")
    if head.startswith(MCAP_MAGIC):
        raise InputError(f"{path}: an MCAP session recording, not a text recording; write one cable as the "
                         f"interchange CSV first: teleop export {path} --csv OUT.csv [--cable N]")
    if b"\0" in head:
        raise InputError(f"{path}: binary content (NUL bytes in the first {len(head)} bytes), expected a text "
                         f"recording (CSV)")
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 3 or len(head) == size:  # not a character cut by the block's end
            raise InputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}), expected a text "
                             f"recording (CSV)") from None


def _read_lines(path: Path, max_mb: float | None = MAX_INPUT_MB) -> list[str]:
    sniff(path, max_mb)
    try:
        return path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not UTF-8 text ({exc.reason})") from None


def _delimiter_hint(header: list[str]) -> str:
    """'; semicolon-separated, expected commas' when a one-cell header holds another delimiter, else ''."""
    if len(header) != 1:
        return ""
    for delim, name in ((";", "semicolon"), ("\t", "tab"), ("|", "pipe")):
        if delim in header[0]:
            return f"; the file is {name}-separated, expected commas (or a column map: --map MAP.toml)"
    return ""


def read_interchange(path: str | Path, max_mb: float | None = MAX_INPUT_MB) -> Recording:
    """Read the interchange CSV: `# key = value` lines, a header of `quantity_unit` names, numbers."""
    path = Path(path)
    meta: dict = {}
    header: list[str] | None = None
    header_line = 0
    rows: list[tuple[int, str]] = []
    for lineno, line in enumerate(_read_lines(path, max_mb), start=1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            if header is None and "=" in s:
                key, _, value = s[1:].partition("=")
                meta[key.strip()] = value.strip()
            continue
        if header is None:
            header = [c.strip() for c in s.split(",")]
            header_line = lineno
        else:
            rows.append((lineno, s))
    if header is None:
        raise InputError(f"{path}: no header row (expected CSV with a 't_s' column)")
    if "t_s" not in header:
        hint = _delimiter_hint(header)
        if hint:
            raise InputError(f"{path}:{header_line}: one column only{hint}")
        shown = ", ".join(header)
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        raise InputError(f"{path}:{header_line}: missing time column 't_s' (header: {shown}; other layouts "
                         f"need a column map: --map NAME|MAP.toml)")
    if len(set(header)) != len(header):
        raise InputError(f"{path}:{header_line}: duplicate column names")
    data = _parse_rows(path, rows, ",", len(header), header)
    linenos = [r[0] for r in rows]
    chans, units, extra = {}, {}, {}
    for c, name in enumerate(header):
        if name == "t_s":
            continue
        parts = split_column(name)
        if parts is None:
            extra[name] = data[:, c]
            continue
        quantity, unit = parts
        if unit not in UNITS or UNITS[unit][0] not in QUANTITIES[quantity]:
            allowed = [u for u, (si, _) in UNITS.items() if si in QUANTITIES[quantity]]
            raise InputError(f"{path}:{header_line}: column '{name}': unknown unit '{unit}' for {quantity} "
                             f"(expected one of: {', '.join(allowed)})")
        if quantity in chans:
            raise InputError(f"{path}:{header_line}: column '{name}': {quantity} given twice")
        si, factor = UNITS[unit]
        chans[quantity] = data[:, c] * factor
        units[quantity] = si
    t = data[:, header.index("t_s")]
    return _build(path, t, chans, units, meta, extra, linenos)


@dataclass(frozen=True)
class ColumnSpec:
    """Column `index` (1-based) holds `quantity`; value in `unit` = raw * scale + offset."""

    index: int
    quantity: str
    unit: str
    scale: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class ColumnMap:
    """A layout: delimiter, comment prefix, lines to skip, header row present, columns, metadata."""

    path: str
    columns: tuple
    delimiter: str = ","
    comment: str = "#"
    skip_lines: int = 0
    header: bool = False
    metadata: dict = field(default_factory=dict)


def load_column_map(path: str | Path) -> ColumnMap:
    """Read a column map TOML ([format] + [[column]] + optional [metadata]); unknown keys raise."""
    path = Path(path)
    doc = load_toml(path)
    check_keys(doc, ("format", "column", "metadata"), str(path))
    fmt = doc.get("format", {})
    check_keys(fmt, ("delimiter", "comment", "skip_lines", "header"), f"{path}: [format]")
    cols = doc.get("column")
    if not isinstance(cols, list) or not cols:
        raise InputError(f"{path}: needs [[column]] tables (index, quantity, unit, scale)")
    specs = []
    for k, col in enumerate(cols):
        where = f"{path}: [[column]] #{k + 1}"
        check_keys(col, ("index", "quantity", "unit", "scale", "offset", "description"), where)
        for key in ("index", "quantity", "unit"):
            if key not in col:
                raise InputError(f"{where}: missing key '{key}'")
        q, u, idx = col["quantity"], col["unit"], col["index"]
        if not isinstance(idx, int) or idx < 1:
            raise InputError(f"{where}: 'index' must be a column number >= 1")
        if q not in QUANTITIES:
            raise InputError(f"{where}: unknown quantity '{q}' (expected one of: {', '.join(QUANTITIES)})")
        if u not in UNITS or UNITS[u][0] not in QUANTITIES[q]:
            raise InputError(f"{where}: unknown unit '{u}' for {q}")
        scale = float(col.get("scale", 1.0))
        offset = float(col.get("offset", 0.0))
        if not (math.isfinite(scale) and math.isfinite(offset)) or scale == 0:
            raise InputError(f"{where}: 'scale' must be finite and non-zero")
        specs.append(ColumnSpec(idx, q, u, scale, offset))
    if sum(s.quantity == "t" for s in specs) != 1:
        raise InputError(f"{path}: exactly one column must have quantity 't'")
    meta = doc.get("metadata", {})
    if not all(isinstance(v, str) for v in meta.values()):
        raise InputError(f"{path}: [metadata] values must be strings")
    delim = fmt.get("delimiter", ",")
    comment = fmt.get("comment", "#")
    skip = fmt.get("skip_lines", 0)
    if not isinstance(delim, str) or not isinstance(comment, str) or not isinstance(skip, int) or skip < 0:
        raise InputError(f"{path}: [format] expects delimiter (text), comment (text), skip_lines (int >= 0)")
    return ColumnMap(str(path), tuple(specs), delim, comment, skip, bool(fmt.get("header", False)),
                     dict(meta))


def builtin_map(name: str) -> Path:
    """Path of a column map shipped in teleop/io/maps (e.g. 'mrdlab')."""
    path = Path(__file__).with_name("maps") / f"{name}.toml"
    if not path.exists():
        shipped = ", ".join(p.stem for p in path.parent.glob("*.toml"))
        raise InputError(f"column map '{name}' not found (shipped: {shipped}; or give a .toml path)")
    return path


def read_mapped(path: str | Path, cmap: ColumnMap, max_mb: float | None = MAX_INPUT_MB) -> Recording:
    """Read any delimited text file through a column map."""
    path = Path(path)
    rows = []
    seen_header = not cmap.header
    for lineno, line in enumerate(_read_lines(path, max_mb), start=1):
        s = line.strip()
        if lineno <= cmap.skip_lines or not s or (cmap.comment and s.startswith(cmap.comment)):
            continue
        if not seen_header:
            seen_header = True
            continue
        rows.append((lineno, s))
    if not rows:
        raise InputError(f"{path}: no data rows")
    first = rows[0][1]
    ncol = len(first.split(cmap.delimiter) if cmap.delimiter else first.split())
    need = max(s.index for s in cmap.columns)
    if ncol < need:
        raise InputError(f"{path}:{rows[0][0]}: {ncol} columns (split at the map's delimiter "
                         f"{cmap.delimiter or 'whitespace'!r}) but map {cmap.path} uses column {need}")
    data = _parse_rows(path, rows, cmap.delimiter, ncol, [f"#{k + 1}" for k in range(ncol)])
    linenos = [r[0] for r in rows]
    chans, units, t = {}, {}, None
    for s in cmap.columns:
        si, factor = UNITS[s.unit]
        x = (data[:, s.index - 1] * s.scale + s.offset) * factor
        if s.quantity == "t":
            t = x
        else:
            if s.quantity in chans:
                raise InputError(f"{cmap.path}: quantity '{s.quantity}' mapped twice")
            chans[s.quantity] = x
            units[s.quantity] = si
    meta = {"source": str(path), **cmap.metadata}
    return _build(path, t, chans, units, meta, {}, linenos)


def read_recording(path: str | Path, column_map: str | Path | None = None,
                   max_mb: float | None = MAX_INPUT_MB) -> Recording:
    """Read `path` as interchange CSV, or through `column_map` (a .toml path or a shipped map name); a file
    larger than `max_mb` [MB] (None: no limit), binary or an MCAP session is refused before it is read."""
    if column_map is None:
        return read_interchange(path, max_mb)
    cm = Path(column_map) if str(column_map).endswith(".toml") else builtin_map(str(column_map))
    return read_mapped(path, load_column_map(cm), max_mb)


# SI unit -> interchange suffix used when writing
_WRITE_SUFFIX = {"m": ("mm", 1e3), "rad": ("deg", 180.0 / math.pi), "N": ("N", 1.0), "N m": ("Nm", 1.0),
                 "C": ("C", 1.0)}


def interchange_text(t: np.ndarray, channels: dict, units: dict, metadata: dict | None = None) -> str:
    """The interchange CSV text for time t (n,) [s] and SI channels (positions written in mm or deg)."""
    lines = [f"# {k} = {v}" for k, v in (metadata or {}).items()]
    names, cols = ["t_s"], [np.asarray(t, float)]
    for name, x in channels.items():
        suffix, factor = _WRITE_SUFFIX[units[name]]
        names.append(f"{name}_{suffix}")
        cols.append(np.asarray(x, float) * factor)
    lines.append(",".join(names))
    block = np.column_stack(cols)
    lines.extend(",".join(f"{v:.9g}" for v in row) for row in block)
    return "\n".join(lines) + "\n"


def write_interchange(path: str | Path, rec_or_t, channels: dict | None = None, units: dict | None = None,
                      metadata: dict | None = None) -> Path:
    """Write a Recording (or t, channels, units, metadata) as interchange CSV, atomically."""
    if isinstance(rec_or_t, Recording):
        rec = rec_or_t
        text = interchange_text(rec.t, rec.channels, rec.units, rec.metadata)
    else:
        text = interchange_text(rec_or_t, channels, units, metadata)
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
