"""How far a campaign is: a tqdm bar (tasks done, rate, ETA) on a terminal, otherwise a plain line every
few seconds (logs of batch jobs, CI) and one at the end."""

from __future__ import annotations

import sys
import time


def _duration(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


class Progress:
    """Counts finished tasks out of `total`.

    stream: where to write (stderr); bar: tqdm bar (default: when `stream` is a terminal); interval: seconds
    between plain lines; clock: monotonic seconds (injectable for tests); ticker: without a bar, a daemon
    thread calls `tick` every `interval` so a line comes even while a long task runs (tests pass False and
    call `tick` themselves).
    """

    def __init__(self, total: int, desc: str = "campaign", stream=None, bar: bool | None = None,
                 interval: float = 5.0, clock=time.monotonic, ticker: bool = True):
        self.total, self.desc = int(total), desc
        self.stream = sys.stderr if stream is None else stream
        self.clock, self.interval = clock, float(interval)
        self.done = self.failed = 0
        self._closed = False
        self.t0 = self.last = clock()
        if bar is None:
            bar = bool(getattr(self.stream, "isatty", lambda: False)())
        self._bar = None
        if bar:
            from tqdm import tqdm

            self._bar = tqdm(total=self.total, desc=desc, unit="task", file=self.stream, dynamic_ncols=True)
        self._stop = None
        if self._bar is None and ticker:
            import threading

            self._stop = threading.Event()
            threading.Thread(target=self._tick_every, daemon=True, name="campaign-progress").start()

    def _tick_every(self) -> None:
        while not self._stop.wait(self.interval):
            self.tick()

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def line(self) -> str:
        """`desc: done/total tasks (failed), rate, elapsed, ETA`."""
        elapsed = self.clock() - self.t0
        n = self.done + self.failed
        rate = n / elapsed if elapsed > 0 else 0.0
        eta = (self.total - n) / rate if rate > 0 else None
        failed = f", {self.failed} failed" if self.failed else ""
        return (f"{self.desc}: {n}/{self.total} tasks{failed}, {rate:.2f} task/s, elapsed {_duration(elapsed)}"
                + (f", ETA {_duration(eta)}" if eta is not None and n < self.total else ""))

    def update(self, ok: bool = True) -> None:
        if ok:
            self.done += 1
        else:
            self.failed += 1
        if self._bar is not None:
            self._bar.update()
            if self.failed:
                self._bar.set_postfix(failed=self.failed)
            return
        self.tick()

    def tick(self) -> None:
        """Without a bar: print the line if `interval` has passed since the last one."""
        now = self.clock()
        if self._bar is None and not self._closed and now - self.last >= self.interval:
            self.last = now
            print(self.line(), file=self.stream, flush=True)

    def note(self, text: str) -> None:
        """A message that does not break the bar."""
        if self._bar is not None:
            self._bar.write(text, file=self.stream)
        else:
            print(text, file=self.stream, flush=True)

    def close(self) -> None:
        """Close the bar, or print the final line (once)."""
        if self._closed:
            return
        self._closed = True
        if self._stop is not None:
            self._stop.set()
        if self._bar is not None:
            self._bar.close()
        else:
            print(self.line(), file=self.stream, flush=True)
