"""Link messages: frame payloads <-> dataclasses, and the SI <-> steps conversions of this edge.

Every payload starts with a little-endian u16 header ``type << 12 | seq`` (12-bit sequence number, one
counter per direction). The layouts mirror ``firmware/protocol.h`` (a test checks the constants agree).

Host -> firmware: HELLO, HOME (6 x i16 positions to declare), COMMAND (6 x i16 target steps), STOP,
ENABLE, HEARTBEAT, DIAG. Firmware -> host: HELLO_REPLY (boot id, versions, limits), TELEMETRY (answers
every other host frame: status, the low byte of the answered seq, six 10-bit ADC counts packed with a
4-bit boot tag, six i16 step positions), DIAG_REPLY (clock, error counters). Sizes are chosen so that a
COMMAND plus a TELEMETRY frame fit in 50 % of a 1 ms period at 1 Mbaud (see ``wire_size``).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from devices.arduino.framing import CRC_SIZE
from teleop.core.robot_status import RobotStatus

PROTOCOL_VERSION = 1
N_CHANNELS = 6
SEQ_BITS = 12
SEQ_MOD = 1 << SEQ_BITS
STEP_LIMIT = 32000  # |position| and |target| bound in steps (i16 with margin for overshoot)


class MsgType(IntEnum):
    HELLO = 1
    HOME = 2
    COMMAND = 3
    STOP = 4
    ENABLE = 5
    HEARTBEAT = 6
    DIAG = 7
    HELLO_REPLY = 8
    TELEMETRY = 9
    DIAG_REPLY = 10


Status = RobotStatus  # bits of the firmware status byte: one definition in teleop.core.robot_status


class MessageError(ValueError):
    """A CRC-valid payload whose type or length is wrong."""


def seq_diff(new: int, old: int) -> int:
    """Signed modular difference new - old of 12-bit sequence numbers, in [-2048, 2047]."""
    return ((new - old + SEQ_MOD // 2) % SEQ_MOD) - SEQ_MOD // 2


def classify_seq(last: int | None, seq: int) -> tuple[str, int]:
    """Received seq vs the last one -> (kind, missing): "first", "next", "gap" (missing > 0 frames lost),
    "duplicate" or "old" (reordered / replayed)."""
    if last is None:
        return "first", 0
    d = seq_diff(seq, last)
    if d == 1:
        return "next", 0
    if d > 1:
        return "gap", d - 1
    return ("duplicate", 0) if d == 0 else ("old", 0)


def _header(msg_type: int, seq: int) -> bytes:
    return struct.pack("<H", (int(msg_type) << SEQ_BITS) | (seq % SEQ_MOD))


@dataclass(frozen=True)
class Hello:
    seq: int


@dataclass(frozen=True)
class Home:
    """Declare the current motor positions [steps] (usually zeros); marks the firmware homed."""

    seq: int
    position_steps: tuple = (0,) * N_CHANNELS


@dataclass(frozen=True)
class Command:
    """Move to target motor positions [steps], rate- and acceleration-limited by the firmware."""

    seq: int
    target_steps: tuple


@dataclass(frozen=True)
class Stop:
    seq: int


@dataclass(frozen=True)
class Enable:
    """Clear the STOP and watchdog latches (motion resumes from where the motors are)."""

    seq: int


@dataclass(frozen=True)
class Heartbeat:
    seq: int


@dataclass(frozen=True)
class DiagRequest:
    seq: int


@dataclass(frozen=True)
class HelloReply:
    seq: int
    protocol: int
    firmware_version: tuple
    boot_id: int
    n_channels: int
    watchdog_ms: int
    tick_hz: int
    v_max_steps_per_s: int
    accel_steps_per_s2: int
    rx_buffer: int

    @property
    def version_string(self) -> str:
        return ".".join(str(v) for v in self.firmware_version)


@dataclass(frozen=True)
class Telemetry:
    """Answer to one host frame: status byte, low 8 bits of the answered seq, raw sensors, positions.

    Attributes:
        adc_counts: (6,) FSR ADC readings [counts, 0..1023].
        boot_tag: low 4 bits of the firmware boot id.
        position_steps: (6,) motor positions [steps] since home (positive = cable hauled in).
    """

    seq: int
    status: int
    reply_to: int
    adc_counts: tuple
    boot_tag: int
    position_steps: tuple


DIAG_COUNTERS = ("crc", "cobs", "short", "overflow", "malformed", "stale", "rejected", "watchdog_trips",
                 "rx_frames", "tx_dropped", "rx_busy")


@dataclass(frozen=True)
class DiagReply:
    """Firmware clock and error counters (u16, saturating).

    Attributes:
        micros: firmware clock [us] (wraps at 2**32).
        last_seq: last accepted host sequence number.
        handle_max_us: longest handling of one frame since boot [us].
        counters: DIAG_COUNTERS name -> count.
    """

    seq: int
    micros: int
    last_seq: int
    status: int
    handle_max_us: int
    counters: dict = field(default_factory=dict)


_EMPTY = {MsgType.HELLO: Hello, MsgType.STOP: Stop, MsgType.ENABLE: Enable,
          MsgType.HEARTBEAT: Heartbeat, MsgType.DIAG: DiagRequest}
_STEPS = struct.Struct("<6h")
_HELLO_REPLY = struct.Struct("<B3BHBBHHIB")
_TELEMETRY = struct.Struct("<BBQ6h")
_DIAG_REPLY = struct.Struct("<IHBH11H")
PAYLOAD_SIZES = {MsgType.HELLO: 0, MsgType.HOME: 12, MsgType.COMMAND: 12, MsgType.STOP: 0,
                 MsgType.ENABLE: 0, MsgType.HEARTBEAT: 0, MsgType.DIAG: 0,
                 MsgType.HELLO_REPLY: _HELLO_REPLY.size, MsgType.TELEMETRY: _TELEMETRY.size,
                 MsgType.DIAG_REPLY: _DIAG_REPLY.size}


def _steps(values) -> tuple:
    steps = tuple(int(v) for v in values)
    if len(steps) != N_CHANNELS or any(abs(s) > STEP_LIMIT for s in steps):
        raise ValueError(f"expected {N_CHANNELS} step values within +-{STEP_LIMIT}, got {values!r}")
    return steps


def pack_adc(adc_counts, boot_tag: int) -> int:
    """Six 10-bit counts (channel i at bits 10i) and a 4-bit boot tag (bits 60-63) -> u64."""
    word = (int(boot_tag) & 0xF) << 60
    for i, c in enumerate(adc_counts):
        word |= (int(c) & 0x3FF) << (10 * i)
    return word


def unpack_adc(word: int) -> tuple[tuple, int]:
    """Inverse of pack_adc -> ((6,) counts, boot tag)."""
    return tuple((word >> (10 * i)) & 0x3FF for i in range(N_CHANNELS)), (word >> 60) & 0xF


def encode(msg) -> bytes:
    """Message dataclass -> frame payload (header + body, without CRC)."""
    if isinstance(msg, (Hello, Stop, Enable, Heartbeat, DiagRequest)):
        kind = next(k for k, cls in _EMPTY.items() if isinstance(msg, cls))
        return _header(kind, msg.seq)
    if isinstance(msg, Home):
        return _header(MsgType.HOME, msg.seq) + _STEPS.pack(*_steps(msg.position_steps))
    if isinstance(msg, Command):
        return _header(MsgType.COMMAND, msg.seq) + _STEPS.pack(*_steps(msg.target_steps))
    if isinstance(msg, HelloReply):
        return _header(MsgType.HELLO_REPLY, msg.seq) + _HELLO_REPLY.pack(
            msg.protocol, *msg.firmware_version, msg.boot_id, msg.n_channels, msg.watchdog_ms, msg.tick_hz,
            msg.v_max_steps_per_s, msg.accel_steps_per_s2, msg.rx_buffer)
    if isinstance(msg, Telemetry):
        return _header(MsgType.TELEMETRY, msg.seq) + _TELEMETRY.pack(
            msg.status, msg.reply_to, pack_adc(msg.adc_counts, msg.boot_tag), *_steps(msg.position_steps))
    if isinstance(msg, DiagReply):
        return _header(MsgType.DIAG_REPLY, msg.seq) + _DIAG_REPLY.pack(
            msg.micros, msg.last_seq, msg.status, msg.handle_max_us, *(msg.counters[k] for k in DIAG_COUNTERS))
    raise TypeError(f"not a link message: {msg!r}")


def decode(payload: bytes):
    """Frame payload -> message dataclass; raises MessageError for an unknown type or a wrong length."""
    if len(payload) < 2:
        raise MessageError(f"payload of {len(payload)} bytes has no header")
    (header,) = struct.unpack_from("<H", payload)
    seq, code = header & (SEQ_MOD - 1), header >> SEQ_BITS
    try:
        kind = MsgType(code)
    except ValueError:
        raise MessageError(f"unknown message type {code}") from None
    body = payload[2:]
    if len(body) != PAYLOAD_SIZES[kind]:
        raise MessageError(f"{kind.name}: expected {PAYLOAD_SIZES[kind]} payload bytes, got {len(body)}")
    if kind in _EMPTY:
        return _EMPTY[kind](seq)
    if kind is MsgType.HOME:
        return Home(seq, _STEPS.unpack(body))
    if kind is MsgType.COMMAND:
        return Command(seq, _STEPS.unpack(body))
    if kind is MsgType.HELLO_REPLY:
        v = _HELLO_REPLY.unpack(body)
        return HelloReply(seq, v[0], tuple(v[1:4]), *v[4:])
    if kind is MsgType.TELEMETRY:
        status, reply_to, word, *pos = _TELEMETRY.unpack(body)
        adc, tag = unpack_adc(word)
        return Telemetry(seq, status, reply_to, adc, tag, tuple(pos))
    v = _DIAG_REPLY.unpack(body)
    return DiagReply(seq, v[0], v[1], v[2], v[3], dict(zip(DIAG_COUNTERS, v[4:])))


def wire_size(kind: MsgType) -> int:
    """Bytes on the wire of one frame of `kind` (payload < 254 bytes: one COBS byte + delimiter)."""
    return 2 + PAYLOAD_SIZES[kind] + CRC_SIZE + 2


def lengths2steps(lengths, home_lengths, steps_per_m: float) -> np.ndarray:
    """Cable lengths (6,) [m] -> motor targets (6,) [steps]; hauling in (shorter cable) is positive."""
    return np.rint((np.asarray(home_lengths, float) - np.asarray(lengths, float)) * steps_per_m).astype(int)


def steps2lengths(steps, home_lengths, steps_per_m: float) -> np.ndarray:
    """Motor positions (6,) [steps] -> cable lengths (6,) [m] (inverse of lengths2steps)."""
    return np.asarray(home_lengths, float) - np.asarray(steps, float) / steps_per_m
