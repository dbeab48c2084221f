"""Fakes of the vendor SDK modules, matching the real APIs: pyOpenHaptics (hd, hd_callback, hd_device:
mikelitu/pyOpenHaptics) and forcedimension_core.dhd (EmDash00/forcedimension_core-python). Install with
`install_*(monkeypatch)`; each returns the fake hardware state the test drives."""

from __future__ import annotations

import sys
import threading
import time
import types


class TouchHardware:
    """What the fake Geomagic Touch 'measures' (mm, like OpenHaptics) and the forces it was given."""

    def __init__(self):
        self.pos_mm = [10.0, -20.0, 30.0]
        self.buttons = 1
        self.forces = []
        self.callbacks = 0
        self.fail_init = False


def install_touch(monkeypatch) -> TouchHardware:
    hw = TouchHardware()
    pkg = types.ModuleType("pyOpenHaptics")
    hd = types.ModuleType("pyOpenHaptics.hd")

    def get_transform():
        # column-major 4x4 (OpenGL / HDdouble[16]); rotation about z by 90 deg, translation in row 3
        return [[0.0, 1.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [*hw.pos_mm, 1.0]]

    hd.get_transform = get_transform
    hd.get_buttons = lambda: hw.buttons
    hd.set_force = lambda f: hw.forces.append(list(f))
    hd.get_model = lambda: "Touch (fake)"
    hd.get_vendor = lambda: "3D Systems (fake)"
    cb = types.ModuleType("pyOpenHaptics.hd_callback")
    cb.hd_callback = lambda fn: fn  # the real decorator wraps fn in CFUNCTYPE with begin/end frame
    dev = types.ModuleType("pyOpenHaptics.hd_device")

    class HapticDevice:
        def __init__(self, callback, device_name="Default Device", scheduler_type="async"):
            if hw.fail_init:
                raise RuntimeError("Unable to initialize the device. Check the connection!")
            self.callback, self.running = callback, True
            self.thread = threading.Thread(target=self._servo, daemon=True)
            self.thread.start()

        def _servo(self):
            while self.running:
                self.callback()
                hw.callbacks += 1
                time.sleep(0.001)

        def close(self):
            self.running = False
            self.thread.join()

    dev.HapticDevice = HapticDevice
    pkg.hd, pkg.hd_callback, pkg.hd_device = hd, cb, dev
    for name, mod in (("pyOpenHaptics", pkg), ("pyOpenHaptics.hd", hd), ("pyOpenHaptics.hd_callback", cb),
                      ("pyOpenHaptics.hd_device", dev)):
        monkeypatch.setitem(sys.modules, name, mod)
    return hw


class OmegaHardware:
    def __init__(self):
        self.pos = [0.01, 0.02, -0.03]
        self.vel = [0.1, 0.0, 0.0]
        self.R = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        self.buttons = 1
        self.forces = []
        self.present = True
        self.fail_set_force = False
        self.force_enabled = False
        self.closed = []


def install_omega(monkeypatch) -> OmegaHardware:
    hw = OmegaHardware()
    pkg = types.ModuleType("forcedimension_core")
    dhd = types.ModuleType("forcedimension_core.dhd")
    err = {"s": "no error"}

    def open_():
        if not hw.present:
            err["s"] = "no device found"
            return -1
        return 0

    def fill(out, src):
        for i, v in enumerate(src):
            if isinstance(v, list):
                out[i][:] = v
            else:
                out[i] = v
        return 0

    def set_force(f, ID=-1):
        if hw.fail_set_force:
            err["s"] = "communication error"
            return -1
        hw.forces.append(list(f))
        return 0

    def enable_force(enable, ID=-1):
        hw.force_enabled = bool(enable)
        return 0

    dhd.open = open_
    dhd.openID = lambda index: open_()
    dhd.close = lambda ID=-1: hw.closed.append(ID) or 0
    dhd.enableForce = enable_force
    dhd.getPosition = lambda out, ID=-1: fill(out, hw.pos)
    dhd.getLinearVelocity = lambda out, ID=-1: fill(out, hw.vel)
    dhd.getOrientationFrame = lambda out, ID=-1: fill(out, hw.R)
    dhd.getButtonMask = lambda ID=-1: hw.buttons
    dhd.setForce = set_force
    dhd.errorGetLastStr = lambda: err["s"]
    pkg.dhd = dhd
    monkeypatch.setitem(sys.modules, "forcedimension_core", pkg)
    monkeypatch.setitem(sys.modules, "forcedimension_core.dhd", dhd)
    return hw
