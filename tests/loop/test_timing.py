"""Pacing and timing statistics (logic only: wall-clock numbers come from `teleop bench loop`)."""

import time

import numpy as np
import pytest

from teleop.loop.core import STAGES
from teleop.loop.tap import session_layout
from teleop.loop.timing import (LATE_NS, TimingLog, budget_verdict, format_histogram, period_histogram,
                                 run_paced, wait_until)
from teleop.io.recording import SecondStats


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


class FakeTime:
    """A controlled clock for teleop.loop.timing: sleep() advances it, each perf_counter_ns() call advances
    it by `spin_ns` (one turn of the spin loop), and ticks advance it by their cost."""

    def __init__(self, spin_ns=1_000):
        self.now, self.spin_ns = 5_000_000_000, spin_ns

    def perf_counter_ns(self):
        self.now += self.spin_ns
        return self.now

    def sleep(self, s):
        self.now += int(s * 1e9)

    def time_ns(self):
        return self.now + 1_700_000_000_000_000_000


class CostlyStub(Stub):
    def __init__(self, clock, cost_ns):
        super().__init__()
        self.clock, self.cost_ns = clock, cost_ns

    def tick(self, now):
        super().tick(now)
        self.clock.now += self.cost_ns(self.k - 1)


def test_run_paced_absolute_schedule_and_summary(monkeypatch):
    """30 ticks of 100 us at 1 kHz on a controlled clock: tick k starts k periods after the start, within
    one spin turn; the summary has the loop-timing keys and the period histogram counts every period."""
    import teleop.loop.timing as timing

    clock = FakeTime()
    monkeypatch.setattr(timing, "time", clock)
    tp = CostlyStub(clock, lambda k: 100_000)
    t0 = []
    log = run_paced(tp, 0.03, 1000.0, on_start=t0.append)
    assert log.n == 30 and len(tp.times) == 30 and t0 and tp.started == 0.0 and log.skipped == 0
    np.testing.assert_allclose(tp.times, np.arange(30) * 1e-3, atol=2e-6)  # within 2 spin turns
    assert np.all(log.lateness[:30] >= 0) and np.all(log.lateness[:30] < 2_000)
    s = log.summary(1000.0)
    assert {"rate_hz", "ticks", "tick_us", "lateness_us", "deadline_misses", "stages_us"} <= set(s)  # docs/formats.md
    assert list(s["stages_us"]) == list(STAGES)
    assert sum(s["period_histogram"]["counts"]) + s["period_histogram"]["overflow"] == 29  # 30 starts
    assert abs(s["period_us"]["p50"] - 1000.0) <= 2.0 and s["deadline_misses"] == 0
    assert abs(s["tick_us"]["p50"] - 100.0) <= 2.0


def test_run_paced_skips_missed_deadlines_and_keeps_the_absolute_schedule(monkeypatch):
    """Tick 5 takes 2.7 periods: deadline 6 is skipped (counted), tick 6 starts 0.7 ms late on deadline 7,
    and the ticks after it are back on the original grid."""
    import teleop.loop.timing as timing

    clock = FakeTime()
    monkeypatch.setattr(timing, "time", clock)
    tp = CostlyStub(clock, lambda k: 2_700_000 if k == 5 else 50_000)
    log = run_paced(tp, 0.02, 1000.0)
    assert log.skipped == 1 and len(tp.times) == 20
    np.testing.assert_allclose(tp.times[6], 7.7e-3, atol=5e-6)  # clock turns: a few us
    np.testing.assert_allclose(tp.times[7:], (np.arange(7, 20) + 1) * 1e-3, atol=3e-6)
    assert abs(log.lateness[6] - 700_000) < 5_000
    assert log.summary(1000.0)["deadline_misses"] == 2  # the late tick and the skipped deadline


def test_run_paced_stops_when_asked(monkeypatch):
    import teleop.loop.timing as timing

    clock = FakeTime()
    monkeypatch.setattr(timing, "time", clock)
    tp = CostlyStub(clock, lambda k: 10_000)
    log = run_paced(tp, 1.0, 1000.0, should_stop=lambda: tp.k >= 7)
    assert log.n == 7 and tp.k == 7


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


def synthetic_log(n=100_000, period=1_000_000, late_every=None, late_ns=0, seed=0):
    """A TimingLog of n ticks on an absolute 1 kHz schedule with seeded jitter (0..20 us) and every
    `late_every`-th tick started `late_ns` late."""
    rng = np.random.default_rng(seed)
    late = rng.integers(0, 20_000, n)
    if late_every:
        late[::late_every] = late_ns
    log = TimingLog(n)
    for k in range(n):
        log.add(int(late[k]), 50_000, np.zeros(len(STAGES)), k * period + int(late[k]))
    return log, late


def test_period_histogram_bins_counts_and_overflow():
    T = 1_000_000
    periods = np.array([T, T + 24_999, T + 25_000, T - 25_000, 2 * T, 3 * T - 25_001, 3 * T - 25_000, 10 * T])
    h = period_histogram(periods, T)
    assert h["nominal_us"] == 1000.0 and h["bin_us"] == 50.0 and len(h["edges_us"]) == len(h["counts"]) + 1 == 61
    assert h["edges_us"][20] == 975.0 and h["edges_us"][21] == 1025.0  # the nominal period is a bin centre
    c = h["counts"]
    assert c[20] == 3 and c[21] == 1 and c[40] == 1 and c[59] == 1  # T-25us and T+24.999us both in bin 20
    assert h["overflow"] == 2 and sum(c) + h["overflow"] == len(periods)
    text = format_histogram(h)
    assert text.count("\n") == 5 and ">=" in text  # header + 4 non-empty bins + overflow


def test_summary_histogram_from_synthetic_ticks_matches_numpy():
    log, late = synthetic_log(late_every=997, late_ns=700_000)
    s = log.summary(1000.0)
    periods = 1_000_000 + np.diff(late)
    h = s["period_histogram"]
    ref, _ = np.histogram(periods, bins=np.array(h["edges_us"]) * 1e3)
    assert h["counts"] == ref.tolist() and h["overflow"] == 0
    assert s["period_us"]["max"] == round(periods.max() / 1e3, 3)
    assert s["period_us"]["min"] == round(periods.min() / 1e3, 3)
    assert abs(s["period_us"]["mean"] - periods.mean() / 1e3) < 1e-3
    assert s["deadline_misses"] == len(late[::997])


@pytest.mark.parametrize("late_every, expect_pass", [(1001, True), (999, False)])
def test_budget_pass_fail_on_synthetic_ticks(late_every, expect_pass):
    """100 000 ticks with every 1001st 0.7 ms late: 100 misses, 0.1 % (pass); every 999th: 101 (fail)."""
    log, late = synthetic_log(late_every=late_every, late_ns=700_000)
    v = budget_verdict(log.summary(1000.0), seconds=100.0, recording=True)
    assert v["pass"] is expect_pass and v["conclusive"] and v["why_not"] == []
    assert v["miss_fraction"] == pytest.approx(len(late[::late_every]) / len(late))


def test_budget_exactly_half_a_millisecond_is_not_late_and_skips_count():
    log, _ = synthetic_log(n=10_000, late_every=2, late_ns=LATE_NS)
    s = log.summary(1000.0)
    assert s["deadline_misses"] == 0 and budget_verdict(s, 60.0, True)["pass"]
    log.skipped = 11  # 11 deadlines skipped: 11 / 10 011 > 0.1 %
    v = budget_verdict(log.summary(1000.0), 60.0, True)
    assert not v["pass"] and v["miss_fraction"] == pytest.approx(11 / 10_011)


def test_budget_short_slow_or_unrecorded_run_is_not_conclusive():
    log, _ = synthetic_log(n=1000)
    v = budget_verdict(log.summary(1000.0), seconds=10.0, recording=False)
    assert v["pass"] and not v["conclusive"]
    assert any("--seconds 60" in w for w in v["why_not"]) and any("recording" in w for w in v["why_not"])
    assert not budget_verdict(log.summary(500.0), 60.0, True)["conclusive"]


def test_a_deadline_miss_is_more_than_half_a_period_late():
    from teleop.loop.timing import late_threshold_ns

    assert late_threshold_ns(1000.0) == LATE_NS and late_threshold_ns(4000.0) == 125_000
    log = TimingLog(400)
    for i in range(400):  # 130 us late every 100th tick: a miss at 4 kHz, not at 1 kHz
        log.add(130_000 if i % 100 == 0 else 1000, 5000, np.zeros(len(STAGES)))
    fast, slow = log.summary(4000.0), log.summary(1000.0)
    assert fast["late_threshold_us"] == 125.0 and fast["deadline_misses"] == 4
    assert slow["late_threshold_us"] == 500.0 and slow["deadline_misses"] == 0
    v = budget_verdict(fast, 60.0, True)
    assert "0.125 ms" in v["criterion"] and v["conclusive"]   # 4 kHz is a budget rate too (CHAI3D's)


def test_run_stepped_ticks_at_exact_periods_and_sets_the_devices_clock():
    from teleop.loop.timing import SimClock, run_stepped

    tp, clock, seen = Stub(), SimClock(), []
    tick = tp.tick
    tp.tick = lambda now: (seen.append(clock()), tick(now))
    log = run_stepped(tp, 0.01, 4000.0, clock=clock)
    assert tp.times == pytest.approx([k * 250e-6 for k in range(40)], rel=1e-12, abs=0)  # whatever the speed
    assert seen == tp.times                                # the devices read the tick's own time
    assert log.n == 40 and not log.lateness[:40].any() and list(log.start[:3]) == [0, 250_000, 500_000]


def test_run_stepped_keeps_its_own_clock_when_none_is_given():
    from teleop.loop.timing import run_stepped

    tp = Stub()
    log = run_stepped(tp, 0.003, 1000.0)
    assert tp.times == pytest.approx([0.0, 1e-3, 2e-3], rel=1e-12, abs=0) and log.n == 3
