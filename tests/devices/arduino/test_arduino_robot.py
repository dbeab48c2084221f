"""ArduinoRobot: the standard Robot conformance sequence over the emulated link, URL parsing, host-side
gap/duplicate/reordering detection."""

from urllib.parse import urlparse

import numpy as np
import pytest

from devices.arduino import messages as msg
from devices.arduino.robot import ArduinoRobot, from_url
from devices.base import DeviceError
from teleop.core.errors import InputError
from teleop.loop.devices_by_url import BACKENDS, open_device

from .conftest import HOME_LENGTHS
from .robot_conformance import check_robot


def test_conformance_sequence_on_the_emulated_firmware(mega):
    check_robot(lambda: ArduinoRobot(mega.port, timeout_s=1.0), prepare=lambda r: r.home(HOME_LENGTHS),
                lengths=HOME_LENGTHS - 0.0005)


def test_project_conformance_check_passes_with_home_lengths_configured(mega):
    """devices.conformance.check_robot (the loop's check) on the serial robot: open() homes at the
    configured lengths, readings' seq is monotonic (unwrapped from the 12-bit link seq)."""
    from devices.conformance import check_robot as project_check_robot

    project_check_robot(ArduinoRobot(mega.port, timeout_s=1.0, home_lengths=HOME_LENGTHS), reads=20)


def test_motion_refused_before_home_and_after_stop(mega):
    with ArduinoRobot(mega.port, timeout_s=1.0) as robot:
        with pytest.raises(DeviceError, match="not homed"):
            robot.command_lengths(HOME_LENGTHS)
        robot.home(HOME_LENGTHS)
        robot.stop()
        with pytest.raises(DeviceError, match="stopped"):
            robot.command_lengths(HOME_LENGTHS)
        robot.enable()
        robot.command_lengths(HOME_LENGTHS)


def test_serial_url_builds_an_unopened_robot_and_rejects_bad_options():
    assert BACKENDS["serial"] == "devices.arduino.robot:from_url"
    robot = open_device("serial:///dev/ttyACM0?baud=1000000")
    assert isinstance(robot, ArduinoRobot) and robot.port == "/dev/ttyACM0" and robot.baud == 1_000_000
    assert not robot.is_open
    with pytest.raises(InputError, match="unknown option"):
        from_url(urlparse("serial:///dev/ttyACM0?bauds=9600"), {"bauds": "9600"})
    with pytest.raises(InputError, match="baud"):
        from_url(urlparse("serial:///dev/ttyACM0?baud=fast"), {"baud": "fast"})
    with pytest.raises(InputError):
        from_url(urlparse("serial://"), {})
    homed = open_device("serial:///dev/ttyACM0?home_mm=30,30,30,30,30,30")
    np.testing.assert_allclose(homed.home_lengths, HOME_LENGTHS)
    with pytest.raises(InputError, match="home"):
        open_device("serial:///dev/ttyACM0?home_mm=30,30")
    with pytest.raises(InputError, match="home_mm"):
        open_device("serial:///dev/ttyACM0?home_mm=a,b")


def test_opening_a_missing_port_is_one_clear_error():
    with pytest.raises(InputError, match="cannot open"):
        ArduinoRobot("/dev/does-not-exist-cdpr").open()


def _telemetry(seq, boot_tag=3):
    return msg.encode(msg.Telemetry(seq, msg.Status.HOMED, seq & 0xFF, (100,) * 6, boot_tag, (0,) * 6))


def test_host_counts_gaps_duplicates_reordering_and_notices_a_new_boot():
    robot = ArduinoRobot("/dev/null")
    robot._on_frames([msg.encode(msg.HelloReply(0, 1, (1, 0, 0), 3, 6, 25, 10000, 2037, 51000, 64))], [], 0.0)
    order = [1, 2, 3, 5, 5, 4, 6, 9, 10]  # 4 missing then late, 5 duplicated, 7 and 8 lost
    robot._on_frames([_telemetry(s) for s in order], ["crc"], 0.1)
    assert (robot.stats.gaps, robot.stats.duplicates, robot.stats.reordered) == (3, 1, 1)
    assert robot.stats.errors == {"crc": 1} and robot._latest.seq == 10
    robot._on_frames([_telemetry(11, boot_tag=4)], [], 0.2)  # boot id changed without a HELLO
    assert robot.reset_detected and robot.stats.resets == 1
    robot._on_frames([b"\x01"], [], 0.3)
    assert robot.stats.errors["malformed"] == 1


def test_bad_settings_rejected_at_construction():
    with pytest.raises(InputError):
        ArduinoRobot("/dev/ttyACM0", baud=0)
    assert np.isfinite(ArduinoRobot("/dev/ttyACM0").spec.steps_per_m)
