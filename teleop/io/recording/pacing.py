"""Down-sampling a stream of rows to a channel rate on the rows' own session time.

A channel at rate f publishes the first row at or after each deadline t0 + k / f; the deadline accumulates
(it is not reset to the time of the row that was sent), so the mean rate is f whatever the row rate and the
rows' timing jitter. The older rule "publish when t - t_last >= 1/f" loses a whole row period whenever a row
comes a hair early (rows 1 ms apart that jitter by tens of ns gave intervals of 10 and 11 ms, 95 instead
of 100 messages a second).
"""

from __future__ import annotations


class Pacer:
    """Decides which rows of a stream a channel at `rate` [Hz] publishes (times in [s] of session time).

    Args:
        rate: messages per second of session time.
        tolerance: a row up to this much [s] before its deadline counts as on time: it absorbs the rows'
            timing jitter (tens of ns) and must stay well below the row period.
    """

    def __init__(self, rate: float, tolerance: float = 1e-6):
        if not rate > 0:
            raise ValueError(f"rate must be > 0 Hz, got {rate}")
        self.period = 1.0 / float(rate)
        self.slack = float(tolerance)
        self.deadline = None  # session time of the next message [s]; None until the first row

    def due(self, t: float) -> bool:
        """True when the row at session time `t` [s] is to be published (then the deadline moves on)."""
        if self.deadline is not None and t < self.deadline - self.slack:
            return False
        if self.deadline is None or t - self.deadline >= self.period:  # first row, or a gap of a period
            self.deadline = t                                         # or more (rows skipped): restart
        self.deadline += self.period
        return True
