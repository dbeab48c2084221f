"""One conformance check over every HapticDevice and Robot implementation (devices.conformance)."""

import importlib.util

import numpy as np
import pytest
from tests.devices._fake_sdks import install_omega, install_touch
from tests.devices._fakes import FakeRobot, record_session

from devices.conformance import ConformanceError, check_haptic, check_robot
from devices.replay import ReplayRobot, ReplayStylus
from devices.simulated import SimulatedStylus
from devices.wrappers import DelayedRobot, LoggedDevice, NoisyStylus
from teleop.loop.devices_by_url import open_device, process_robot


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("rec") / "s.mcap"
    record_session(path, ticks=60)
    return str(path)


HAPTICS = ["sim", "sim_omega_spec", "replay", "touch", "omega", "noisy"]


@pytest.mark.parametrize("kind", HAPTICS)
def test_haptic_conformance(kind, recording, monkeypatch):
    if kind == "sim":
        dev = open_device("sim://?script=sine")
    elif kind == "sim_omega_spec":
        dev = open_device("sim://?script=pokes&spec=omega&clutch=0-1")
    elif kind == "replay":
        dev = ReplayStylus(recording)
    elif kind == "touch":
        install_touch(monkeypatch)
        dev = open_device("touch://")
    elif kind == "omega":
        install_omega(monkeypatch)
        dev = open_device("omega://")
    else:
        dev = NoisyStylus(SimulatedStylus(), 1e-4, seed=1)
    check_haptic(dev)


ROBOTS = ["fake", "replay", "delayed", "logged"]
if importlib.util.find_spec("scenes.sim_robot") is not None:
    ROBOTS += ["sim_robot", "process_sim_robot"]


@pytest.mark.parametrize("kind", ROBOTS)
def test_robot_conformance(kind, recording):
    robot = {"fake": lambda: FakeRobot(), "replay": lambda: ReplayRobot(recording),
             "delayed": lambda: DelayedRobot(FakeRobot(), 3), "logged": lambda: LoggedDevice(FakeRobot()),
             "sim_robot": lambda: open_device("sim://robot"),
             "process_sim_robot": lambda: process_robot("sim://robot", rate_hz=500.0)}[kind]()
    check_robot(robot)


def test_conformance_catches_broken_devices():
    class OpensInInit(SimulatedStylus):
        def __init__(self):
            super().__init__()
            self.open()

    with pytest.raises(ConformanceError, match="__init__ must not open"):
        check_haptic(OpensInInit())

    class NanStylus(SimulatedStylus):
        def read(self):
            s = super().read()
            s.measured_cp[1] = np.nan
            return s

    with pytest.raises(ConformanceError, match="measured_cp"):
        check_haptic(NanStylus())

    class AcceptsNan(FakeRobot):
        def command_lengths(self, lengths):
            self.L = np.asarray(lengths, dtype=float)

    with pytest.raises(ConformanceError, match="NaN"):
        check_robot(AcceptsNan())


def test_delayed_robot_delays_and_logged_records():
    r = DelayedRobot(FakeRobot(), 2)
    with r:
        seqs = [r.read().seq for _ in range(5)]
    assert seqs == [1, 1, 1, 2, 3]
    lg = LoggedDevice(FakeRobot())
    with lg:
        lg.read()
        lg.command_lengths(np.full(6, 0.025))
        lg.stop()
    assert [k for k, _ in lg.log] == ["read", "command_lengths", "stop"]
