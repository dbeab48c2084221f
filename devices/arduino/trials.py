"""Measurements on the emulated link: watchdog stop time (emulated clock) and round-trip latency (wall).

Used by the tests (which assert the watchdog bound) and by ``teleop bench link`` (which reports both).
"""

from __future__ import annotations

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


def watchdog_trials(robot: ArduinoRobot, mega: EmulatedMega, home_lengths, n: int = 100,
                    stream_s: float = 0.010, silence_ms: float = 60.0, travel_m: float = 0.02,
                    max_attempts: int | None = None) -> WatchdogTrials:
    """Run n episodes: ENABLE, command a far target, stream heartbeats for stream_s [s] of wall time
    while the motors accelerate, go silent, and read the stop time from the harness once silence_ms of
    emulated time have passed since the last received byte (silence_ms above the bound being tested: a
    motor still running then shows a stop time of about silence_ms)."""
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
        if reading.status & msg.Status.WATCHDOG_STOP or not reading.status & msg.Status.MOVING:
            early += 1
            continue
        while True:
            time.sleep(0.01)
            status = mega.status()
            if status["t_ns"] - status["last_rx_ns"] >= silence_ms * 1e6:
                break
        stop_ms.append((status["last_step_ns"] - status["last_rx_ns"]) * 1e-6)
        steps_after.append(status["steps_after_rx"])
        latched.append(bool(robot.read_fresh().status & msg.Status.WATCHDOG_STOP))
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
