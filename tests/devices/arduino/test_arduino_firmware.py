"""The real firmware in simavr, over a pseudo-terminal with pyserial at 1 Mbaud: every message, corrupted
frames, resync, bounded input, stale commands, firmware reset, step counting, ADC, pulse timing."""

import time

import numpy as np
import pytest

from devices.arduino import framing
from devices.arduino import messages as msg
from devices.base import DeviceError, RobotSpec

from .conftest import HOME_LENGTHS

ERROR_COUNTERS = ("crc", "cobs", "short", "overflow", "malformed")
SPEC = RobotSpec()


def delta(after: msg.DiagReply, before: msg.DiagReply) -> dict:
    return {k: after.counters[k] - before.counters[k] for k in msg.DIAG_COUNTERS}


def keep_going(robot, target):
    """Re-enable and re-command when the watchdog stopped the motors (a host stall > 25 ms on a loaded
    machine is a real silence to the firmware); returns the fresh reading."""
    reading = robot.read_fresh()
    if reading.status & msg.Status.WATCHDOG_STOP:
        robot.enable()
        robot.command_lengths(target)
        reading = robot.read_fresh()
    return reading


def wait_for(predicate, timeout=3.0, period=0.01):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(period)
    return predicate()


def test_round_trip_of_every_message(raw):
    h = raw.hello
    assert (h.protocol, h.firmware_version, h.n_channels) == (msg.PROTOCOL_VERSION, (1, 0, 0), 6)
    assert (h.watchdog_ms, h.tick_hz, h.v_max_steps_per_s, h.rx_buffer) == (25, 10000, 2037, framing.MAX_FRAME)
    s = raw.next_seq()
    t = raw.exchange(msg.Home(s, (10, -20, 30, -40, 50, -60)))
    assert isinstance(t, msg.Telemetry) and t.reply_to == s & 0xFF and t.boot_tag == h.boot_id & 0xF
    assert t.position_steps == (10, -20, 30, -40, 50, -60) and t.status & msg.Status.HOMED
    for _ in range(3):  # a host stall > 25 ms on a loaded machine lets the watchdog stop the motors first
        s = raw.next_seq()
        t = raw.exchange(msg.Command(s, (10, -20, 30, -40, 50, -60)))
        if not t.status & msg.Status.WATCHDOG_STOP:
            break
        raw.exchange(msg.Enable(raw.next_seq()))
    assert t.reply_to == s & 0xFF and not t.status & msg.Status.REJECTED
    s = raw.next_seq()
    t = raw.exchange(msg.Heartbeat(s))
    assert t.reply_to == s & 0xFF and all(0 < c < 1023 for c in t.adc_counts)
    t = raw.exchange(msg.Stop(raw.next_seq()))
    assert t.status & msg.Status.STOPPED
    t = raw.exchange(msg.Command(raw.next_seq(), (0,) * 6))
    assert t.status & msg.Status.REJECTED                   # STOP latches
    t = raw.exchange(msg.Enable(raw.next_seq()))
    assert not t.status & (msg.Status.STOPPED | msg.Status.REJECTED)
    d = raw.exchange(msg.DiagRequest(raw.next_seq()))
    assert isinstance(d, msg.DiagReply) and d.last_seq == raw.seq and d.micros > 0
    assert not raw.errors


def corrupt_frames(rng, n, payload_of):
    """n corrupted COMMAND frames (1-3 flipped bits or changed bytes in the COBS body) -> (bytes list,
    expected error count = non-empty pieces between delimiters)."""
    frames, expected = [], 0
    for i in range(n):
        wire = bytearray(framing.encode_frame(payload_of(i))[:-1])
        for j in rng.choice(len(wire), size=int(rng.integers(1, 4)), replace=False):
            if i % 2:
                wire[j] ^= 1 << int(rng.integers(0, 8))
            else:
                wire[j] = (wire[j] + int(rng.integers(1, 256))) % 256
        expected += sum(1 for piece in wire.split(b"\x00") if piece)
        frames.append(bytes(wire) + b"\x00")
    return frames, expected


def test_corrupted_frames_sent_to_the_firmware_are_all_rejected_and_counted(raw, mega):
    rng = np.random.default_rng(404)
    far = (20000, -20000, 20000, -20000, 20000, -20000)   # an accepted one would start a long move
    frames, expected = corrupt_frames(rng, 300, lambda i: msg.encode(msg.Command(raw.next_seq(), far)))
    before, pos_before = raw.diag(), mega.status()["pos"]
    for k in range(0, len(frames), 3):
        raw.write(b"".join(frames[k:k + 3]))
        raw.receive(0.002)
    raw.write(framing.encode_frame(msg.encode(msg.Heartbeat(raw.next_seq()))))
    replies = raw.receive(1.0)
    after = raw.diag()
    d = delta(after, before)
    assert d["rx_busy"] == 0
    assert sum(d[k] for k in ERROR_COUNTERS) == expected      # every corrupted piece counted once
    assert d["rx_frames"] == 2                                 # only the heartbeat and the DIAG request
    assert [type(r) for r in replies] == [msg.Telemetry]       # nothing answered the corrupted frames
    assert not replies[0].status & msg.Status.MOVING
    assert mega.status()["pos"] == pos_before                  # nothing moved


def test_resync_after_garbage_burst_and_truncated_frame(raw):
    rng = np.random.default_rng(9)
    before = raw.diag()
    raw.write(rng.integers(0, 256, 600, dtype=np.uint8).tobytes())  # garbage, zeros included
    raw.receive(0.05)
    truncated = framing.encode_frame(msg.encode(msg.Command(raw.next_seq(), (9000,) * 6)))[:10]
    raw.write(b"\x00" + truncated + b"\x00")
    s = raw.next_seq()
    replies = [r for r in raw.receive(0.3, count=1) if isinstance(r, msg.Telemetry)] or \
        [raw.exchange(msg.Heartbeat(s))]
    t = raw.exchange(msg.Heartbeat(raw.next_seq()))      # the next valid frame is accepted
    assert isinstance(t, msg.Telemetry) and t.reply_to == raw.seq & 0xFF
    assert t.position_steps == (0,) * 6 and not t.status & msg.Status.MOVING  # the truncated command never ran
    d = delta(raw.diag(), before)
    assert sum(d[k] for k in ERROR_COUNTERS) >= 2
    assert replies


def test_oversized_unterminated_input_is_bounded_rejected_and_counted(raw):
    before = raw.diag()
    raw.write(b"\x41" * 5000)                            # 5 kB without a delimiter
    time.sleep(0.08)
    raw.write(b"\x00" + b"\x42" * 100 + b"\x00")         # one more oversized frame, terminated
    t = raw.exchange(msg.Heartbeat(raw.next_seq()))
    assert isinstance(t, msg.Telemetry)                  # resynchronised at the delimiter
    d = delta(raw.diag(), before)
    assert d["overflow"] == 2 and sum(d[k] for k in ERROR_COUNTERS) == 2


def test_stale_and_duplicate_commands_are_rejected_and_never_applied(raw, mega):
    before = raw.diag()
    s_a = raw.next_seq()
    a = msg.Command(s_a, (40,) * 6)                                # built now, delivered late
    raw.exchange(msg.Enable(raw.next_seq()))                       # (the watchdog may have tripped)
    raw.seq = (raw.seq + 5) % msg.SEQ_MOD
    b = msg.Command(raw.next_seq(), (-30,) * 6)
    assert not raw.exchange(b).status & msg.Status.REJECTED        # newest command: applied
    t_dup = raw.exchange(b)                                        # duplicate
    t_old = raw.exchange(a)                                        # older seq, arriving late
    assert t_dup.status & msg.Status.REJECTED and t_old.status & msg.Status.REJECTED
    stop_stale = raw.exchange(msg.Stop(s_a))                       # STOP is obeyed even when stale
    assert stop_stale.status & msg.Status.STOPPED
    d = delta(raw.diag(), before)
    assert d["stale"] == 2
    for _ in range(100):                                           # keep the watchdog fed while moving
        t = raw.exchange(msg.Heartbeat(raw.next_seq()))
        if t.position_steps == (-30,) * 6 and not t.status & msg.Status.MOVING:
            break
        if t.status & (msg.Status.WATCHDOG_STOP | msg.Status.STOPPED):  # STOP above, or a host stall
            raw.exchange(msg.Enable(raw.next_seq()))
            raw.exchange(msg.Command(raw.next_seq(), (-30,) * 6))
        time.sleep(0.003)
    assert t.position_steps == (-30,) * 6                          # went to B, never toward A


def test_robot_moves_counts_steps_and_reads_the_tension_model(robot, mega):
    start = np.array(mega.status()["pos"])
    target = HOME_LENGTHS - np.array([0.001, 0.002, 0.0005, 0.0, 0.0015, 0.001])  # haul in up to 2 mm
    robot.command_lengths(target)
    expected = msg.lengths2steps(target, HOME_LENGTHS, SPEC.steps_per_m)

    def arrived():
        reading = keep_going(robot, target)
        return reading if (np.array_equal(reading.position_steps, expected)
                           and not reading.status & msg.Status.MOVING) else None

    reading = wait_for(arrived, timeout=5.0, period=0.005)
    assert reading is not None, "the motors did not reach the target"
    status = mega.status()
    np.testing.assert_array_equal(np.array(status["pos"]) - start, expected)  # pulses counted == firmware steps
    np.testing.assert_allclose(reading.extras["lengths"], target, atol=1 / SPEC.steps_per_m)
    np.testing.assert_array_equal(reading.commanded_lengths, target)
    robot.read_fresh()
    counts = robot.read_fresh().fsr_counts
    np.testing.assert_allclose(counts, np.array(status["adc_mv"]) / 5000 * 1024, atol=2)
    assert counts[1] > counts[3]                      # the cable hauled in 2 mm is tighter than the idle one
    assert status["pulse_min_ns"] >= 2000             # step pulse >= 1.9 us (DRV8825), here one tick
    assert status["dir_setup_min_ns"] >= 650         # DIR settles >= 650 ns before a step edge
    assert status["tx_dropped"] == 0


def test_speed_limit_respected(robot, mega):
    target = HOME_LENGTHS - 0.010                        # 10 mm: longer than the ramp
    robot.command_lengths(target)
    windows = 0
    for _ in range(10):
        a = mega.status()
        for _ in range(20):
            keep_going(robot, target)
        b = mega.status()
        dt = (b["t_ns"] - a["t_ns"]) * 1e-9
        moved = np.abs(np.array(b["pos"]) - np.array(a["pos"]))
        assert np.all(moved <= SPEC.v_max * SPEC.steps_per_m * dt + 2)  # v <= v_max (emulated clock)
        windows += moved.max() > 0
    assert windows >= 5                                   # it was moving, not standing still
    robot.stop()


def test_acceleration_limit_respected_from_rest(robot, mega):
    """From rest, steps taken by emulated time t after the command are <= a (t + 1 ms)^2 / 2 + 1."""
    accel = robot.hello.accel_steps_per_s2
    target = HOME_LENGTHS - 0.010
    for _ in range(5):                  # retry if a host stall trips the watchdog (no motion to measure then)
        robot.enable()
        before = mega.status()
        start = np.array(before["pos"])
        robot.command_lengths(target)
        wire = msg.wire_size(msg.MsgType.COMMAND)
        st = wait_for(lambda: (lambda s: s if s["rx_bytes"] >= before["rx_bytes"] + wire else None)(mega.status()),
                      timeout=2.0, period=0.0)
        t0 = st["last_rx_ns"]                              # the COMMAND's delimiter entered the UART
        samples = []
        for _ in range(25):
            reading = robot.read_fresh()
            st = mega.status()
            samples.append(((st["t_ns"] - t0) * 1e-9, np.abs(np.array(st["pos"]) - start).max()))
        t, x = np.array(samples).T
        if not reading.status & msg.Status.WATCHDOG_STOP and x.max() > 0:
            break
        robot.stop()
    assert x.max() > 0
    assert np.all(x <= 0.5 * accel * (t + 0.001) ** 2 + 1), list(zip(t, x))
    robot.stop()


def test_firmware_reset_detected_and_motion_refused_until_rehomed(robot, mega):
    boot = robot.boot_id
    mega.reset()
    assert wait_for(lambda: robot.read_fresh() and robot.reset_detected, timeout=2.0)
    assert robot.boot_id != boot and not robot.is_homed
    with pytest.raises(DeviceError, match="reset"):
        robot.command_lengths(HOME_LENGTHS)
    reading = robot.read_fresh()
    assert not reading.status & msg.Status.HOMED        # the firmware itself refuses motion as well
    assert mega.status()["enable"] == 1                  # power-on default: drivers disabled (EN high)
    assert robot.stats.resets == 1
    robot.home(HOME_LENGTHS)
    assert mega.status()["enable"] == 0                  # HOME enables the drivers
    robot.command_lengths(HOME_LENGTHS - 0.0005)
    reading = robot.read_fresh()
    if reading.status & msg.Status.WATCHDOG_STOP:        # a host stall after HOME: not the point here
        robot.enable()
        robot.command_lengths(HOME_LENGTHS - 0.0005)
        reading = robot.read_fresh()
    assert reading.extras["rejected"] is False
