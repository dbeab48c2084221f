"""The device side's own guard on a commanded stylus force, shared by every HapticDevice backend."""

from __future__ import annotations

import numpy as np

from devices.base import DeviceError
from teleop.core.kernels.jit import f64c
from teleop.core.rendering import clamp_norm


def guarded_force(dev, force, who: str) -> tuple:
    """(fx, fy, fz) [N] to apply for servo_cf(force) on `dev` (needs dev.is_open and dev.spec).

    Not open or not 3 components -> DeviceError naming `who`; any non-finite component -> zero force (never
    apply NaN); the norm is clamped to dev.spec.max_force_peak with the direction kept.
    """
    if not dev.is_open:
        raise DeviceError(f"{who}: servo_cf() before open()")
    F = f64c(force)  # the loop's (3,) float64 array as it is
    if F.shape != (3,):
        raise DeviceError(f"{who}: force must have 3 components, got shape {F.shape}")
    x, y, z = F.tolist()
    peak = dev.spec.max_force_peak
    if x * x + y * y + z * z <= peak * peak:  # the usual case (False for any nan/inf)
        return x, y, z
    return clamp_norm(x, y, z, peak)
