"""Shared-memory ring of tick rows: one producer (the loop), one gating consumer (the recorder), any number of
lossy readers (the live server).

The producer's push is a memory copy and two integer stores: no syscall, no lock, no allocation. With a
gating consumer (`gated=True`, the recorder) a full ring drops the new row and counts it; without one (a
live view with no recording) the producer overwrites the oldest row. A lossy reader (`Cursor`) never holds
the producer back: it copies what is there and, if the producer lapped it (or may have overwritten a row
while it was being copied), skips those rows and counts them.
"""

from __future__ import annotations

import multiprocessing as mp

import numpy as np

# ctrl slots (int64): rows pushed, rows consumed by the gating consumer, rows dropped (ring full), alarm
# status, stop flag, rows written, chunk flushes, wall-clock time of session time 0 [ns], rows made durable
# (flushed to the file), gating flag
HEAD, TAIL, DROPS, STATUS, STOP, WRITTEN, FLUSHES, T0_NS, DURABLE, GATED = range(10)
N_CTRL = 10
OK, ALARM_FULL, ALARM_ERROR = 0, 1, 2


class Ring:
    """Single-producer ring of float64 rows in shared memory (see module docstring).

    Args:
        width: numbers per row.
        capacity: rows (memory: capacity x width x 8 bytes).
        gated: a consumer pops rows and the producer never overwrites what it has not popped.
    """

    def __init__(self, width: int, capacity: int, ctx=None, gated: bool = True):
        ctx = ctx or mp.get_context("fork")
        self.width, self.capacity = int(width), int(capacity)
        self.raw = ctx.RawArray("d", self.width * self.capacity)
        self.ctrl_raw = ctx.RawArray("q", N_CTRL)
        self.attach()
        self.ctrl[GATED] = int(bool(gated))

    def attach(self) -> None:
        self.data = np.frombuffer(self.raw, dtype=np.float64).reshape(self.capacity, self.width)
        self.ctrl = np.frombuffer(self.ctrl_raw, dtype=np.int64)

    def __getstate__(self):
        return {"width": self.width, "capacity": self.capacity, "raw": self.raw, "ctrl_raw": self.ctrl_raw}

    def __setstate__(self, d):
        self.__dict__.update(d)
        self.attach()

    def set_t0(self, t0_ns: int) -> None:
        """Wall-clock time [ns since epoch] of session time 0, for the consumers' log times."""
        self.ctrl[T0_NS] = int(t0_ns)

    def push(self, row: np.ndarray) -> bool:
        """Copy a row in (producer); False (and a drop counted) when a gated ring is full."""
        c = self.ctrl
        head = int(c[HEAD])
        if c[GATED] and head - int(c[TAIL]) >= self.capacity:
            c[DROPS] += 1
            if c[STATUS] == OK:
                c[STATUS] = ALARM_FULL
            return False
        self.data[head % self.capacity] = row
        c[HEAD] = head + 1
        return True

    def pop(self, max_rows: int = 1 << 30) -> np.ndarray:
        """Copy out the rows pushed since the last pop (the gating consumer)."""
        c = self.ctrl
        tail, head = int(c[TAIL]), int(c[HEAD])
        n = min(head - tail, max_rows)
        if n <= 0:
            return np.zeros((0, self.width))
        idx = (np.arange(tail, tail + n) % self.capacity)
        out = self.data[idx].copy()
        c[TAIL] = tail + n
        return out


class Cursor:
    """A lossy reader of a Ring: `read()` returns the rows pushed since the last read that are still intact.

    Attributes:
        next: index of the next row to read.
        skipped: rows lost because the producer lapped this reader.
    """

    def __init__(self, ring: Ring, start: int | None = None):
        self.ring = ring
        self.next = int(ring.ctrl[HEAD]) if start is None else int(start)
        self.skipped = 0

    def _oldest_intact(self, head: int) -> int:
        """Oldest row the producer cannot be overwriting now: row i's slot is written while head == i + cap
        (so rows >= head - cap + 1 are safe), and a gated ring never writes over a row its consumer has not
        popped (rows >= tail are safe too)."""
        c = self.ring.ctrl
        safe = head - self.ring.capacity + 1
        return min(safe, int(c[TAIL])) if c[GATED] else safe

    def read(self, max_rows: int = 4096) -> np.ndarray:
        r, c = self.ring, self.ring.ctrl
        cap = r.capacity
        head = int(c[HEAD])
        lo = max(self.next, self._oldest_intact(head))
        hi = min(head, lo + max_rows)
        if hi <= lo:
            self.skipped += lo - self.next
            self.next = lo
            return np.zeros((0, r.width))
        out = r.data[np.arange(lo, hi) % cap].copy()
        valid = max(lo, self._oldest_intact(int(c[HEAD])))  # what may have been overwritten during the copy
        self.skipped += valid - self.next
        self.next = hi
        return out[valid - lo:]
