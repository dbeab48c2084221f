"""Session fixtures: build the firmware and the simavr harness once, run one emulated Mega2560.

The toolchain (gcc-avr, avr-libc, arduino-core-avr, libsimavr-dev, libelf-dev) is required: a missing
piece fails the simavr tests with one line naming the packages (scripts/install-system-deps.sh).
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from devices.arduino import build
from devices.arduino import framing
from devices.arduino import messages as msg
from devices.arduino.robot import ArduinoRobot
from devices.arduino.simulator import EmulatedMega

HOME_LENGTHS = np.full(6, 0.030)  # [m]


@pytest.fixture(scope="session")
def arduino_build(tmp_path_factory):
    """(firmware .elf, harness executable), built once per session outside the source tree."""
    try:
        build.check_toolchain()
    except build.ToolchainMissing as exc:
        pytest.fail(f"Arduino/simavr toolchain: {exc}", pytrace=False)
    out = tmp_path_factory.mktemp("arduino-build")
    return build.build_firmware(out), build.build_harness(out)


@pytest.fixture(scope="package")
def mega(arduino_build):
    """One emulated Mega2560 running the firmware for this directory's tests, stopped after them: a running
    emulator keeps taking CPU (it paces the firmware against the wall clock, waking every 50 us of emulated
    time) from the rest of the suite."""
    elf, harness = arduino_build
    with EmulatedMega(harness, elf) as emulated:
        yield emulated


@pytest.fixture
def robot(mega):
    """An opened ArduinoRobot on the emulator's pty, homed at HOME_LENGTHS; closed afterwards."""
    r = ArduinoRobot(mega.port, timeout_s=1.0)
    with r:
        r.home(HOME_LENGTHS)
        yield r


class RawLink:
    """Byte-level client for the firmware: send raw bytes or messages, collect decoded replies."""

    def __init__(self, port: str):
        import serial

        self.serial = serial.Serial(port, 1_000_000, timeout=0.01)
        self.serial.reset_input_buffer()
        deadline = time.monotonic() + 0.1  # drop what is still on its way from a previous test's frames
        while self.serial.read(4096) and time.monotonic() < deadline:
            pass
        self.state = framing.DecoderState()
        self.seq = 0
        self.errors: list[str] = []

    def close(self) -> None:
        self.serial.close()

    def next_seq(self) -> int:
        self.seq = (self.seq + 1) % msg.SEQ_MOD
        return self.seq

    def write(self, data: bytes) -> None:
        self.serial.write(data)

    def send(self, message) -> None:
        self.write(framing.encode_frame(msg.encode(message)))

    def receive(self, timeout: float = 0.5, count: int = 1) -> list:
        """Messages received until `count` arrived or `timeout` [s] passed."""
        out: list = []
        deadline = time.monotonic() + timeout
        while len(out) < count and time.monotonic() < deadline:
            data = self.serial.read(max(1, self.serial.in_waiting))
            self.state, payloads, errors = framing.decode_stream(self.state, data)
            self.errors += errors
            out += [msg.decode(p) for p in payloads]
        return out

    @staticmethod
    def answers(reply, message) -> bool:
        """Whether `reply` can be the firmware's answer to `message` (telemetry names the frame it answers)."""
        if isinstance(reply, msg.Telemetry):
            return reply.reply_to == message.seq & 0xFF
        if isinstance(reply, msg.HelloReply):
            return isinstance(message, msg.Hello)
        if isinstance(reply, msg.DiagReply):
            return isinstance(message, msg.DiagRequest)
        return True

    def exchange(self, message, timeout: float = 1.0):
        """Send one message and return its reply, skipping late replies to earlier frames (a reply still on
        its way from a previous test, or a retransmission's second answer); fails the test when none arrives."""
        self.send(message)
        deadline = time.monotonic() + timeout
        while True:
            replies = self.receive(max(0.0, deadline - time.monotonic()))
            assert replies, f"no reply to {message!r} within {timeout} s"
            for r in replies:
                if self.answers(r, message):
                    return r

    def diag(self) -> msg.DiagReply:
        self.send(msg.DiagRequest(self.next_seq()))
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline:
            for reply in self.receive(0.2):
                if isinstance(reply, msg.DiagReply):
                    return reply
        raise AssertionError("no DIAG reply")


@pytest.fixture
def raw(mega):
    """A RawLink that has said HELLO (fresh sequence window) and homed the firmware at steps 0."""
    link = RawLink(mega.port)
    try:
        hello = link.exchange(msg.Hello(link.next_seq()))
        assert isinstance(hello, msg.HelloReply)
        link.hello = hello
        home = link.exchange(msg.Home(link.next_seq(), (0,) * 6))
        assert home.status & msg.Status.HOMED
        yield link
    finally:
        link.close()
