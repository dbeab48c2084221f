"""A lab geometry's limits reach the serial robot: its length range and cable speed (devices.arduino.robot.spec_for)
through open_device(url, geometry=...), the speed checked against the firmware's HELLO_REPLY, the length range
against the firmware's step range; no emulator needed."""

import numpy as np
import pytest

from devices.arduino import messages as msg
from devices.arduino.robot import ArduinoRobot, check_speed_limit, spec_for
from devices.base import RobotSpec
from teleop.core.errors import InputError
from teleop.core.geometry import default_geometry
from teleop.loop.devices_by_url import open_device


def hello(v_max_steps_per_s: int) -> msg.HelloReply:
    return msg.HelloReply(seq=1, protocol=msg.PROTOCOL_VERSION, firmware_version=(1, 0, 0), boot_id=1, n_channels=6,
                          watchdog_ms=25, tick_hz=10000, v_max_steps_per_s=v_max_steps_per_s,
                          accel_steps_per_s2=51000, rx_buffer=64)


def test_geometry_sets_the_serial_robots_length_and_speed_limits():
    lab = default_geometry().replace(l_min=0.010, l_max=0.050, v_max=0.012)
    robot = open_device("serial:///dev/ttyACM0", geometry=lab)
    assert (robot.spec.l_min, robot.spec.l_max, robot.spec.v_max) == (0.010, 0.050, 0.012)
    assert open_device("serial:///dev/ttyACM0").spec == RobotSpec()  # no geometry: the seed robot's limits
    with pytest.raises(ValueError, match="outside"):  # a length the lab geometry forbids is refused on the host
        robot._check_lengths(np.full(6, 0.055))
    with pytest.raises(InputError, match="--geometry"):
        open_device("serial:///dev/ttyACM0?geometry=lab.toml")


def test_speed_faster_than_the_firmware_and_a_range_beyond_its_steps_are_refused():
    firmware = hello(2037)  # V_MAX_STEPS of firmware/protocol.h: 20 mm/s
    check_speed_limit(spec_for(default_geometry()), firmware, "/dev/x")  # the seed robot's 20 mm/s fits
    with pytest.raises(InputError, match="v_max_mm_s 30 is faster than the firmware's 20 mm/s"):
        check_speed_limit(spec_for(default_geometry().replace(v_max=0.030)), firmware, "/dev/x")
    with pytest.raises(InputError, match="l_min_mm..l_max_mm"):
        ArduinoRobot("/dev/x", spec=spec_for(default_geometry().replace(l_min=0.005, l_max=0.400)))


def test_a_stylus_url_takes_no_geometry():
    with pytest.raises(InputError, match="geometry applies to a robot"):
        open_device("sim://", geometry=default_geometry())
