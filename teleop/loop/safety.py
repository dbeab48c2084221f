"""Safety monitors of the loop (docs/safety.md): each returns a fault reason or None.

Monitors hold a little state and are updated once per tick with the host time `now` [s]; none of them
trips on a single noisy sample: a condition must persist for its window.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels import safety as KS
from teleop.core.kernels.jit import bind, f64c


def beyond(value: float, limit: float, unit: str, op: str = ">") -> str:
    """"VALUE UNIT > LIMIT UNIT" (op ">" or "<") with the limit as set and the value to the fewest decimals
    (at least one) that keep the printed comparison true: 20.04 ms over a 20 ms limit reads
    "20.04 ms > 20 ms", not "20.0 ms > 20.0 ms"."""
    lim = f"{limit:g}"
    shown = repr(float(value))  # all the digits, where a few do not show the difference
    for digits in range(1, 10):
        text = f"{value:.{digits}f}"
        if (float(text) > float(lim)) if op == ">" else (float(text) < float(lim)):
            shown = text
            break
    return f"{shown} {unit} {op} {lim} {unit}"


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
                return f"{self.name} telemetry missing for {beyond(1e3 * (now - self.t_start), 1e3 * self.startup, 'ms')}"
            return None
        age = now - self.t_fresh
        if age > self.limit:
            return f"{self.name} telemetry stale: {beyond(1e3 * age, 1e3 * self.limit, 'ms')}"
        return None

    def is_fresh(self, now: float) -> bool:
        return self.t_fresh is not None and now - self.t_fresh <= self.limit


class TensionRange:
    """Over-range or slack tension on any cable persisting longer than `window` [s] -> fault.

    The rule is the kernel safety.tension_range (one compiled call per update)."""

    def __init__(self, t_max: float, t_slack: float, window: float, n: int = 6):
        self.t_max, self.t_slack, self.window, self.n = float(t_max), float(t_slack), float(window), n
        self.reset()

    def reset(self) -> None:
        # host time each condition started [s] (row 0 over-range, row 1 slack), NaN while it does not hold
        self.since = np.full((2, self.n), np.nan)

    def update(self, now: float, t) -> str | None:
        t = np.ascontiguousarray(t, dtype=float)
        k = KS.tension_range(float(now), t, self.t_max, self.t_slack, self.window, self.since)
        return None if k < 0 else self.reason(now, k, t)

    def reason(self, now: float, k: int, t) -> str:
        """The fault message for the kernel's code k (row * n + cable) at tensions t (n,) [N]."""
        row, i = divmod(k, self.n)
        held = beyond(1e3 * (now - self.since[row, i]), 1e3 * self.window, "ms")
        value = beyond(float(t[i]), self.t_slack, "N", "<") if row else beyond(float(t[i]), self.t_max, "N")
        return f"cable {i + 1} tension {'slack' if row else 'over-range'} for {held} ({value})"


class StuckCable:
    """A cable commanded to pay out (length increasing) whose tension keeps rising is stuck (seed 000 §1).

    The pay-out streak of each cable starts when its commanded length begins to increase; once the streak has
    lasted `window` [s], a tension more than `rise` [N] above the lowest tension of the streak, seen on
    `confirm` consecutive updates, reports the cable stuck. A pause or reversal of the command ends the streak.
    Tensions are low-pass filtered first (time constant `tau` [s]) so sensor noise and FSR branch flips
    do not count as a rise. The rule is the kernel safety.stuck_cable (one compiled call per update).
    """

    def __init__(self, window: float, rise: float, payout_eps: float, n: int = 6, confirm: int = 3,
                 tau: float = 0.02):
        self.window, self.rise, self.eps, self.confirm, self.tau, self.n = (float(window), float(rise), float(payout_eps),
                                                                            float(confirm), float(tau), n)
        self.st = np.zeros((4, n))  # filtered tension, streak start (NaN: none), streak minimum, rises
        self.sc = np.array([np.nan, 0.0])  # previous update time [s], filtered tension valid
        self.reset()

    def reset(self) -> None:
        self.st[KS.T0] = np.nan
        self.st[KS.COUNT] = 0.0
        self.sc[KS.HAS_TF] = 0.0

    def update(self, now: float, t, dL) -> str | None:
        bad = KS.stuck_cable(float(now), np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(dL, dtype=float),
                             self.st, self.sc, self.tau, self.eps, self.window, self.rise, self.confirm)
        return None if bad < 0 else self.reason(now, bad)

    def reason(self, now: float, bad: int) -> str:
        """The fault message for stuck cable index `bad`."""
        st = self.st
        return (f"cable {bad + 1} stuck: tension rose {beyond(st[KS.TF, bad] - st[KS.TMIN, bad], self.rise, 'N')} "
                f"over {1e3 * (now - st[KS.T0, bad]):.0f} ms while paying out")


_monitors = [None]  # kernel safety.tension_monitors bound to its argument types (one set for every caller)


def tension_monitors(rng: TensionRange, stuck: StuckCable, now: float, t, dL, check_range: bool = True) -> str | None:
    """`rng.update(now, t)` (when check_range) and, unless it reports, `stuck.update(now, t, dL)`: the loop's
    tension monitors on each estimate, in one compiled call (kernel safety.tension_monitors). The first
    reason, or None. t (n,) tensions [N], dL (n,) length steps [m]."""
    t, dL = f64c(t), f64c(dL)  # the loop's float64 arrays as they are
    if type(now) is not float:
        now = float(now)
    call = _monitors[0] if t.ndim == 1 and dL.ndim == 1 else KS.tension_monitors
    if call is None:  # bound at the first call (jit.bind): floats, a truth value, float64 arrays (t, dL checked 1-D)
        call = _monitors[0] = bind(KS.tension_monitors, now, t, dL, check_range, rng.since, rng.t_max, rng.t_slack,
                                   rng.window, stuck.st, stuck.sc, stuck.tau, stuck.eps, stuck.window, stuck.rise,
                                   stuck.confirm)
    k = call(now, t, dL, check_range, rng.since, rng.t_max, rng.t_slack, rng.window, stuck.st, stuck.sc, stuck.tau,
             stuck.eps, stuck.window, stuck.rise, stuck.confirm)
    if k < 0:
        return None
    n2 = 2 * rng.n
    return rng.reason(now, k, t) if k < n2 else stuck.reason(now, k - n2)


def _all_finite(values) -> bool:
    if _numeric(values):  # a compiled loop (the devices' arrays)
        return KS.all_finite(values)
    return all(math.isfinite(v) for v in (values.tolist() if hasattr(values, "tolist") else values))


def _numeric(a) -> bool:
    return type(a) is np.ndarray and a.dtype.kind in "fiu"


_ND = np.ndarray
# numpy's float64 and int64 dtypes: an array's dtype is one of these objects in the usual case, told by identity
# (`is`, ~20 ns) before its kind (~70 ns: the checks below run six times a tick)
_F64, _I64 = np.dtype(np.float64), np.dtype(np.int64)


def is_finite_sample(sample) -> bool:
    """True when a HapticSample's numbers are all finite."""
    cp, cv, R = sample.measured_cp, sample.measured_cv, sample.orientation
    # numeric arrays and a float time: one compiled call (_numeric written out: this runs every tick)
    if type(cp) is _ND and type(cv) is _ND and type(R) is _ND and type(sample.t) is float \
            and (cp.dtype is _F64 or cp.dtype.kind in "fiu") and (cv.dtype is _F64 or cv.dtype.kind in "fiu") \
            and (R.dtype is _F64 or R.dtype.kind in "fiu"):
        return KS.all_finite3(cp, cv, R, sample.t)
    return (_all_finite(cp) and _all_finite(cv) and _all_finite(np.ravel(R)) and math.isfinite(sample.t))


def is_finite_reading(reading) -> bool:
    """True when a RobotReading's numbers are all finite."""
    c, s, L = reading.fsr_counts, reading.position_steps, reading.commanded_lengths
    if type(c) is _ND and type(s) is _ND and type(L) is _ND and type(reading.t) is float \
            and (c.dtype is _I64 or c.dtype.kind in "fiu") and (s.dtype is _I64 or s.dtype.kind in "fiu") \
            and (L.dtype is _F64 or L.dtype.kind in "fiu"):  # as is_finite_sample
        return KS.all_finite3(c, s, L, reading.t)
    return (_all_finite(c) and _all_finite(s) and _all_finite(L) and math.isfinite(reading.t))
