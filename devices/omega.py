"""`omega://`: Force Dimension devices (omega.x, delta.x, sigma.x, Novint Falcon) through forcedimension-core.

Synchronous DHD calls each tick: dhd.getPosition / getLinearVelocity / getOrientationFrame (SI: m, m/s)
and dhd.getButtonMask on read(), dhd.setForce [N] on servo_cf(). Every call that returns -1 becomes a
DeviceError with dhd.errorGetLastStr(). The SDK is imported in open(): without it, open() fails with one
DeviceUnavailable line.

URL: ``omega://`` (first device) or ``omega://?id=N``.
"""

from __future__ import annotations

import time

import numpy as np

from devices.base import OMEGA_SPEC, ContextDevice, DeviceError, DeviceUnavailable, HapticSample
from devices.guard import guarded_force
from teleop.core.errors import InputError


class OmegaStylus(ContextDevice):
    """A Force Dimension haptic device as a HapticDevice."""

    def __init__(self, device_id: int | None = None):
        self.device_id = device_id
        self.spec = OMEGA_SPEC
        self.is_open = False

    def open(self) -> None:
        try:  # the vendor SDK is optional: loaded when an omega opens
            from forcedimension_core import dhd
        except (ImportError, OSError, RuntimeError) as exc:
            raise DeviceUnavailable(f"omega://: Force Dimension SDK unavailable ({type(exc).__name__}: {exc}); "
                                    "install the SDK and `pip install forcedimension-core`") from None
        self._dhd = dhd
        ID = dhd.open() if self.device_id is None else dhd.openID(self.device_id)
        if ID == -1:
            raise DeviceUnavailable(f"omega://: no Force Dimension device ({dhd.errorGetLastStr()})")
        self.ID = ID
        self._check(dhd.enableForce(True, ID=ID), "enableForce")
        self._pos, self._vel = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
        self._R = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        self.is_open = True

    def _check(self, ret, op: str):
        if ret == -1:
            raise DeviceError(f"omega://: dhd.{op} failed ({self._dhd.errorGetLastStr()})")
        return ret

    def close(self) -> None:
        if not self.is_open:
            return
        try:
            self._dhd.setForce([0.0, 0.0, 0.0], ID=self.ID)
        finally:
            self._dhd.close(self.ID)
            self.is_open = False

    def read(self) -> HapticSample:
        if not self.is_open:
            raise DeviceError("omega://: read() before open()")
        d, ID = self._dhd, self.ID
        self._check(d.getPosition(out=self._pos, ID=ID), "getPosition")
        self._check(d.getLinearVelocity(out=self._vel, ID=ID), "getLinearVelocity")
        self._check(d.getOrientationFrame(out=self._R, ID=ID), "getOrientationFrame")
        buttons = int(d.getButtonMask(ID=ID))
        return HapticSample(t=time.perf_counter(), measured_cp=np.array(self._pos, dtype=float),
                            orientation=np.array(self._R, dtype=float), measured_cv=np.array(self._vel, dtype=float),
                            buttons=buttons & 3, operator_present=bool(buttons & 1))

    def servo_cf(self, force) -> None:
        self._check(self._dhd.setForce(list(guarded_force(self, force, "omega://")), ID=self.ID), "setForce")


def from_url(parsed, options: dict) -> OmegaStylus:
    unknown = set(options) - {"id"}
    if unknown:
        raise InputError(f"omega://: unknown option(s) {', '.join(sorted(unknown))} (expected: id)")
    try:
        device_id = int(options["id"]) if "id" in options else None
    except ValueError:
        raise InputError(f"omega://: id must be an integer, got {options['id']!r}") from None
    return OmegaStylus(device_id)
