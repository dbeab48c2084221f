"""The calibration file (TOML) that `teleop calibrate` writes and the loop loads (docs/formats.md).

    format = "cdpr-teleop calibration 1"
    kind = "fsr" | "fbg" | "one-sensor"
    source = "<recording>"
    [fsr] / [fbg] / [one_sensor]     the values the loop needs (units in the key names)
    [stderr]                         their standard errors, same keys
    [fit]                            fit quality and derived values (informational, not loaded)

Written by a small emitter here: Python's tomllib only reads TOML, and the file holds nothing but flat
tables of numbers, strings and number lists, so a writer library would be a dependency for 20 lines.
Numbers are written with repr (round trip exact).
"""

from __future__ import annotations

import math
from pathlib import Path

from teleop.core.config import check_keys, load_toml
from teleop.core.errors import InputError
from teleop.core.sensors import FbgParams, FsrCalibration, ProximalDistalModel
from teleop.io.outputs import atomic_write

FORMAT = "cdpr-teleop calibration 1"
SECTION = {"fsr": "fsr", "fbg": "fbg", "one-sensor": "one_sensor"}
KEYS = {"fsr": ("loading_S", "unloading_S", "t_max_N"),
        "fbg": ("S_pm_N", "r", "kT1_pm_C", "kT2_pm_C", "noise_pm"),
        "one-sensor": ("Kp", "Kr", "bp", "br", "unit")}


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        v = float(v)
        if not math.isfinite(v):
            return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"calibration file: cannot write {type(v).__name__}")


def dumps(top: dict, tables: dict[str, dict]) -> str:
    """TOML text of top-level keys and flat tables (a nested dict becomes a dotted sub-table)."""
    lines = [f"{k} = {_value(v)}" for k, v in top.items()]

    def table(name: str, body: dict) -> None:
        lines.append("")
        lines.append(f"[{name}]")
        subs = []
        for k, v in body.items():
            if isinstance(v, dict):
                subs.append((f"{name}.{k}", v))
            else:
                lines.append(f"{k} = {_value(v)}")
        for sub_name, sub in subs:
            table(sub_name, sub)

    for name, body in tables.items():
        table(name, body)
    return "\n".join(lines) + "\n"


def write_calibration(path: str | Path, kind: str, source: str, values: dict, stderr: dict, fit: dict,
                      comment: str = "") -> Path:
    """Write a calibration file atomically; `values` must hold exactly KEYS[kind]."""
    check_keys(values, KEYS[kind], f"calibration {kind}")
    head = f"# {comment}\n" if comment else ""
    text = head + dumps({"format": FORMAT, "kind": kind, "source": source},
                        {SECTION[kind]: values, "stderr": stderr, "fit": fit})
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def _number(table: dict, key: str, where: str) -> float:
    v = table.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(f"{where}: key '{key}' must be a finite number, got {v!r}")
    return float(v)


def load_calibration(path: str | Path):
    """(kind, model) from a calibration file: an FsrCalibration, FbgParams or ProximalDistalModel.

    Unknown keys, a missing key or a wrong type raise an InputError naming the file and key."""
    doc = load_toml(path)
    check_keys(doc, ("format", "kind", "source", "fsr", "fbg", "one_sensor", "stderr", "fit"), str(path))
    if doc.get("format") != FORMAT:
        raise InputError(f"{path}: key 'format' must be \"{FORMAT}\", got {doc.get('format')!r}")
    kind = doc.get("kind")
    if kind not in SECTION:
        raise InputError(f"{path}: key 'kind' must be one of {', '.join(SECTION)}, got {kind!r}")
    sec = SECTION[kind]
    table = doc.get(sec)
    where = f"{path}: [{sec}]"
    if not isinstance(table, dict):
        raise InputError(f"{path}: missing table [{sec}] for kind = \"{kind}\"")
    check_keys(table, KEYS[kind], where)
    for key in KEYS[kind]:
        if key not in table:
            raise InputError(f"{where}: missing key '{key}'")
    if kind == "fsr":
        coefs = {}
        for key in ("loading_S", "unloading_S"):
            c = table[key]
            if not isinstance(c, list) or len(c) < 2 or not all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in c):
                raise InputError(f"{where}: key '{key}' must be a list of finite numbers (power-series "
                                 f"coefficients of conductance [S] in tension [N], lowest first)")
            coefs[key] = tuple(float(x) for x in c)
        t_max = _number(table, "t_max_N", where)
        if t_max <= 0:
            raise InputError(f"{where}: key 't_max_N' must be > 0, got {t_max}")
        return kind, FsrCalibration(coefs["loading_S"], coefs["unloading_S"], t_max)
    if kind == "fbg":
        v = {k: _number(table, k, where) for k in KEYS[kind]}
        if v["S_pm_N"] <= 0:
            raise InputError(f"{where}: key 'S_pm_N' must be > 0, got {v['S_pm_N']}")
        return kind, FbgParams(**v)
    v = {k: _number(table, k, where) for k in ("Kp", "Kr", "bp", "br")}
    if v["Kp"] == 0 or v["Kr"] == 0:
        raise InputError(f"{where}: keys 'Kp' and 'Kr' must be non-zero slopes")
    return kind, ProximalDistalModel(**v)


def load_fsr(path: str | Path):
    """The FsrCalibration of a calibration file of kind "fsr" (the loop reads FSR tensions; an FBG or
    one-sensor file is refused with what it holds)."""
    kind, model = load_calibration(path)
    if kind != "fsr":
        raise InputError(f"{path}: kind = \"{kind}\", expected \"fsr\" (this reads an FSR array's calibration; "
                         f"FBG and one-sensor files calibrate `teleop palpate --sensor fbg|one --calibration FILE`)")
    return model
