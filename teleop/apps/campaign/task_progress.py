"""How far a campaign is, in tasks (TaskProgress): teleop.io.progress's reporter (a tqdm bar with tasks done,
rate and ETA on a terminal, otherwise a plain line every few seconds) counting tasks, plus what a campaign
needs on top: failures counted and noted as they happen, and a ticker so a plain line comes even while long
tasks run."""

from __future__ import annotations

import sys
import threading
import time

from tqdm import tqdm

from teleop.io.progress import PLAIN_INTERVAL_S, PlainProgress


class TaskProgress:
    """Counts finished tasks out of `total` on `stream` (stderr).

    bar: tqdm (default: when `stream` is a terminal) or plain lines every `interval` seconds of `clock`;
    ticker: with plain lines, a daemon thread calls `tick` every `interval` (tests pass False and call it).
    """

    def __init__(self, total: int, desc: str = "campaign", stream=None, bar: bool | None = None,
                 interval: float = PLAIN_INTERVAL_S, clock=time.monotonic, ticker: bool = True):
        self.stream = sys.stderr if stream is None else stream
        self.failed = 0
        self._closed = False
        if bar is None:
            bar = bool(getattr(self.stream, "isatty", lambda: False)())
        if bar:
            self.reporter = tqdm(total=total, desc=desc, unit="task", file=self.stream, dynamic_ncols=True)
        else:
            self.reporter = PlainProgress(total, desc, "tasks", stream=self.stream, interval_s=interval, clock=clock,
                                          first_s=interval)  # the campaign says its plan at once already
        self._stop = None
        if not bar and ticker:
            self._stop = threading.Event()
            threading.Thread(target=self._tick_every, args=(interval,), daemon=True, name="campaign-progress").start()

    def _tick_every(self, interval: float) -> None:
        while not self._stop.wait(interval):
            self.tick()

    def __enter__(self) -> "TaskProgress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def tick(self) -> None:
        """A plain line if its interval has passed (nothing finished meanwhile)."""
        if isinstance(self.reporter, PlainProgress) and not self._closed:
            self.reporter.update(0)

    def update(self, ok: bool = True) -> None:
        """One task finished (ok) or failed."""
        if not ok:
            self.failed += 1
            if not isinstance(self.reporter, PlainProgress):
                self.reporter.set_postfix(failed=self.failed, refresh=False)
        self.reporter.update(1)

    def note(self, text: str) -> None:
        """A message that does not break the bar."""
        if isinstance(self.reporter, PlainProgress):
            print(text, file=self.stream, flush=True)
        else:
            self.reporter.write(text, file=self.stream)

    def close(self) -> None:
        self._closed = True
        if self._stop is not None:
            self._stop.set()
        self.reporter.close()
