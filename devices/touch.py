"""`touch://`: Geomagic Touch (3D Systems) through pyOpenHaptics (OpenHaptics HD API).

pyOpenHaptics runs a servo callback in the OpenHaptics scheduler thread (1 kHz, between hdBeginFrame and
hdEndFrame): it reads HD_CURRENT_TRANSFORM (column-major 4x4, translation in mm) and HD_CURRENT_BUTTONS and
sets HD_CURRENT_FORCE [N]. This adapter's callback publishes the latest state (one tuple assignment, atomic
under the GIL) and applies the latest commanded force; `read()` and `servo_cf()` only swap tuples, so the
teleoperation loop never waits on the device. The SDK is imported in open(): without it (or without
libHD.so) open() fails with one DeviceUnavailable line.

URL: ``touch://`` or ``touch://?name=Default%20Device``.
"""

from __future__ import annotations

import time

import numpy as np

from devices.base import TOUCH_SPEC, ContextDevice, DeviceError, DeviceUnavailable, HapticSample
from devices.guard import guarded_force
from teleop.core.errors import InputError

MM = 1e-3


class TouchStylus(ContextDevice):
    """Geomagic Touch as a HapticDevice (positions in m, forces in N, frame of the device)."""

    def __init__(self, name: str = "Default Device", first_sample_timeout: float = 1.0):
        self.name = str(name)
        self.timeout = float(first_sample_timeout)
        self.spec = TOUCH_SPEC
        self.is_open = False
        self._state = None
        self._force = (0.0, 0.0, 0.0)

    def open(self) -> None:
        try:  # the vendor SDK is optional: loaded when a Touch opens
            import pyOpenHaptics.hd as hd
            from pyOpenHaptics.hd_callback import hd_callback
            from pyOpenHaptics.hd_device import HapticDevice as HdDevice
        except (ImportError, OSError) as exc:
            raise DeviceUnavailable(f"touch://: Geomagic Touch SDK unavailable ({type(exc).__name__}: {exc}); "
                                    "install OpenHaptics and `pip install pyOpenHaptics`") from None
        self._hd = hd
        self._state = None
        self._force = (0.0, 0.0, 0.0)
        prev = {"t": None, "p": None}

        def servo():
            T = hd.get_transform()
            t = time.perf_counter()
            p = (T[3][0] * MM, T[3][1] * MM, T[3][2] * MM)
            R = tuple(T[j][i] for i in range(3) for j in range(3))  # column-major -> row-major rotation
            v = (0.0, 0.0, 0.0)
            if prev["t"] is not None and t > prev["t"]:
                dt = t - prev["t"]
                v = tuple((a - b) / dt for a, b in zip(p, prev["p"]))
            prev["t"], prev["p"] = t, p
            self._state = (t, p, R, v, int(hd.get_buttons()))
            hd.set_force(list(self._force))

        self._callback = hd_callback(servo)  # keep a reference: the scheduler holds only a C pointer
        try:
            self._dev = HdDevice(callback=self._callback, device_name=self.name, scheduler_type="async")
        except Exception as exc:  # noqa: BLE001 - the SDK raises its own exception types
            raise DeviceUnavailable(f"touch://: cannot open '{self.name}' ({type(exc).__name__}: {exc})") from None
        deadline = time.monotonic() + self.timeout
        while self._state is None and time.monotonic() < deadline:
            time.sleep(0.001)
        if self._state is None:
            self._dev.close()
            raise DeviceError(f"touch://: no servo callback within {self.timeout:g} s")
        self.is_open = True

    def close(self) -> None:
        if not self.is_open:
            return
        self._force = (0.0, 0.0, 0.0)
        time.sleep(0.003)  # let the scheduler apply zero force before it stops
        self._dev.close()
        self.is_open = False

    def read(self) -> HapticSample:
        if not self.is_open:
            raise DeviceError("touch://: read() before open()")
        t, p, R, v, buttons = self._state
        # Touch buttons: bit 0 dark grey (used as deadman/enable), bit 1 light grey (clutch)
        return HapticSample(t=t, measured_cp=np.array(p), orientation=np.array(R).reshape(3, 3),
                            measured_cv=np.array(v), buttons=buttons & 3, operator_present=bool(buttons & 1))

    def servo_cf(self, force) -> None:
        self._force = guarded_force(self, force, "touch://")


def from_url(parsed, options: dict) -> TouchStylus:
    unknown = set(options) - {"name"}
    if unknown:
        raise InputError(f"touch://: unknown option(s) {', '.join(sorted(unknown))} (expected: name)")
    return TouchStylus(name=str(options.get("name", "Default Device")))
