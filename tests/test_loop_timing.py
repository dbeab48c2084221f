"""Pacing and timing statistics (logic only: wall-clock numbers come from `teleop bench loop`)."""

import time

import numpy as np

from teleop.loop.core import STAGES
from teleop.loop.tap import session_layout
from teleop.loop.timing import LATE_NS, TimingLog, run_paced, wait_until
from teleop.recording import SecondStats


def test_wait_until_never_returns_early():
    for spin in (0, 50_000, 200_000):
        deadline = time.perf_counter_ns() + 300_000
        assert wait_until(deadline, spin) >= deadline


class Stub:
    def __init__(self):
        self.k = 0
        self.stage_ns = np.arange(len(STAGES), dtype=np.int64)
        self.times = []

    def start(self, now):
        self.started = now

    def tick(self, now):
        self.times.append(now)
        self.k += 1


def test_run_paced_absolute_schedule_and_summary():
    tp = Stub()
    t0 = []
    log = run_paced(tp, 0.03, 1000.0, on_start=t0.append)
    assert log.n == 30 and len(tp.times) == 30 and t0 and tp.started == 0.0
    assert np.all(np.diff(tp.times) > 0) and np.all(log.lateness[:30] >= 0)
    assert tp.times[-1] >= 0.029  # tick k does not start before k periods
    s = log.summary(1000.0)
    assert set(s) == {"rate_hz", "ticks", "tick_us", "lateness_us", "deadline_misses", "stages_us"}
    assert list(s["stages_us"]) == list(STAGES)


def test_summary_counts_misses_and_skips():
    log = TimingLog(1000)
    for i in range(1000):
        log.add(LATE_NS + 1 if i % 100 == 0 else 1000, 5000, np.zeros(len(STAGES)))
    log.skipped = 3
    s = log.summary(1000.0)
    assert s["deadline_misses"] == 13
    assert s["lateness_us"]["max"] == round((LATE_NS + 1) / 1e3, 3) and s["lateness_us"]["p50"] == 1.0


def test_per_second_stats_from_rows():
    layout = session_layout()
    sl = layout.slices()
    stats = SecondStats(layout)
    out = []
    for k in range(2500):
        row = np.zeros(layout.width)
        row[sl[("/loop", "t")][0]] = k * 1e-3
        row[sl[("/loop", "lateness_us")][0]] = 600.0 if k % 500 == 0 else 10.0
        s = stats.add(row)
        if s:
            out.append(s)
    assert [s["second"] for s in out] == [0, 1] and [s["ticks"] for s in out] == [1000, 1000]
    assert out[0]["misses"] == 2 and out[0]["lateness_us"]["max"] == 600.0
