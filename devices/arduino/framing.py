"""Link framing: COBS with a 0x00 delimiter around ``payload + CRC-32``; pure functions of bytes.

Wire format of one frame::

    COBS(payload || crc32(payload) as 4 bytes little-endian) || 0x00

CRC-32 is the IEEE 802.3 / zlib one (reflected 0xEDB88320, init and xorout 0xFFFFFFFF); for frames this
short it has Hamming distance 6 and detects every burst up to 32 bits. COBS removes every 0x00 from the
body, so a receiver resynchronises at the next delimiter after any garbage. The stream decoder never
decodes a partial frame, keeps at most ``max_frame`` bytes pending, and reports oversized input.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

DELIMITER = 0x00
CRC_SIZE = 4
MAX_FRAME = 64  # encoded bytes between delimiters the receivers accept (firmware rx buffer is the same)

# Error kinds reported by the decoders (the firmware counts the same ones).
COBS_ERROR = "cobs"          # a COBS code byte points past the end of the frame
SHORT_ERROR = "short"        # decoded frame shorter than one payload byte + CRC
CRC_ERROR = "crc"            # CRC mismatch
OVERFLOW_ERROR = "overflow"  # more than max_frame bytes without a delimiter (discarded up to the next 0x00)
ERROR_KINDS = (COBS_ERROR, SHORT_ERROR, CRC_ERROR, OVERFLOW_ERROR)


class FrameError(ValueError):
    """A frame failed to decode; ``kind`` is one of ERROR_KINDS."""

    def __init__(self, kind: str, message: str):
        super().__init__(message)
        self.kind = kind


def crc32(data: bytes) -> int:
    """CRC-32 (IEEE, as zlib) of `data` -> int in [0, 2**32)."""
    return zlib.crc32(data) & 0xFFFFFFFF


def cobs_encode(data: bytes) -> bytes:
    """COBS-encode `data`: the result holds no 0x00 and is len(data) + 1 bytes for len(data) < 254."""
    out = bytearray()
    for chunk in bytes(data).split(b"\x00"):
        while len(chunk) >= 254:      # code 0xFF: 254 data bytes, no implied zero
            out.append(0xFF)
            out += chunk[:254]
            chunk = chunk[254:]
        out.append(len(chunk) + 1)    # code n: n-1 data bytes then an implied zero (dropped at the end)
        out += chunk
    return bytes(out)


def cobs_decode(encoded: bytes) -> bytes:
    """Invert cobs_encode; raises FrameError(COBS_ERROR) on a zero byte or a code past the end."""
    out = bytearray()
    i, n = 0, len(encoded)
    while i < n:
        code = encoded[i]
        if code == 0:
            raise FrameError(COBS_ERROR, f"zero byte at {i} inside a COBS frame")
        j = i + code
        if j > n:
            raise FrameError(COBS_ERROR, f"COBS code {code} at {i} runs past the frame end ({n} bytes)")
        out += encoded[i + 1:j]
        i = j
        if code < 0xFF and i < n:
            out.append(0)
    return bytes(out)


def encode_frame(payload: bytes) -> bytes:
    """payload -> wire bytes: COBS(payload + CRC-32 LE) + 0x00."""
    body = bytes(payload) + crc32(payload).to_bytes(CRC_SIZE, "little")
    return cobs_encode(body) + b"\x00"


def decode_frame(encoded: bytes) -> bytes:
    """Wire bytes of one frame without its delimiter -> payload; raises FrameError."""
    body = cobs_decode(encoded)
    if len(body) < CRC_SIZE + 1:
        raise FrameError(SHORT_ERROR, f"frame of {len(body)} bytes is shorter than payload + CRC")
    payload, crc = body[:-CRC_SIZE], int.from_bytes(body[-CRC_SIZE:], "little")
    if crc32(payload) != crc:
        raise FrameError(CRC_ERROR, "CRC mismatch")
    return payload


@dataclass(frozen=True)
class DecoderState:
    """Stream decoder state between calls.

    Attributes:
        pending: bytes received after the last delimiter (at most max_frame of them).
        discarding: True while skipping an oversized frame up to its delimiter.
    """

    pending: bytes = b""
    discarding: bool = False


def decode_stream(state: DecoderState, data: bytes,
                  max_frame: int = MAX_FRAME) -> tuple[DecoderState, list[bytes], list[str]]:
    """Feed received bytes: (state, data) -> (new state, payloads of complete valid frames, error kinds).

    Empty frames (two delimiters in a row) are idle fill and ignored. An oversized frame counts one
    OVERFLOW_ERROR when it is detected and is discarded up to its delimiter; pending stays bounded.
    """
    parts = (state.pending + bytes(data)).split(b"\x00")
    tail = parts.pop()
    discarding = state.discarding
    frames: list[bytes] = []
    errors: list[str] = []
    for part in parts:
        if discarding:           # the rest of an oversized frame, already counted
            discarding = False
            continue
        if not part:
            continue
        if len(part) > max_frame:
            errors.append(OVERFLOW_ERROR)
            continue
        try:
            frames.append(decode_frame(part))
        except FrameError as exc:
            errors.append(exc.kind)
    if discarding:
        tail = b""
    elif len(tail) > max_frame:
        errors.append(OVERFLOW_ERROR)
        tail, discarding = b"", True
    return DecoderState(tail, discarding), frames, errors
