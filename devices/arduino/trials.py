"""Measurements on the emulated link: watchdog stop time (emulated clock) and round-trip latency (wall).

The host goes silent three ways (docs/safety.md): the loop pauses (watchdog_trials), the host process is
killed (kill_trials), the port is closed without a STOP (close_trials); each runs many episodes on one
emulator and reads every stop time from the harness on the emulated clock.

Used by the tests (which assert the watchdog bound) and by ``teleop bench link`` (which reports both).
"""

from __future__ import annotations

import json
import mmap
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np

from devices.arduino import messages as msg
from devices.arduino.robot import ArduinoRobot
from devices.arduino.simulator import EmulatedMega


@dataclass(frozen=True)
class WatchdogTrials:
    """Host-silence episodes.

    Attributes:
        stop_ms: (n,) per episode, emulated time from the last byte the UART received to the last step
            pulse [ms].
        steps_after_silence: (n,) step pulses emitted after the last received byte (> 0: was moving).
        latched: (n,) firmware reported WATCHDOG_STOP afterwards.
        early_trips: episodes discarded because the watchdog tripped before the intended silence (the
            host itself stalled > WATCHDOG_MS while streaming, e.g. on a loaded machine).
    """

    stop_ms: np.ndarray
    steps_after_silence: np.ndarray
    latched: np.ndarray
    early_trips: int = 0
    extras: dict = field(default_factory=dict)


def wait_for_silence(mega: EmulatedMega, silence_ms: float, poll_s: float = 0.005) -> dict:
    """Poll the harness until `silence_ms` [ms] of emulated time have passed since the UART's last received
    byte; returns that status (emulated-clock fields: t_ns, last_rx_ns, last_step_ns, steps_after_rx)."""
    while True:
        time.sleep(poll_s)
        status = mega.status()
        if status["t_ns"] - status["last_rx_ns"] >= silence_ms * 1e6:
            return status


def _stop_time(status: dict) -> tuple[float, int]:
    """(last received byte -> last step pulse [ms, emulated], step pulses after the last received byte)."""
    return (status["last_step_ns"] - status["last_rx_ns"]) * 1e-6, int(status["steps_after_rx"])


def _measured(mega: EmulatedMega, silence_ms: float) -> tuple[float, int] | None:
    """`_stop_time` of the episode once `silence_ms` have passed, or None when the motors had stopped before
    the host's last byte arrived (a watchdog trip in a host stall, seen late: an early trip, to repeat)."""
    ms, steps = _stop_time(wait_for_silence(mega, silence_ms))
    return None if steps == 0 else (ms, steps)


def _is_moving(status: int) -> bool:
    """A telemetry status of a firmware still moving and not stopped by its watchdog."""
    return bool(status & msg.Status.MOVING) and not status & msg.Status.WATCHDOG_STOP


def watchdog_trials(robot: ArduinoRobot, mega: EmulatedMega, home_lengths, n: int = 100,
                    stream_s: float = 0.010, silence_ms: float = 60.0, travel_m: float = 0.02,
                    max_attempts: int | None = None) -> WatchdogTrials:
    """Loop paused: run n episodes: ENABLE, command a far target, stream heartbeats for stream_s [s] of
    wall time while the motors accelerate, go silent, and read the stop time from the harness once
    silence_ms of emulated time have passed since the last received byte (silence_ms above the bound being
    tested: a motor still running then shows a stop time of about silence_ms)."""
    home = np.asarray(home_lengths, float)
    stop_ms, steps_after, latched, early = [], [], [], 0
    attempts = 0
    while len(stop_ms) < n:
        attempts += 1
        if max_attempts is not None and attempts > max_attempts:
            raise RuntimeError(f"watchdog trials: {early} early trips in {attempts - 1} attempts")
        robot.enable()
        robot.command_lengths(home - travel_m if len(stop_ms) % 2 == 0 else home + travel_m)
        t_end = time.monotonic() + stream_s
        while time.monotonic() < t_end:
            robot.read()
            time.sleep(0.001)
        reading = robot.read_fresh()  # the last frame before the silence
        if not _is_moving(reading.status):
            early += 1
            continue
        measured = _measured(mega, silence_ms)
        if measured is None:
            early += 1
            continue
        ms, steps = measured
        stop_ms.append(ms)
        steps_after.append(steps)
        latched.append(bool(robot.read_fresh().status & msg.Status.WATCHDOG_STOP))
    return WatchdogTrials(np.array(stop_ms), np.array(steps_after), np.array(latched), early)


def _first_status(port: str) -> int:
    """Connect (HELLO), read one telemetry status, and drop the port without a STOP."""
    robot = ArduinoRobot(port, timeout_s=1.0)
    robot.open()
    try:
        return int(robot.read_fresh().status)
    finally:
        drop_port(robot)


def drop_port(robot: ArduinoRobot) -> None:
    """Close the serial port under an open ArduinoRobot without the STOP its close() sends first: what
    the firmware sees when the host's port goes away (host crash, cable pulled, port closed by the OS)."""
    transport = robot._transport  # noqa: SLF001 - the test harness bypasses the orderly close on purpose
    if transport is not None:
        transport.close()
        robot._transport = None  # noqa: SLF001
    robot.close()


def _host_episode(robot: ArduinoRobot, home, target, stream_s: float) -> int:
    """HOME (clears any latch, enables), command `target`, stream heartbeats for stream_s [s]; returns the
    status of a fresh telemetry frame at the end."""
    robot.home(home)
    robot.command_lengths(target)
    t_end = time.monotonic() + stream_s
    while time.monotonic() < t_end:
        robot.read()
        time.sleep(0.001)
    return int(robot.read_fresh().status)


def close_trials(mega: EmulatedMega, home_lengths, n: int = 100, stream_s: float = 0.010,
                 silence_ms: float = 60.0, travel_m: float = 0.02, max_attempts: int | None = None) -> WatchdogTrials:
    """Port closed: n episodes, each a new connection (open, HELLO, HOME, far target, stream_s [s] of
    heartbeats) whose serial port is then closed with no STOP (drop_port). Stop time as in watchdog_trials.
    `latched[i]` is the WATCHDOG_STOP bit in the first telemetry of the next connection."""
    home = np.asarray(home_lengths, float)
    stop_ms, steps_after, latched, early, attempts = [], [], [], 0, 0
    while len(stop_ms) < n:
        attempts += 1
        if max_attempts is not None and attempts > max_attempts:
            raise RuntimeError(f"close trials: {early} early trips in {attempts - 1} attempts")
        robot = ArduinoRobot(mega.port, timeout_s=1.0)
        robot.open()
        first = int(robot.read_fresh().status)
        if len(latched) < len(stop_ms):
            latched.append(bool(first & msg.Status.WATCHDOG_STOP))
        status = _host_episode(robot, home, home - travel_m if len(stop_ms) % 2 == 0 else home + travel_m,
                               stream_s)
        if not _is_moving(status):
            early += 1
            robot.close()  # orderly: STOP
            continue
        drop_port(robot)
        measured = _measured(mega, silence_ms)
        if measured is None:
            early += 1
            continue
        ms, steps = measured
        stop_ms.append(ms)
        steps_after.append(steps)
    latched.append(bool(_first_status(mega.port) & msg.Status.WATCHDOG_STOP))
    return WatchdogTrials(np.array(stop_ms), np.array(steps_after), np.array(latched), early)


def _killed_host(port: str, home, target, stream_s: float, state: np.ndarray) -> None:
    """A host to be killed: connect, report the first status (state[1]), run an episode, set state[0] = 1
    with the last status seen in state[2], and keep streaming heartbeats until SIGKILLed."""
    robot = ArduinoRobot(port, timeout_s=1.0)
    robot.open()
    state[1] = int(robot.read_fresh().status)
    state[2] = _host_episode(robot, home, target, stream_s)
    state[0] = 1
    while True:
        state[2] = int(robot.read().status)
        time.sleep(0.001)


def zygote_main() -> None:
    """Host factory for kill_trials (run as its own interpreter, no threads): for each JSON line
    {"port", "home", "target", "stream_s", "state"} on stdin, fork a host running _killed_host with its
    state in the 3 int64 of the file "state" (mmap), and print the host's pid. Hosts are reaped by the
    kernel (SIGCHLD ignored); a host that fails sets state[0] = -1."""
    signal.signal(signal.SIGCHLD, signal.SIG_IGN)
    for line in sys.stdin:
        job = json.loads(line)
        pid = os.fork()
        if pid == 0:
            code = 0
            with open(job["state"], "r+b") as f:
                state = np.frombuffer(mmap.mmap(f.fileno(), 24), dtype=np.int64)
                try:
                    _killed_host(job["port"], np.array(job["home"]), np.array(job["target"]), job["stream_s"],
                                 state)
                except BaseException:  # noqa: BLE001 - reported to the parent through the state
                    state[0] = -1
                    code = 1
            os._exit(code)
        print(pid, flush=True)


def kill_trials(mega: EmulatedMega, home_lengths, n: int = 100, stream_s: float = 0.010,
                silence_ms: float = 60.0, travel_m: float = 0.02, seed: int = 0,
                max_attempts: int | None = None) -> WatchdogTrials:
    """Process killed: n episodes, each a new host process (connect, HOME, far target, heartbeats every
    1 ms) SIGKILLed while it streams, 0-2 ms (seeded) after the motors were seen moving: no STOP, the
    kernel closes its port. The hosts are forked by a helper interpreter that imported the host side once
    (zygote_main), so each starts in milliseconds. Stop time as in watchdog_trials; `latched[i]` is the
    WATCHDOG_STOP bit in the first telemetry of the next host. An episode whose host saw its own watchdog
    stop before the kill (the host stalled > WATCHDOG_MS) is an early trip and is repeated."""
    rng = np.random.default_rng(seed)
    home = np.asarray(home_lengths, float)
    stop_ms, steps_after, latched, early, attempts = [], [], [], 0, 0
    zygote = subprocess.Popen([sys.executable, "-c", "from devices.arduino.trials import zygote_main; zygote_main()"],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    with tempfile.NamedTemporaryFile(prefix="kill-trial-") as f:
        f.write(bytes(24))
        f.flush()
        state = np.frombuffer(mmap.mmap(f.fileno(), 24), dtype=np.int64)
        try:
            while len(stop_ms) < n:
                attempts += 1
                if max_attempts is not None and attempts > max_attempts:
                    raise RuntimeError(f"kill trials: {early} early trips in {attempts - 1} attempts")
                state[:] = 0
                target = home - travel_m if len(stop_ms) % 2 == 0 else home + travel_m
                zygote.stdin.write(json.dumps({"port": mega.port, "home": home.tolist(), "target": target.tolist(),
                                               "stream_s": stream_s, "state": f.name}) + "\n")
                zygote.stdin.flush()
                line = zygote.stdout.readline()
                if not line.strip().isdigit():
                    raise RuntimeError(f"kill trials: the host factory stopped (exit code {zygote.poll()})")
                pid = int(line)
                deadline = time.monotonic() + 10.0
                while state[0] == 0 and time.monotonic() < deadline:
                    time.sleep(0.0005)
                if state[0] == 1:
                    if len(latched) < len(stop_ms):
                        latched.append(bool(state[1] & msg.Status.WATCHDOG_STOP))
                    time.sleep(float(rng.uniform(0.0, 0.002)))
                try:
                    os.kill(pid, signal.SIGKILL)
                    while True:  # gone once the kernel has reaped it
                        time.sleep(0.0005)
                        os.kill(pid, 0)
                except ProcessLookupError:
                    pass
                if state[0] != 1:
                    raise RuntimeError(f"kill trials: the host process did not start an episode (state {state[0]})")
                if not _is_moving(int(state[2])):
                    early += 1
                    wait_for_silence(mega, silence_ms)
                    continue
                measured = _measured(mega, silence_ms)
                if measured is None:
                    early += 1
                    continue
                ms, steps = measured
                stop_ms.append(ms)
                steps_after.append(steps)
        finally:
            zygote.stdin.close()
            zygote.wait(10)
            zygote.stdout.close()
    latched.append(bool(_first_status(mega.port) & msg.Status.WATCHDOG_STOP))
    return WatchdogTrials(np.array(stop_ms), np.array(steps_after), np.array(latched), early)


def round_trips(robot: ArduinoRobot, n: int = 1000, period_s: float = 0.001) -> np.ndarray:
    """(n,) wall-clock round-trip times [s] of HEARTBEAT -> TELEMETRY over the link, one per period_s."""
    out = np.empty(n)
    for i in range(n):
        t0 = time.perf_counter()
        robot.read_fresh()
        out[i] = time.perf_counter() - t0
        rest = period_s - (time.perf_counter() - t0)
        if rest > 0:
            time.sleep(rest)
    return out


@dataclass(frozen=True)
class StreamResult:
    """A loop-like run: one COMMAND and one read() per tick.

    Attributes:
        ticks: ticks run.
        fresh: ticks whose read() returned a telemetry frame newer than the previous tick's.
        age_ms: (ticks,) age of the reading at read() time (host receive clock) [ms].
        late_ticks: ticks that started more than one period late (host scheduling).
        watchdog_trips: times the firmware stopped on host silence during the run (then re-enabled).
    """

    ticks: int
    fresh: int
    age_ms: np.ndarray
    late_ticks: int
    watchdog_trips: int


def stream(robot: ArduinoRobot, home_lengths, seconds: float = 5.0, rate_hz: float = 1000.0,
           amplitude_m: float = 0.002) -> StreamResult:
    """Command a slow sine on all cables at rate_hz for `seconds` [s], reading back every tick."""
    home = np.asarray(home_lengths, float)
    period = 1.0 / rate_hz
    n = int(seconds * rate_hz)
    ages = np.empty(n)
    fresh, late, trips, last_seq = 0, 0, 0, None
    t0 = time.perf_counter()
    for k in range(n):
        due = t0 + k * period
        now = time.perf_counter()
        if now < due:
            time.sleep(due - now)
        elif now - due > period:
            late += 1
        robot.command_lengths(home - amplitude_m * np.sin(2 * np.pi * 0.5 * k * period))
        reading = robot.read()
        ages[k] = (time.monotonic() - reading.t) * 1e3
        fresh += reading.seq != last_seq
        last_seq = reading.seq
        if reading.status & msg.Status.WATCHDOG_STOP:  # a host stall > WATCHDOG_MS: resume
            trips += 1
            robot.enable()
    return StreamResult(n, fresh, ages, late, trips)
