"""Progress of long commands: a tqdm bar on a terminal; otherwise (stderr logged or piped) a plain line
every few seconds, so that a log shows the run is alive and how far it got.

tqdm's own non-terminal output redraws the bar with carriage returns (one unreadable log line), hence the
plain writer here.
"""

from __future__ import annotations

import sys
import time

from tqdm import tqdm

PLAIN_INTERVAL_S = 5.0  # [s] between plain lines when stderr is not a terminal
FIRST_LINE_S = 2.0  # [s] of a run before its first plain line: a longer run says what it does within this


class PlainProgress:
    """``desc: k/total unit (p %), t s elapsed[, about s left][, postfix]`` on `stream`: the first at the first
    update `first_s` seconds of `clock` into the run (or at once with `start_line`), then at most every
    `interval_s` seconds, and a last line on close when at least one line was written (a run shorter than
    `first_s` stays silent). The time left is the elapsed time per unit done so far times the units left."""

    def __init__(self, total: int | None, desc: str, unit: str = "it", stream=None,
                 interval_s: float = PLAIN_INTERVAL_S, clock=time.monotonic, start_line: bool = False,
                 first_s: float = FIRST_LINE_S):
        self.total, self.desc, self.unit = total, desc, unit
        self.stream = stream if stream is not None else sys.stderr
        self.interval_s, self.clock = interval_s, clock
        self.n = 0
        self.lines = 0
        self.t0 = self.clock()
        self._last = self.t0 - (0.0 if start_line else max(0.0, interval_s - first_s))  # first line first_s in
        self._closed = False
        self.postfix = ""
        if start_line:
            self.lines += 1
            print(self._line(self.t0), file=self.stream, flush=True)

    def _line(self, now: float, done: bool = False) -> str:
        elapsed = now - self.t0
        count = f"{self.n}/{self.total}" if self.total else f"{self.n}"
        share = f" ({100.0 * self.n / self.total:.0f} %)" if self.total else ""
        post = f", {self.postfix}" if self.postfix else ""
        if done:
            return f"{self.desc}: done, {self.n} {self.unit} in {elapsed:.0f} s{post}"
        left = ""
        if self.total and 0 < self.n < self.total:
            left = f", about {elapsed * (self.total - self.n) / self.n:.0f} s left"
        return f"{self.desc}: {count} {self.unit}{share}, {elapsed:.0f} s elapsed{left}{post}"

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Text added to the next lines (as tqdm's set_postfix_str)."""
        self.postfix = str(s)

    def update(self, n: int = 1) -> None:
        self.n += n
        now = self.clock()
        if now - self._last >= self.interval_s:
            self._last = now
            self.lines += 1
            print(self._line(now), file=self.stream, flush=True)

    def close(self) -> None:
        if not self._closed and self.lines:
            print(self._line(self.clock(), done=True), file=self.stream, flush=True)
        self._closed = True

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def progress(total: int | None, desc: str, unit: str = "it", stream=None, start_line: bool = False, **tqdm_kwargs):
    """A progress reporter with ``update(n)``, ``set_postfix_str(s)`` and ``close()`` (also a context manager):
    tqdm when `stream` (default stderr) is a terminal (its bar shows at once), else PlainProgress (with a
    first line at once if `start_line`)."""
    stream = stream if stream is not None else sys.stderr
    if stream.isatty():
        return tqdm(total=total, desc=desc, unit=unit, file=stream, **tqdm_kwargs)
    return PlainProgress(total, desc, unit, stream=stream, start_line=start_line)
