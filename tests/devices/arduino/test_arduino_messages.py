"""Link messages: every type round-trips, bad payloads are refused, sequence tracking, bandwidth, and the
firmware's protocol.h / CRC table agree with the host."""

import re
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devices.arduino import framing
from devices.arduino import messages as msg
from devices.base import RobotSpec

FIRMWARE = Path(msg.__file__).resolve().parent / "firmware"
steps6 = st.tuples(*[st.integers(-msg.STEP_LIMIT, msg.STEP_LIMIT)] * 6)
seq = st.integers(0, msg.SEQ_MOD - 1)
u16 = st.integers(0, 0xFFFF)

MESSAGES = st.one_of(
    st.builds(msg.Hello, seq), st.builds(msg.Stop, seq), st.builds(msg.Enable, seq),
    st.builds(msg.Heartbeat, seq), st.builds(msg.DiagRequest, seq),
    st.builds(msg.Home, seq, steps6), st.builds(msg.Command, seq, steps6),
    st.builds(msg.HelloReply, seq, st.integers(0, 255), st.tuples(*[st.integers(0, 255)] * 3), u16,
              st.integers(0, 255), st.integers(0, 255), u16, u16, st.integers(0, 2**32 - 1), st.integers(0, 255)),
    st.builds(msg.Telemetry, seq, st.integers(0, 255), st.integers(0, 255),
              st.tuples(*[st.integers(0, 1023)] * 6), st.integers(0, 15), steps6),
    st.builds(msg.DiagReply, seq, st.integers(0, 2**32 - 1), st.integers(0, msg.SEQ_MOD - 1),
              st.integers(0, 255), u16, st.fixed_dictionaries({k: u16 for k in msg.DIAG_COUNTERS})),
)


@settings(max_examples=200)
@given(MESSAGES)
def test_every_message_round_trips_through_payload_and_frame(m):
    payload = msg.encode(m)
    assert msg.decode(payload) == m
    wire = framing.encode_frame(payload)
    assert msg.decode(framing.decode_frame(wire[:-1])) == m
    kind = msg.MsgType(int.from_bytes(payload[:2], "little") >> msg.SEQ_BITS)
    assert len(wire) == msg.wire_size(kind)  # fixed sizes: COBS adds exactly one byte below 254


def test_every_type_is_covered():
    examples = [msg.Hello(1), msg.Home(2), msg.Command(3, (0,) * 6), msg.Stop(4), msg.Enable(5),
                msg.Heartbeat(6), msg.DiagRequest(7),
                msg.HelloReply(8, 1, (1, 0, 0), 3, 6, 25, 10000, 2037, 51000, 64),
                msg.Telemetry(9, 1, 9, (1, 2, 3, 4, 5, 6), 3, (1, -2, 3, -4, 5, -6)),
                msg.DiagReply(10, 5, 6, 7, 8, {k: i for i, k in enumerate(msg.DIAG_COUNTERS)})]
    assert {msg.MsgType(int.from_bytes(msg.encode(m)[:2], "little") >> 12) for m in examples} == set(msg.MsgType)
    for m in examples:
        assert msg.decode(msg.encode(m)) == m


def test_wrong_length_unknown_type_and_out_of_range_steps_are_refused():
    good = msg.encode(msg.Command(5, (1,) * 6))
    with pytest.raises(msg.MessageError):
        msg.decode(good[:-1])
    with pytest.raises(msg.MessageError):
        msg.decode(good + b"\x00")
    with pytest.raises(msg.MessageError):
        msg.decode((15 << 12 | 5).to_bytes(2, "little"))
    with pytest.raises(msg.MessageError):
        msg.decode(b"\x01")
    with pytest.raises(ValueError):
        msg.encode(msg.Command(5, (msg.STEP_LIMIT + 1,) + (0,) * 5))
    with pytest.raises(ValueError):
        msg.encode(msg.Command(5, (0,) * 5))


def test_sequence_tracking_detects_every_gap_duplicate_and_reordering():
    rng = np.random.default_rng(11)
    n = 6000
    s = [i % msg.SEQ_MOD for i in range(n)]               # wraps past 4095 once
    received, n_drop, n_dup, n_swap, i = [], 0, 0, 0, 0
    while i < n:                                          # isolated events, so each is countable
        r = rng.random()
        if 0 < i < n - 3 and r < 0.04:                    # drop s[i]
            received += [s[i + 1]]
            n_drop, i = n_drop + 1, i + 2
        elif 0 < i < n - 3 and r < 0.06:                  # duplicate s[i]
            received += [s[i], s[i], s[i + 1]]
            n_dup, i = n_dup + 1, i + 2
        elif 0 < i < n - 3 and r < 0.08:                  # s[i] and s[i+1] swapped
            received += [s[i + 1], s[i], s[i + 2]]
            n_swap, i = n_swap + 1, i + 3
        else:
            received.append(s[i])
            i += 1
    last, counts, missing = None, {}, 0
    for q in received:
        kind, k = msg.classify_seq(last, q)
        counts[kind] = counts.get(kind, 0) + 1
        if kind in ("first", "next", "gap"):
            last, missing = q, missing + k
    assert min(n_drop, n_dup, n_swap) > 20
    assert counts["duplicate"] == n_dup
    assert counts["old"] == n_swap                        # the late one of each swapped pair
    assert missing == n_drop + n_swap                     # every drop (and every overtaken frame) seen
    assert msg.seq_diff(0, 4095) == 1 and msg.seq_diff(4095, 0) == -1 and msg.seq_diff(7, 7) == 0


def test_worst_case_command_plus_telemetry_fits_half_a_1ms_period_at_1mbaud():
    bits_per_byte, baud, period = 10, 1_000_000, 1e-3
    worst = {}
    for kind, example in [(msg.MsgType.COMMAND, msg.Command(4095, (-1,) * 6)),
                          (msg.MsgType.TELEMETRY, msg.Telemetry(4095, 255, 255, (1023,) * 6, 15, (-1,) * 6))]:
        sizes = [len(framing.encode_frame(msg.encode(example)))]
        zeros = msg.decode(msg.encode(example))  # all-zero content: COBS worst case for these sizes
        sizes.append(len(framing.encode_frame(bytes(len(msg.encode(zeros))))))
        worst[kind] = max(sizes)
        assert worst[kind] == msg.wire_size(kind)
    t_link = (worst[msg.MsgType.COMMAND] + worst[msg.MsgType.TELEMETRY]) * bits_per_byte / baud
    assert t_link <= 0.5 * period, f"{t_link * 1e6:.0f} us of a {period * 1e6:.0f} us period"


@settings(max_examples=50)
@given(st.lists(st.floats(0.005, 0.060), min_size=6, max_size=6))
def test_lengths_steps_round_trip_within_half_a_step(lengths):
    spec = RobotSpec()
    home = np.full(6, 0.030)
    steps = msg.lengths2steps(lengths, home, spec.steps_per_m)
    back = msg.steps2lengths(steps, home, spec.steps_per_m)
    np.testing.assert_allclose(back, lengths, atol=0.5 / spec.steps_per_m + 1e-12)
    assert np.all(np.abs(steps) <= msg.STEP_LIMIT)
    shorter = msg.lengths2steps(home - 0.001, home, spec.steps_per_m)
    assert np.all(shorter > 0)  # hauling in (shorter cable) is positive


def _defines(text: str) -> dict:
    return {m[1]: m[2] for m in re.finditer(r"#define[ \t]+(\w+)[ \t]+([^ \t\n]+)", text)}


def test_firmware_protocol_header_agrees_with_host():
    d = _defines((FIRMWARE / "protocol.h").read_text())
    assert int(d["PROTOCOL_VERSION"]) == msg.PROTOCOL_VERSION
    assert int(d["N_CHANNELS"]) == msg.N_CHANNELS and int(d["SEQ_BITS"]) == msg.SEQ_BITS
    assert int(d["MAX_FRAME"]) == framing.MAX_FRAME and int(d["CRC_SIZE"]) == framing.CRC_SIZE
    assert int(d["STEP_LIMIT"]) == msg.STEP_LIMIT
    for kind in msg.MsgType:
        assert int(d[f"MSG_{kind.name}"]) == kind.value
    assert int(d["HELLO_REPLY_SIZE"]) == msg.PAYLOAD_SIZES[msg.MsgType.HELLO_REPLY]
    assert int(d["TELEMETRY_SIZE"]) == msg.PAYLOAD_SIZES[msg.MsgType.TELEMETRY]
    assert 9 + 2 * int(d["DIAG_COUNTERS"]) == msg.PAYLOAD_SIZES[msg.MsgType.DIAG_REPLY]
    assert int(d["DIAG_COUNTERS"]) == len(msg.DIAG_COUNTERS)
    for bit in msg.Status:
        assert int(d[f"STATUS_{bit.name}"], 16) == bit.value
    spec = RobotSpec()
    assert int(d["V_MAX_STEPS"]) == round(spec.v_max * spec.steps_per_m)


def test_firmware_crc_table_is_zlib_crc32():
    text = (FIRMWARE / "link.cpp").read_text()
    body = text[text.index("kCrcTable[256]"):]
    table = [int(v, 16) for v in re.findall(r"0x([0-9A-F]{8})UL", body[:body.index("};")])]
    assert len(table) == 256
    rng = np.random.default_rng(5)
    for n in (0, 1, 9, 28, 200):
        data = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        crc = 0xFFFFFFFF
        for b in data:  # the firmware's loop: crc = (crc >> 8) ^ table[(crc ^ b) & 0xFF]
            crc = (crc >> 8) ^ table[(crc ^ b) & 0xFF]
        assert crc ^ 0xFFFFFFFF == zlib.crc32(data)
