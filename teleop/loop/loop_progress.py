"""Progress of a running loop (`teleop session`, `teleop bench loop`): ticks done of the run's, the loop's
state, deadline misses and faults so far, on stderr: a tqdm bar on a terminal, a plain line every few seconds
off one (teleop.io.progress).

The loop calls `on_tick` after every tick; it looks at the timing log only every CHECK_EVERY ticks (a slice
of the lateness since the last look), so a tick pays one modulo and a call. A stderr that fails (the terminal
closed: SIGHUP) ends the reporting, never the loop.
"""

from __future__ import annotations

import numpy as np

from teleop.io.progress import progress
from teleop.loop.states import State
from teleop.loop.timing import TimingLog, late_threshold_ns

CHECK_EVERY = 250  # ticks between looks at the log


class LoopProgress:
    """Reports `tp` (teleop.loop.core.Teleop) running into `log` for `total` ticks at `rate_hz` [Hz].

    bar: a reporter with update(n), set_postfix_str(s), close() (default: teleop.io.progress.progress on
    stderr, a first plain line at once off a terminal)."""

    def __init__(self, tp, log: TimingLog, total: int, rate_hz: float, desc: str = "session", bar=None):
        self.tp, self.log = tp, log
        self.late_ns = late_threshold_ns(rate_hz)
        self.bar = bar if bar is not None else progress(total, desc, unit="ticks", start_line=True,
                                                        mininterval=0.5)
        self.silent = False  # set when the stream failed
        self.seen = 0  # ticks of the log already counted
        self.misses = 0  # ticks more than half a period late among them (skipped deadlines added at each look)
        self._closed = False

    def on_tick(self, k: int, lateness_ns: int) -> None:
        """After tick k (run_paced / run_stepped's on_tick)."""
        if k % CHECK_EVERY == 0 and not self.silent:
            self.look()

    def look(self) -> None:
        """Count the ticks logged since the last look and show the state, misses and faults."""
        n = self.log.n
        self.misses += int(np.count_nonzero(self.log.lateness[self.seen:n] > self.late_ns))
        faults = sum(1 for e in self.tp.events if e.dst == State.FAULT.name)
        try:
            self.bar.set_postfix_str(f"{self.tp.state.name}, {self.misses + self.log.skipped} misses, "
                                     f"{faults} faults", refresh=False)
            self.bar.update(n - self.seen)
        except (OSError, ValueError):  # stderr closed or gone: report no more
            self.silent = True
        self.seen = n

    def close(self) -> None:
        """A last look, then the reporter's last line."""
        if not self._closed:
            self._closed = True
            if not self.silent:
                self.look()
            try:
                self.bar.close()
            except (OSError, ValueError):
                pass
