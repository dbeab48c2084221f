"""The robot's status byte: the one definition of its bits, shared by the firmware header
(devices/arduino/firmware/protocol.h: tests hold its STATUS_* defines equal to these), the host messages
(devices.arduino.messages.Status is this class), the simulated robot and the loop.
"""

from __future__ import annotations

from enum import IntFlag


class RobotStatus(IntFlag):
    """Bits of RobotReading.status (the firmware's status byte)."""

    HOMED = 1 << 0
    WATCHDOG_STOP = 1 << 1  # the firmware stopped the steppers: the host went silent
    STOPPED = 1 << 2        # the host STOP latch (a stop the host asked for)
    MOVING = 1 << 3
    REJECTED = 1 << 4       # the answered host frame was refused (stale seq, not homed, latched, range)
    LINK_ERRORS = 1 << 5    # an error counter changed since the last DIAG


def robot_status(homed: bool = False, watchdog_stop: bool = False, stopped: bool = False,
                 moving: bool = False) -> int:
    """The status byte with these bits set."""
    return int((RobotStatus.HOMED if homed else 0) | (RobotStatus.WATCHDOG_STOP if watchdog_stop else 0)
               | (RobotStatus.STOPPED if stopped else 0) | (RobotStatus.MOVING if moving else 0))


def stop_reason(status: int) -> str:
    """Why a robot with this status byte is not moving ('' when neither stop bit is set)."""
    s = RobotStatus(int(status) & 0x3F)
    if s & RobotStatus.WATCHDOG_STOP:
        return "firmware watchdog stop (host silent)"
    if s & RobotStatus.STOPPED:
        return "stopped by a host STOP"
    return ""
