"""Per-second timing statistics from the tick rows' /loop columns (computed in the recorder and live processes)."""

from __future__ import annotations

import numpy as np

from teleop.io.recording.layout import Layout

LATE_US = 500.0  # a tick more than this late is a miss (docs/safety.md)


class SecondStats:
    """Collects rows; `add` returns a summary dict each time a whole second of session time is complete."""

    def __init__(self, layout: Layout):
        sl = layout.slices()
        self.cols = {s.name: sl[("/loop", s.name)][0] for s in layout.signals
                     if s.topic == "/loop" and s.name.endswith("_us")}
        self.t_col = sl[("/loop", "t")][0]
        self.rows = []
        self.second = 0

    def add(self, row: np.ndarray):
        """Add a row; returns a stats dict when a whole second has been collected."""
        out = None
        sec = int(row[self.t_col])
        if sec != self.second and self.rows:
            out = self.summary()
            self.rows = []
        self.second = sec
        self.rows.append(row[[c for c in self.cols.values()]].copy())
        return out

    def summary(self) -> dict:
        a = np.array(self.rows)
        out = {"second": self.second, "ticks": len(a)}
        for j, name in enumerate(self.cols):
            v = a[:, j]
            out[name] = {"mean": round(float(v.mean()), 3), "p99": round(float(np.percentile(v, 99)), 3),
                         "p999": round(float(np.percentile(v, 99.9)), 3), "max": round(float(v.max()), 3)}
            if name == "lateness_us":
                out["misses"] = int((v > LATE_US).sum())
        return out
