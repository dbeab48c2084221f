"""Safety monitors of the loop (RELIABILITY.md "Watchdogs" and "Limits"): each returns a fault reason or None.

Monitors hold a little state and are updated once per tick with the host time `now` [s]; none of them
trips on a single noisy sample: a condition must persist for its window.
"""

from __future__ import annotations

import math

import numpy as np


class Freshness:
    """Telemetry watchdog: a source is stale when its sequence number (or timestamp) has not advanced for
    longer than `limit` [s], and missing when nothing arrived within `startup` [s] of `reset(now)` (None:
    `limit`, so silence from the start faults as soon as silence after a frame would)."""

    def __init__(self, name: str, limit: float, startup: float | None = None):
        self.name, self.limit = name, limit
        self.startup = limit if startup is None else startup
        self.reset(0.0)

    def reset(self, now: float) -> None:
        self.t_start = now
        self.t_fresh = None
        self.last_key = None

    def update(self, now: float, key) -> None:
        """Note a value identified by `key` (seq or timestamp) received at host time `now`."""
        if key is not None and key != self.last_key:
            self.last_key = key
            self.t_fresh = now

    def age(self, now: float) -> float:
        """Seconds since the last fresh value (inf before the first one)."""
        return math.inf if self.t_fresh is None else now - self.t_fresh

    def check(self, now: float) -> str | None:
        if self.t_fresh is None:
            if now - self.t_start > self.startup:
                return f"{self.name} telemetry missing for {1e3 * (now - self.t_start):.1f} ms"
            return None
        age = now - self.t_fresh
        if age > self.limit:
            return f"{self.name} telemetry stale: {1e3 * age:.1f} ms > {1e3 * self.limit:.1f} ms"
        return None

    def is_fresh(self, now: float) -> bool:
        return self.t_fresh is not None and now - self.t_fresh <= self.limit


class TensionRange:
    """Over-range or slack tension on any cable persisting longer than `window` [s] -> fault.

    Six cables per tick: plain floats (numpy's per-call cost would dominate)."""

    def __init__(self, t_max: float, t_slack: float, window: float, n: int = 6):
        self.t_max, self.t_slack, self.window, self.n = t_max, t_slack, window, n
        self.reset()

    def reset(self) -> None:
        self.since_over = [None] * self.n  # host time the condition started [s], None while it does not hold
        self.since_slack = [None] * self.n

    def update(self, now: float, t) -> str | None:
        t = [float(v) for v in t]
        t_max, t_slack, window = self.t_max, self.t_slack, self.window
        for since, what, over in ((self.since_over, "over-range", True), (self.since_slack, "slack", False)):
            for i, ti in enumerate(t):
                if (ti > t_max) if over else (ti < t_slack):
                    if since[i] is None:
                        since[i] = now
                    elif now - since[i] > window:
                        return (f"cable {i + 1} tension {what} for {1e3 * (now - since[i]):.1f} ms "
                                f"({ti:.3f} N; limits {t_slack:g}..{t_max:g} N)")
                else:
                    since[i] = None
        return None


class StuckCable:
    """A cable commanded to pay out (length increasing) whose tension keeps rising is stuck (seed 000 §1).

    The pay-out streak of each cable starts when its commanded length begins to increase; once the streak has
    lasted `window` [s], a tension more than `rise` [N] above the lowest tension of the streak, seen on
    `confirm` consecutive updates, reports the cable stuck. A pause or reversal of the command ends the streak.
    Tensions are low-pass filtered first (time constant `tau` [s]) so sensor noise and FSR branch flips
    do not count as a rise. Plain floats, like TensionRange.
    """

    def __init__(self, window: float, rise: float, payout_eps: float, n: int = 6, confirm: int = 3,
                 tau: float = 0.02):
        self.window, self.rise, self.eps, self.confirm, self.tau, self.n = window, rise, payout_eps, confirm, tau, n
        self.Tmin = [0.0] * n
        self.t_prev = None
        self.reset()

    def reset(self) -> None:
        self.t0 = [None] * self.n  # start of each cable's pay-out streak [s], None outside one
        self.count = [0] * self.n
        self.tf = None

    def update(self, now: float, t, dL) -> str | None:
        t = [float(v) for v in t]
        if self.tf is None:
            self.tf = t
        else:  # tf += a (t - tf), a = 1 - exp(-dt / tau)
            a = 1.0 - math.exp(-max(now - self.t_prev, 0.0) / self.tau)
            self.tf = [f + a * (ti - f) for f, ti in zip(self.tf, t)]
        self.t_prev = now
        tf, t0, Tmin, count = self.tf, self.t0, self.Tmin, self.count
        bad = None
        for i, (ti, dl) in enumerate(zip(tf, dL)):
            if not float(dl) > self.eps:  # not paying out: the streak ends
                t0[i] = None
                count[i] = 0
                continue
            if t0[i] is None:
                t0[i], Tmin[i] = now, ti
            elif ti < Tmin[i]:
                Tmin[i] = ti
            if now - t0[i] >= self.window and ti - Tmin[i] > self.rise:
                count[i] += 1
                if count[i] >= self.confirm and bad is None:
                    bad = i
            else:
                count[i] = 0
        if bad is not None:
            return (f"cable {bad + 1} stuck: tension rose {tf[bad] - Tmin[bad]:.2f} N over "
                    f"{1e3 * (now - t0[bad]):.0f} ms while paying out")
        return None


def _all_finite(values) -> bool:
    return all(math.isfinite(v) for v in (values.tolist() if hasattr(values, "tolist") else values))


def is_finite_sample(sample) -> bool:
    """True when a HapticSample's numbers are all finite."""
    return (_all_finite(sample.measured_cp) and _all_finite(sample.measured_cv)
            and _all_finite(np.ravel(sample.orientation)) and math.isfinite(sample.t))


def is_finite_reading(reading) -> bool:
    """True when a RobotReading's numbers are all finite."""
    return (_all_finite(reading.fsr_counts) and _all_finite(reading.position_steps)
            and _all_finite(reading.commanded_lengths) and math.isfinite(reading.t))
