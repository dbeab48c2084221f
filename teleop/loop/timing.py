"""Pacing and timing statistics of the loop.

Pacing (CHAI3D / OpenHaptics style, in Python): sleep until `spin` before the deadline, then spin on
time.perf_counter_ns(); the schedule is absolute (deadline_k = t0 + k T), so lateness does not accumulate.
A tick that starts more than one period late skips the missed deadlines (counted) instead of bursting.
"""

from __future__ import annotations

import os
import time

import numpy as np

from teleop.loop.core import STAGES

LATE_NS = 500_000  # a tick more than 0.5 ms late is a deadline miss at 1 kHz (docs/safety.md)


def late_threshold_ns(rate_hz: float) -> int:
    """Lateness [ns] beyond which a tick is a deadline miss: half a period (0.5 ms at 1 kHz, docs/safety.md;
    0.125 ms at 4 kHz)."""
    return int(round(0.5e9 / rate_hz))


def set_realtime(priority: int) -> str:
    """Ask for SCHED_FIFO at `priority` for this process (as haptic servo threads run on a real rig).

    Returns what was obtained, e.g. "SCHED_FIFO 50" or "SCHED_OTHER (PermissionError: ...)". The kernel's
    RT throttling (sched_rt_runtime_us) still leaves other processes 5 % of each CPU.
    """
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(int(priority)))
        return f"SCHED_FIFO {int(priority)}"
    except (AttributeError, OSError) as exc:
        return f"SCHED_OTHER ({type(exc).__name__}: {exc})"


def set_normal() -> None:
    """Back to the default time-sharing policy."""
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


HIST_BINS_PER_PERIOD = 20  # period histogram bin width: T / 20 (50 us at 1 kHz)
HIST_SPAN_PERIODS = 3  # bins cover [0, 3 T); longer periods go to the overflow count


def period_histogram(periods_ns: np.ndarray, period_ns: int) -> dict:
    """Histogram of tick-to-tick periods (start of tick k-1 -> start of tick k) [ns in, us out].

    Bins of width w = T / 20 centred on multiples of w (T = the nominal period `period_ns`, so the nominal
    period is a bin centre), edges -w/2, w/2, ..., 3 T - w/2; `overflow` counts the periods at or past the
    last edge (a tick that skipped deadlines). Returns {"nominal_us", "bin_us", "edges_us" (n + 1,),
    "counts" (n,), "overflow"}.
    """
    v = np.asarray(periods_ns, dtype=np.float64)
    width = period_ns / HIST_BINS_PER_PERIOD
    nbins = HIST_BINS_PER_PERIOD * HIST_SPAN_PERIODS
    idx = np.floor(v / width + 0.5).astype(np.int64)  # bin i: [(i - 1/2) w, (i + 1/2) w)
    counts = np.bincount(idx[(idx >= 0) & (idx < nbins)], minlength=nbins)
    return {"nominal_us": round(period_ns / 1e3, 3), "bin_us": round(width / 1e3, 3),
            "edges_us": [round((i - 0.5) * width / 1e3, 3) for i in range(nbins + 1)],
            "counts": [int(c) for c in counts], "overflow": int((idx >= nbins).sum())}


def format_histogram(hist: dict, width: int = 40) -> str:
    """Compact text view of a period_histogram(): one line per non-empty bin, bar length ~ log10(count)."""
    counts = list(hist["counts"]) + [hist["overflow"]]
    edges = hist["edges_us"]
    top = max(1.0, float(np.log10(max(counts) + 1)))
    lines = [f"period histogram (nominal {hist['nominal_us']:g} us, bins {hist['bin_us']:g} us, bar ~ log count)"]
    for i, c in enumerate(counts):
        if not c:
            continue
        label = f"[{edges[i]:7.0f}, {edges[i + 1]:7.0f})" if i < len(hist["counts"]) else f">= {edges[-1]:7.0f}     "
        bar = "#" * max(1, int(round(width * np.log10(c + 1) / top)))
        lines.append(f"  {label} us {c:9d} {bar}")
    return "\n".join(lines)


BUDGET_RATES_HZ = (1000.0, 4000.0)  # the loop rates the timing budget is checked at (1 kHz; CHAI3D's 4 kHz)


def budget_verdict(summary: dict, seconds: float, recording: bool, max_fraction: float = 0.001,
                   min_seconds: float = 60.0, rates_hz: tuple = BUDGET_RATES_HZ) -> dict:
    """The timing budget of docs/safety.md on a loop summary: <= max_fraction of ticks more than half a period
    late (skipped deadlines count), over >= min_seconds [s] at one of rates_hz [Hz] with recording on.

    `pass` is the criterion on the misses; `conclusive` says whether the run was long enough, at a budget rate
    and with recording on, for the pass to count as the budget check (`why_not` lists what is missing).
    """
    ticks = int(summary["ticks"])
    misses = int(summary["deadline_misses"])
    frac = misses / max(1, ticks + summary.get("skipped", 0))
    rates = " or ".join(f"{r:g}" for r in rates_hz)
    why = []
    if seconds < min_seconds:
        why.append(f"needs --seconds {min_seconds:g} (ran {seconds:g} s)")
    if summary["rate_hz"] not in rates_hz:
        why.append(f"needs --rate {rates} (ran {summary['rate_hz']:g} Hz)")
    if not recording:
        why.append("needs recording on")
    late_ms = late_threshold_ns(summary["rate_hz"]) / 1e6
    return {"criterion": f"<= {100 * max_fraction:g} % of ticks > {late_ms:g} ms (half a period) late over >= "
                         f"{min_seconds:g} s at {summary['rate_hz']:g} Hz ({rates} Hz), recording on",
            "miss_fraction": frac, "max_miss_fraction": max_fraction, "pass": bool(frac <= max_fraction),
            "conclusive": not why, "why_not": why}


class TimingLog:
    """Preallocated per-tick timing: lateness, tick duration, per-stage durations and tick start [ns]."""

    def __init__(self, capacity: int):
        self.lateness = np.zeros(capacity, dtype=np.int64)
        self.tick = np.zeros(capacity, dtype=np.int64)
        self.start = np.zeros(capacity, dtype=np.int64)
        self.stages = np.zeros((capacity, len(STAGES)), dtype=np.int64)
        self.n = 0
        self.skipped = 0

    def add(self, lateness_ns: int, tick_ns: int, stage_ns: np.ndarray, start_ns: int = 0) -> None:
        """Log one tick; `start_ns` is its start (wake) time on any fixed clock [ns]."""
        i = self.n
        if i < len(self.tick):
            self.lateness[i] = lateness_ns
            self.tick[i] = tick_ns
            self.start[i] = start_ns
            self.stages[i] = stage_ns
            self.n = i + 1

    def periods(self) -> np.ndarray:
        """(n - 1,) start-to-start periods of the logged ticks [ns]."""
        return np.diff(self.start[:self.n])

    def summary(self, rate_hz: float) -> dict:
        """The `teleop bench loop` JSON body (docs/formats.md) for the ticks logged so far, plus the period
        statistics ("period_us": mean, p50, p99, p999, max, min) and histogram ("period_histogram")."""
        n = self.n
        lat, tick = self.lateness[:n], self.tick[:n]
        t = percentiles_us(tick)
        la = percentiles_us(lat)
        periods = self.periods()
        pe = percentiles_us(periods)
        pe["min"] = round(float(periods.min()) / 1e3, 3) if periods.size else 0.0
        return {
            "rate_hz": rate_hz,
            "ticks": int(n),
            "tick_us": {"p50": t["p50"], "p99": t["p99"], "max": t["max"]},
            "lateness_us": {"p50": la["p50"], "p99": la["p99"], "p999": la["p999"], "max": la["max"]},
            "late_threshold_us": late_threshold_ns(rate_hz) / 1e3,
            "deadline_misses": int((lat > late_threshold_ns(rate_hz)).sum()) + int(self.skipped),
            "stages_us": {name: {k: v for k, v in percentiles_us(self.stages[:n, j]).items() if k in ("p50", "p99")}
                          for j, name in enumerate(STAGES)},
            "skipped": int(self.skipped),
            "period_us": {k: pe[k] for k in ("mean", "p50", "p99", "p999", "max", "min")},
            "period_histogram": period_histogram(periods, int(round(1e9 / rate_hz))),
        }


def default_spin_us(rate_hz: float) -> float:
    """Spin before each deadline [us]: 200 us, at most half the period. A SCHED_FIFO loop that spins
    through the whole period (200 us of a 250 us period at 4 kHz) hits the kernel's real-time throttle
    (sched_rt_runtime_us: 950 ms of each second) and is stopped for ~50 ms every second: 5 % of the ticks.
    Less spin means more sleeps, whose wake-ups a shared virtual machine sometimes delays by milliseconds;
    half the period is the compromise."""
    return min(200.0, 0.5e6 / rate_hz)


class SimClock:
    """The session time of a simulated clock [s]: callable like time.perf_counter, read by the simulated devices
    (the stylus's script, the feed-forward's command timing); `run_stepped` sets it before each tick."""

    __slots__ = ("now",)

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def run_stepped(tp, seconds: float, rate_hz: float, log: TimingLog | None = None, on_tick=None,
                should_stop=None, on_start=None, clock: SimClock | None = None) -> TimingLog:
    """Run `tp.tick(k / rate_hz)` for k = 0 .. seconds * rate_hz - 1 on a simulated clock: no waiting, tick k
    at exactly k periods, as fast as the machine runs. The same inputs give the same session on any machine
    and load (a paced session's tick times follow the scheduler); lateness is 0 by construction and the log's
    tick durations are the machine's. `clock`, if given, reads the tick's time (the devices' clock). Other
    arguments as `run_paced`.
    """
    period = int(round(1e9 / rate_hz))
    n = int(round(seconds * rate_hz))
    log = log or TimingLog(n)
    pc = time.perf_counter_ns
    if on_start is not None:
        on_start(time.time_ns())
    tp.start(0.0)
    clock = clock if clock is not None else SimClock()
    for k in range(n):
        tp.lateness_ns = 0
        clock.now = now = k * period * 1e-9
        wake = pc()
        tp.tick(now)
        end = pc()
        tp.prev_tick_ns = end - wake
        log.add(0, end - wake, tp.stage_ns, k * period)
        if on_tick is not None:
            on_tick(tp.k - 1, 0)
        if should_stop is not None and should_stop():
            break
    return log


def run_paced(tp, seconds: float, rate_hz: float, log: TimingLog | None = None, spin_us: float | None = None,
              on_tick=None, should_stop=None, on_start=None) -> TimingLog:
    """Run `tp.tick(now)` at `rate_hz` for `seconds` (now = seconds since start); returns the timing log.
    spin_us: spin before each deadline (default_spin_us(rate_hz) when None).

    `on_start(t0_wall_ns)` is told the wall-clock time of session time 0; `on_tick(k, lateness_ns)` runs after
    each tick; `should_stop()` ends the run early when it returns True.
    """
    period = int(round(1e9 / rate_hz))
    n = int(round(seconds * rate_hz))
    log = log or TimingLog(n)
    spin = int((default_spin_us(rate_hz) if spin_us is None else spin_us) * 1e3)
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
        log.add(late, end - wake, tp.stage_ns, wake - t0)
        if on_tick is not None:
            on_tick(tp.k - 1, late)
        k_sched += 1
        if should_stop is not None and should_stop():
            break
    return log
