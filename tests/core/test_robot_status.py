"""The status byte defined once: the host messages use it, and a host STOP is named as such."""

from devices.arduino import messages as msg
from teleop.core.robot_status import RobotStatus, robot_status, stop_reason


def test_host_messages_use_the_one_definition():
    assert msg.Status is RobotStatus
    assert RobotStatus.STOPPED == 4 and RobotStatus.WATCHDOG_STOP == 2 and RobotStatus.HOMED == 1


def test_a_host_stop_is_not_reported_as_a_watchdog_or_firmware_fault():
    stopped = robot_status(homed=True, stopped=True)
    assert stopped == 0b101
    assert "host STOP" in stop_reason(stopped) and "watchdog" not in stop_reason(stopped)
    assert "watchdog" in stop_reason(robot_status(homed=True, watchdog_stop=True))
    assert stop_reason(robot_status(homed=True, moving=True)) == ""
