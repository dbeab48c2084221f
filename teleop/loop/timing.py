"""Pacing and timing statistics of the loop.

Pacing (CHAI3D / OpenHaptics style, in Python): sleep until `spin` before the deadline, then spin on
time.perf_counter_ns(); the schedule is absolute (deadline_k = t0 + k T), so lateness does not accumulate.
A tick that starts more than one period late skips the missed deadlines (counted) instead of bursting.
"""

from __future__ import annotations

import time

import numpy as np

from teleop.loop.core import STAGES

LATE_NS = 500_000  # a tick more than 0.5 ms late is a deadline miss (RELIABILITY.md)


def set_realtime(priority: int) -> str:
    """Ask for SCHED_FIFO at `priority` for this process (as haptic servo threads run on a real rig).

    Returns what was obtained, e.g. "SCHED_FIFO 50" or "SCHED_OTHER (PermissionError: ...)". The kernel's
    RT throttling (sched_rt_runtime_us) still leaves other processes 5 % of each CPU.
    """
    import os

    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(int(priority)))
        return f"SCHED_FIFO {int(priority)}"
    except (AttributeError, OSError) as exc:
        return f"SCHED_OTHER ({type(exc).__name__}: {exc})"


def set_normal() -> None:
    """Back to the default time-sharing policy."""
    import os

    try:
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    except (AttributeError, OSError):
        pass


def wait_until(deadline_ns: int, spin_ns: int = 200_000) -> int:
    """Sleep, then spin, until perf_counter_ns() >= deadline_ns; returns the wake time [ns]."""
    pc, sleep = time.perf_counter_ns, time.sleep
    now = pc()
    rem = deadline_ns - now
    if rem > spin_ns:
        sleep((rem - spin_ns) * 1e-9)
    while True:
        now = pc()
        if now >= deadline_ns:
            return now


def percentiles_us(values_ns: np.ndarray) -> dict:
    """{"p50", "p99", "p999", "max", "mean"} of a nanosecond array, in microseconds."""
    v = np.asarray(values_ns, dtype=float)
    if v.size == 0:
        return {"p50": 0.0, "p99": 0.0, "p999": 0.0, "max": 0.0, "mean": 0.0}
    p50, p99, p999 = np.percentile(v, [50, 99, 99.9])
    return {"p50": round(p50 / 1e3, 3), "p99": round(p99 / 1e3, 3), "p999": round(p999 / 1e3, 3),
            "max": round(float(v.max()) / 1e3, 3), "mean": round(float(v.mean()) / 1e3, 3)}


class TimingLog:
    """Preallocated per-tick timing: lateness, tick duration and per-stage durations [ns]."""

    def __init__(self, capacity: int):
        self.lateness = np.zeros(capacity, dtype=np.int64)
        self.tick = np.zeros(capacity, dtype=np.int64)
        self.stages = np.zeros((capacity, len(STAGES)), dtype=np.int64)
        self.n = 0
        self.skipped = 0

    def add(self, lateness_ns: int, tick_ns: int, stage_ns: np.ndarray) -> None:
        i = self.n
        if i < len(self.tick):
            self.lateness[i] = lateness_ns
            self.tick[i] = tick_ns
            self.stages[i] = stage_ns
            self.n = i + 1

    def summary(self, rate_hz: float) -> dict:
        """The `teleop bench loop` JSON body (DESIGN.md) for the ticks logged so far."""
        n = self.n
        lat, tick = self.lateness[:n], self.tick[:n]
        t = percentiles_us(tick)
        la = percentiles_us(lat)
        return {
            "rate_hz": rate_hz,
            "ticks": int(n),
            "tick_us": {"p50": t["p50"], "p99": t["p99"], "max": t["max"]},
            "lateness_us": {"p50": la["p50"], "p99": la["p99"], "p999": la["p999"], "max": la["max"]},
            "deadline_misses": int((lat > LATE_NS).sum()) + int(self.skipped),
            "stages_us": {name: {k: v for k, v in percentiles_us(self.stages[:n, j]).items() if k in ("p50", "p99")}
                          for j, name in enumerate(STAGES)},
        }


def run_paced(tp, seconds: float, rate_hz: float, log: TimingLog | None = None, spin_us: float = 200.0,
              on_tick=None, should_stop=None, on_start=None) -> TimingLog:
    """Run `tp.tick(now)` at `rate_hz` for `seconds` (now = seconds since start); returns the timing log.

    `on_start(t0_wall_ns)` is told the wall-clock time of session time 0; `on_tick(k, lateness_ns)` runs after
    each tick; `should_stop()` ends the run early when it returns True.
    """
    period = int(round(1e9 / rate_hz))
    n = int(round(seconds * rate_hz))
    log = log or TimingLog(n)
    spin = int(spin_us * 1e3)
    pc = time.perf_counter_ns
    t0 = pc() + period
    if on_start is not None:
        on_start(time.time_ns() + (t0 - pc()))
    tp.start(0.0)
    k_sched = 0
    for _ in range(n):
        deadline = t0 + k_sched * period
        wake = wait_until(deadline, spin)
        late = wake - deadline
        if late > period:  # skip the deadlines already missed; keep the absolute schedule
            missed = late // period
            log.skipped += int(missed)
            k_sched += int(missed)
            deadline = t0 + k_sched * period
            late = wake - deadline
        tp.lateness_ns = late
        tp.tick((wake - t0) * 1e-9)
        end = pc()
        tp.prev_tick_ns = end - wake
        log.add(late, end - wake, tp.stage_ns)
        if on_tick is not None:
            on_tick(tp.k - 1, late)
        k_sched += 1
        if should_stop is not None and should_stop():
            break
    return log
