"""Host framing (COBS + CRC-32): round trips, split delivery, >= 10^5 corrupted frames, resync, bounds."""

import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devices.arduino import framing
from devices.arduino.framing import (CRC_ERROR, MAX_FRAME, DecoderState, cobs_decode, cobs_encode,
                                     decode_frame, decode_stream, encode_frame)

N_CORRUPT = 100_000


def feed(chunks, max_frame=MAX_FRAME):
    """Run the stream decoder over chunks -> (frames, errors, final state)."""
    state, frames, errors = DecoderState(), [], []
    for chunk in chunks:
        state, f, e = decode_stream(state, chunk, max_frame)
        frames += f
        errors += e
    return frames, errors, state


def test_crc_is_zlib_crc32_with_known_check_value():
    assert framing.crc32(b"123456789") == 0xCBF43926 == zlib.crc32(b"123456789")


@pytest.mark.parametrize("payload", [
    b"", b"\x00", b"\x00" * 300, b"\x01" * 253, b"\x01" * 254, b"\x01" * 255, b"\xff" * 508,
    bytes(range(256)) * 3, b"\x11\x00" * 200,
])
def test_cobs_worst_case_stuffing_round_trip(payload):
    encoded = cobs_encode(payload)
    assert b"\x00" not in encoded
    assert cobs_decode(encoded) == payload
    # overhead: one byte per started 254-byte run, as COBS promises
    assert len(encoded) <= len(payload) + 1 + len(payload) // 254


@settings(max_examples=60)
@given(st.binary(min_size=1, max_size=300))
def test_frame_round_trip_random_payloads(payload):
    wire = encode_frame(payload)
    assert wire.endswith(b"\x00") and wire.count(0) == 1
    assert decode_frame(wire[:-1]) == payload


@settings(max_examples=40)
@given(st.lists(st.one_of(st.binary(min_size=1, max_size=40),
                          st.integers(1, 40).map(lambda n: b"\x00" * n)), min_size=1, max_size=6))
def test_split_at_every_byte_boundary_decodes_exactly_and_never_partially(payloads):
    stream = b"".join(encode_frame(p) for p in payloads)
    for k in range(len(stream) + 1):
        state, first, errors1 = decode_stream(DecoderState(), stream[:k])
        # only complete frames come out of a prefix: one per delimiter seen
        assert first == payloads[:stream[:k].count(0)]
        state, second, errors2 = decode_stream(state, stream[k:])
        assert first + second == payloads and not errors1 and not errors2
    frames, errors, _ = feed([stream[i:i + 1] for i in range(len(stream))])  # byte by byte
    assert frames == payloads and not errors


def _random_payloads(rng, n, lo=2, hi=26):
    lengths = rng.integers(lo, hi + 1, n)
    data = rng.integers(0, 256, int(lengths.sum()), dtype=np.uint8).tobytes()
    ends = np.cumsum(lengths)
    return [data[e - n_:e] for e, n_ in zip(ends, lengths)]


def _distinct_positions(rng, sizes):
    """(n, 3) positions, distinct within each row, each in [0, size); plus how many to use (1-3)."""
    sizes = np.asarray(sizes)
    d1 = 1 + (rng.random(len(sizes)) * (sizes - 2)).astype(int)          # 1 .. size-2
    d2 = 1 + (rng.random(len(sizes)) * (sizes - 1 - d1)).astype(int)     # 1 .. size-1-d1
    base = rng.integers(0, sizes)
    pos = (base[:, None] + np.stack([np.zeros_like(d1), d1, d1 + d2], axis=1)) % sizes[:, None]
    return pos, rng.integers(1, 4, len(sizes))


def test_bit_flips_in_1e5_frames_are_all_rejected_and_counted_as_crc_errors():
    rng = np.random.default_rng(20261121)
    payloads = _random_payloads(rng, N_CORRUPT)
    bits, n_flips = _distinct_positions(rng, [8 * (len(p) + 4) for p in payloads])
    wire = []
    for payload, (b0, b1, b2), k in zip(payloads, bits.tolist(), n_flips.tolist()):
        body = bytearray(payload + framing.crc32(payload).to_bytes(4, "little"))
        for bit in (b0, b1, b2)[:k]:          # k distinct bits
            body[bit >> 3] ^= 1 << (bit & 7)
        wire.append(cobs_encode(body) + b"\x00")
    stream = b"".join(wire)
    frames, errors, _ = feed([stream[i:i + 8192] for i in range(0, len(stream), 8192)])
    assert frames == []                                        # zero corrupted frames accepted
    assert errors.count(CRC_ERROR) == len(errors) == N_CORRUPT  # the CRC error counter matches


def test_wire_corruption_in_1e5_frames_never_accepted_and_next_frame_resyncs():
    """Flipped bits (odd frames) or changed random bytes, zeros included (even frames), on the COBS wire
    bytes before the delimiter; a clean frame follows each corrupted one."""
    rng = np.random.default_rng(7)
    bad = [encode_frame(p)[:-1] for p in _random_payloads(rng, N_CORRUPT)]
    pool = _random_payloads(rng, 997)
    pool_wire = [encode_frame(p) for p in pool]
    good = [pool[i % len(pool)] for i in range(N_CORRUPT)]
    where, n_bad = _distinct_positions(rng, [len(w) for w in bad])
    change = rng.integers(1, 256, (N_CORRUPT, 3)).tolist()
    flips = (1 << rng.integers(0, 8, (N_CORRUPT, 3))).tolist()
    chunks, expected_errors = [], 0
    for i, (w, idx, k, add, flip) in enumerate(zip(bad, where.tolist(), n_bad.tolist(), change, flips)):
        wire = bytearray(w)
        for j in range(k):
            if i % 2:
                wire[idx[j]] ^= flip[j]
            else:
                wire[idx[j]] = (wire[idx[j]] + add[j]) % 256   # a different byte, 0x00 included
        expected_errors += sum(1 for piece in wire.split(b"\x00") if piece)
        chunks.append(bytes(wire) + b"\x00" + pool_wire[i % len(pool)])
    stream = b"".join(chunks)
    frames, errors, _ = feed([stream[i:i + 8192] for i in range(0, len(stream), 8192)])
    assert frames == good                    # every clean frame after garbage accepted, nothing else
    assert len(errors) == expected_errors    # every corrupted piece rejected and counted once


def test_resync_after_garbage_burst_and_truncated_frame():
    rng = np.random.default_rng(3)
    garbage = rng.integers(0, 256, 5000, dtype=np.uint8).tobytes()
    truncated = encode_frame(b"\x33" * 20)[:12]
    stream = garbage + b"\x00" + truncated + b"\x00" + encode_frame(b"hello") + encode_frame(b"\x00\x01")
    frames, errors, _ = feed([stream])
    assert frames == [b"hello", b"\x00\x01"]
    assert errors  # the garbage and the truncated frame were noticed


def test_oversized_unterminated_input_is_bounded_rejected_and_counted_once():
    state = DecoderState()
    errors = []
    for _ in range(1000):  # 100 kB without a delimiter
        state, frames, e = decode_stream(state, b"\x5a" * 100)
        assert frames == [] and len(state.pending) <= MAX_FRAME
        errors += e
    assert errors == [framing.OVERFLOW_ERROR]
    state, frames, e = decode_stream(state, b"\x5a\x00" + encode_frame(b"next"))
    assert frames == [b"next"] and e == []
    # an oversized frame delivered whole in one chunk is also one overflow
    _, frames, e = decode_stream(DecoderState(), encode_frame(b"\x01" * 100) + encode_frame(b"ok"))
    assert frames == [b"ok"] and e == [framing.OVERFLOW_ERROR]


def test_malformed_cobs_and_short_frames_are_classified():
    with pytest.raises(framing.FrameError) as exc:
        decode_frame(b"\x09\x01\x02")                      # code points past the end
    assert exc.value.kind == framing.COBS_ERROR
    with pytest.raises(framing.FrameError) as exc:
        decode_frame(cobs_encode(b"\x01\x02\x03"))          # shorter than 1 byte + CRC
    assert exc.value.kind == framing.SHORT_ERROR
