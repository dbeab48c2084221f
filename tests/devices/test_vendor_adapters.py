"""touch:// and omega:// adapters against fakes of pyOpenHaptics and forcedimension_core (same API)."""

import sys

import numpy as np
import pytest
from tests.devices._fake_sdks import install_omega, install_touch

from devices.base import DeviceError, DeviceUnavailable
from teleop.apps.cli import main
from teleop.loop.devices_by_url import open_device


def test_touch_missing_sdk_is_one_clear_line(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "pyOpenHaptics", None)
    monkeypatch.setitem(sys.modules, "pyOpenHaptics.hd", None)
    dev = open_device("touch://")  # building does not touch the SDK
    with pytest.raises(DeviceUnavailable, match="Geomagic Touch SDK unavailable"):
        dev.open()
    assert main(["session", "--haptic", "touch://", "--robot", "sim://robot", "--seconds", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "teleop: error: touch://" in err


def test_touch_reads_si_units_and_applies_forces(monkeypatch):
    hw = install_touch(monkeypatch)
    with open_device("touch://") as dev:
        s = dev.read()
        assert np.allclose(s.measured_cp, [0.010, -0.020, 0.030])  # mm -> m
        assert np.allclose(s.orientation, [[0, -1, 0], [1, 0, 0], [0, 0, 1]])  # column-major transform
        assert s.operator_present and s.buttons == 1
        dev.servo_cf([0.1, 0.2, -0.3])
        n = hw.callbacks
        while hw.callbacks < n + 3:
            pass
        assert hw.forces[-1] == [0.1, 0.2, -0.3]
        dev.servo_cf([100.0, 0.0, 0.0])
        n = hw.callbacks
        while hw.callbacks < n + 3:
            pass
        assert np.linalg.norm(hw.forces[-1]) == pytest.approx(dev.spec.max_force_peak)
        dev.servo_cf([np.nan, 0.0, 0.0])
        hw.buttons = 2
        n = hw.callbacks
        while hw.callbacks < n + 3:
            pass
        assert hw.forces[-1] == [0.0, 0.0, 0.0]
        s = dev.read()
        assert not s.operator_present and s.buttons == 2
    assert hw.forces[-1] == [0.0, 0.0, 0.0]


def test_touch_init_failure(monkeypatch):
    hw = install_touch(monkeypatch)
    hw.fail_init = True
    with pytest.raises(DeviceUnavailable, match="cannot open"):
        open_device("touch://?name=Left").open()


def test_omega_missing_sdk_and_missing_device(monkeypatch):
    monkeypatch.setitem(sys.modules, "forcedimension_core", None)
    with pytest.raises(DeviceUnavailable, match="Force Dimension SDK unavailable"):
        open_device("omega://").open()
    hw = install_omega(monkeypatch)
    hw.present = False
    with pytest.raises(DeviceUnavailable, match="no Force Dimension device \\(no device found\\)"):
        open_device("omega://?id=1").open()


def test_omega_reads_and_forces_and_errors(monkeypatch):
    hw = install_omega(monkeypatch)
    with open_device("omega://") as dev:
        assert hw.force_enabled
        s = dev.read()
        assert np.allclose(s.measured_cp, hw.pos) and np.allclose(s.measured_cv, hw.vel)
        assert np.allclose(s.orientation, np.eye(3)) and s.operator_present
        dev.servo_cf([1.0, 2.0, 3.0])
        assert hw.forces[-1] == [1.0, 2.0, 3.0]
        dev.servo_cf([1e6, 0.0, 0.0])
        assert hw.forces[-1][0] == pytest.approx(dev.spec.max_force_peak)
        hw.fail_set_force = True
        with pytest.raises(DeviceError, match="setForce failed \\(communication error\\)"):
            dev.servo_cf([0.0, 0.0, 0.0])
        hw.fail_set_force = False
    assert hw.closed == [0] and hw.forces[-1] == [0.0, 0.0, 0.0]


def test_bad_options_are_input_errors():
    from teleop.core.errors import InputError

    for url in ("touch://?speed=2", "omega://?id=x", "omega://?foo=1"):
        with pytest.raises(InputError):
            open_device(url)
