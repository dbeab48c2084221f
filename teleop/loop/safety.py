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
    """Over-range or slack tension on any cable persisting longer than `window` [s] -> fault."""

    def __init__(self, t_max: float, t_slack: float, window: float, n: int = 6):
        self.t_max, self.t_slack, self.window = t_max, t_slack, window
        self.since_over = np.full(n, np.nan)
        self.since_slack = np.full(n, np.nan)

    def reset(self) -> None:
        self.since_over[:] = np.nan
        self.since_slack[:] = np.nan

    def update(self, now: float, t) -> str | None:
        t = np.asarray(t, dtype=float)
        for since, cond, what in ((self.since_over, t > self.t_max, "over-range"),
                                  (self.since_slack, t < self.t_slack, "slack")):
            since[~cond] = np.nan
            start = cond & np.isnan(since)
            since[start] = now
            held = now - since
            bad = np.flatnonzero(held > self.window)
            if bad.size:
                i = int(bad[0])
                return (f"cable {i + 1} tension {what} for {1e3 * held[i]:.1f} ms "
                        f"({t[i]:.3f} N; limits {self.t_slack:g}..{self.t_max:g} N)")
        return None


class StuckCable:
    """A cable commanded to pay out (length increasing) whose tension keeps rising is stuck (seed 000 §1).

    The pay-out streak of each cable starts when its commanded length begins to increase; once the streak has
    lasted `window` [s], a tension more than `rise` [N] above the lowest tension of the streak, seen on
    `confirm` consecutive updates, reports the cable stuck. A pause or reversal of the command ends the streak.
    Tensions are low-pass filtered first (time constant `tau` [s]) so sensor noise and FSR branch flips
    do not count as a rise.
    """

    def __init__(self, window: float, rise: float, payout_eps: float, n: int = 6, confirm: int = 3,
                 tau: float = 0.02):
        self.window, self.rise, self.eps, self.confirm, self.tau = window, rise, payout_eps, confirm, tau
        self.t0 = np.full(n, np.nan)
        self.Tmin = np.zeros(n)
        self.count = np.zeros(n, dtype=int)
        self.tf = None
        self.t_prev = None

    def reset(self) -> None:
        self.t0[:] = np.nan
        self.count[:] = 0
        self.tf = None

    def update(self, now: float, t, dL) -> str | None:
        t = np.asarray(t, dtype=float)
        if self.tf is None:
            self.tf = t.copy()
        else:  # tf += a (t - tf), a = 1 - exp(-dt / tau)
            self.tf += (1.0 - math.exp(-max(now - self.t_prev, 0.0) / self.tau)) * (t - self.tf)
        self.t_prev = now
        t = self.tf
        paying = np.asarray(dL, dtype=float) > self.eps
        self.t0[~paying] = np.nan
        start = paying & np.isnan(self.t0)
        self.t0[start] = now
        self.Tmin[start] = t[start]
        np.minimum(self.Tmin, t, out=self.Tmin, where=paying)
        held = now - self.t0
        cond = (held >= self.window) & (t - self.Tmin > self.rise)
        self.count = np.where(cond, self.count + 1, 0)
        bad = np.flatnonzero(self.count >= self.confirm)
        if bad.size:
            i = int(bad[0])
            return (f"cable {i + 1} stuck: tension rose {t[i] - self.Tmin[i]:.2f} N over "
                    f"{1e3 * held[i]:.0f} ms while paying out")
        return None


def is_finite_sample(sample) -> bool:
    """True when a HapticSample's numbers are all finite."""
    return bool(np.isfinite(sample.measured_cp).all() and np.isfinite(sample.measured_cv).all()
                and np.isfinite(sample.orientation).all() and math.isfinite(sample.t))


def is_finite_reading(reading) -> bool:
    """True when a RobotReading's numbers are all finite."""
    return bool(np.isfinite(reading.fsr_counts).all() and np.isfinite(reading.position_steps).all()
                and np.isfinite(reading.commanded_lengths).all() and math.isfinite(reading.t))
