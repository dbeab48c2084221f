"""Watchdog: the host goes silent (loop paused, process killed, port closed) -> the firmware stops the
steppers within 50 ms of emulated time, in 100 of 100 trials of each kind (one emulator per session, each
episode timed on the emulated clock by the harness: last received byte -> last step pulse), and not before
its own watchdog time (25 ms). An episode whose watchdog tripped before the intended silence (an "early
trip") is repeated by the trials; that is only right when the host really fell silent for the watchdog
time (a stall of this shared machine): a test reads the emulator's byte trace and fails on any watchdog
stop that no such silence preceded."""

import numpy as np
import pytest

from devices.arduino.trials import close_trials, kill_trials, watchdog_trials

from .conftest import HOME_LENGTHS

N_TRIALS = 100
BOUND_MS = 50.0
WATCHDOG_MS = 25.0   # the firmware's watchdog time (protocol.h, reported in HELLO)
TICK_MS = 1.0        # the firmware counts silence in 1 ms motion ticks


def check(result, what: str) -> None:
    assert len(result.stop_ms) == N_TRIALS
    assert np.all(result.steps_after_silence > 0)       # every episode was moving when the host fell silent
    assert np.all(result.latched)                        # and the firmware reports the watchdog stop
    assert result.stop_ms.min() >= WATCHDOG_MS - 2 * TICK_MS, f"{what}: a stop before the watchdog time"
    assert result.stop_ms.max() <= BOUND_MS, f"{what}: stop times [ms]: max {result.stop_ms.max():.2f}"
    print(f"\n{what}: watchdog stop [ms, emulated]: max {result.stop_ms.max():.2f} mean {result.stop_ms.mean():.2f} "
          f"min {result.stop_ms.min():.2f}; early trips (host stalls) {result.early_trips}")


def test_host_silence_stops_steppers_within_50ms_in_100_of_100_trials(robot, mega):
    """Loop paused: the open host stops sending."""
    check(watchdog_trials(robot, mega, HOME_LENGTHS, n=N_TRIALS, max_attempts=10 * N_TRIALS), "loop paused")


def test_killed_host_process_stops_steppers_within_50ms_in_100_of_100_trials(mega):
    """SIGKILL a host process mid-motion while it streams (no STOP, its port closed by the kernel)."""
    check(kill_trials(mega, HOME_LENGTHS, n=N_TRIALS, seed=0, max_attempts=10 * N_TRIALS), "process killed")


def test_closed_port_stops_steppers_within_50ms_in_100_of_100_trials(mega):
    """The host's serial port closes mid-motion without a STOP (host crash, cable pulled)."""
    check(close_trials(mega, HOME_LENGTHS, n=N_TRIALS, max_attempts=10 * N_TRIALS), "port closed")


@pytest.mark.parametrize("trials", [close_trials, kill_trials])
def test_a_motor_still_running_after_the_bound_is_seen(mega, trials):
    """The trials can fail: read each episode after a silence shorter than the watchdog's stop time and the
    motors are still stepping, so the reported stop time is the whole silence observed (>= the window),
    as it would be past 50 ms for a firmware whose watchdog did not stop them within the 60 ms window."""
    result = trials(mega, HOME_LENGTHS, n=3, silence_ms=5.0, max_attempts=30)
    assert np.all(result.steps_after_silence > 0) and np.all(result.stop_ms >= 5.0 - 0.5)


F_CPU = 16_000_000  # emulated clock [Hz]


def watchdog_onsets_and_rx_gaps(trace_path):
    """From the harness byte trace (CDPR_SIM_TRACE: "R|T cycle byte" lines): the emulated times [s] of the
    telemetry frames, whether each reports a watchdog stop, and the received bytes' times [s]."""
    from devices.arduino import framing
    from devices.arduino import messages as msg

    rx, tele_t, tele_wd, frame, start = [], [], [], bytearray(), None
    for line in open(trace_path):
        kind, cycle, byte = line.split()
        t, b = int(cycle) / F_CPU, int(byte, 16)
        if kind == "R":
            rx.append(t)
            continue
        if b != 0:
            frame.append(b)
            continue
        try:
            m = msg.decode(framing.decode_frame(bytes(frame)))
        except (framing.FrameError, msg.MessageError):
            m = None
        frame = bytearray()
        if isinstance(m, msg.Telemetry):
            tele_t.append(t)
            tele_wd.append(bool(m.status & msg.Status.WATCHDOG_STOP))
    return np.array(tele_t), np.array(tele_wd), np.array(rx)


def silences_before_stops(trace_path) -> list:
    """[(t [s], gap [ms])]: for each telemetry frame first reporting a watchdog stop, the longest gap between
    received bytes from the last byte before the previous telemetry frame (the end of the host frame it
    answered) to the stop's frame."""
    t, wd, rx = watchdog_onsets_and_rx_gaps(trace_path)
    out = []
    for k in np.flatnonzero(wd[1:] & ~wd[:-1]) + 1:
        first = max(int(np.searchsorted(rx, t[k - 1])) - 1, 0)
        window = rx[first:int(np.searchsorted(rx, t[k], side="right"))]
        out.append((t[k], np.diff(window).max() * 1e3 if len(window) > 1 else 0.0))
    return out


@pytest.mark.parametrize("trials", [watchdog_trials, close_trials])
def test_every_watchdog_stop_follows_a_host_silence_of_the_watchdog_time(arduino_build, tmp_path, monkeypatch,
                                                                         trials):
    """Early trips are repeated only when the host itself was silent: in the byte trace of a fresh emulator,
    every telemetry frame that first reports a watchdog stop follows, since the last frame without it, a gap
    of at least the watchdog time between received bytes (emulated clock). A firmware that trips while the
    host streams fails here instead of being retried."""
    from devices.arduino.robot import ArduinoRobot
    from devices.arduino.simulator import EmulatedMega

    elf, harness = arduino_build
    trace = tmp_path / "trace.txt"
    monkeypatch.setenv("CDPR_SIM_TRACE", str(trace))
    with EmulatedMega(harness, elf) as mega:
        if trials is watchdog_trials:
            with ArduinoRobot(mega.port, timeout_s=1.0) as robot:
                robot.home(HOME_LENGTHS)
                result = watchdog_trials(robot, mega, HOME_LENGTHS, n=20, max_attempts=200)
        else:
            result = close_trials(mega, HOME_LENGTHS, n=20, max_attempts=200)
    stops = silences_before_stops(trace)
    assert len(stops) >= len(result.stop_ms)  # every episode's stop is seen in the trace (and each early trip)
    for at, gap_ms in stops:
        assert gap_ms >= WATCHDOG_MS - TICK_MS, f"watchdog stop at t = {at:.4f} s after a silence of {gap_ms:.2f} ms"


def test_the_silence_check_sees_a_stop_while_the_host_streams(tmp_path):
    """The trace reading behind the check above: host bytes every 1 ms, then a telemetry frame reporting a
    watchdog stop -> the largest gap before it is 1 ms (a firmware fault the check fails on); with a 30 ms
    silence before the stop, 30 ms."""
    from devices.arduino import framing
    from devices.arduino import messages as msg

    def telemetry(status):
        return framing.encode_frame(msg.encode(msg.Telemetry(1, status, 0, (0,) * 6, 0, (0,) * 6)))

    def trace(silence_ms):
        lines, ms = [], 0.0
        for k in range(10):
            ms += 1.0
            lines.append(f"R {int(ms * 1e-3 * F_CPU)} 00")
            if k == 4:
                lines += [f"T {int(ms * 1e-3 * F_CPU) + 100 + j} {b:02x}" for j, b in enumerate(telemetry(0))]
        ms += silence_ms
        lines.append(f"R {int(ms * 1e-3 * F_CPU)} 00")
        stop = telemetry(msg.Status.WATCHDOG_STOP)
        lines += [f"T {int(ms * 1e-3 * F_CPU) + 100 + j} {b:02x}" for j, b in enumerate(stop)]
        path = tmp_path / f"trace{silence_ms}.txt"
        path.write_text("\n".join(lines) + "\n")
        return path

    for silence_ms in (1.0, 30.0):
        (_, gap_ms), = silences_before_stops(trace(silence_ms))
        assert gap_ms == pytest.approx(silence_ms, abs=1e-3)
