"""A campaign file's values, checked: whole numbers and fields typed as their dataclass declares them, each
error naming the file and key."""

from __future__ import annotations

import math

from teleop.core.errors import InputError


def get_int(table: dict, key: str, where: str, default: int | None = None, minimum: int | None = None) -> int:
    """A whole number from `table[key]` (or `default`), at least `minimum`, with the file and key named."""
    if key not in table:
        if default is None:
            raise InputError(f"{where}: missing key '{key}' (expected a whole number)")
        return int(default)
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, int):
        raise InputError(f"{where}: key '{key}' must be a whole number, got {v!r}")
    if minimum is not None and v < minimum:
        raise InputError(f"{where}: key '{key}' must be >= {minimum}, got {v}")
    return int(v)


def coerce(kind: str, value, where: str):
    """`value` checked against a dataclass field type written as text ('float', 'int', 'bool', 'str',
    'float | None'); ints are accepted for floats. Returns the value as that type."""
    base = kind.replace(" | None", "").strip()
    if base == "bool":
        if not isinstance(value, bool):
            raise InputError(f"{where}: expected true or false, got {value!r}")
        return value
    if base == "str":
        if not isinstance(value, str):
            raise InputError(f"{where}: expected a string, got {value!r}")
        return value
    if base == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(f"{where}: expected a whole number, got {value!r}")
        return int(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{where}: expected a number, got {value!r}")
    if not math.isfinite(value):
        raise InputError(f"{where}: expected a finite number, got {value!r}")
    return float(value)
