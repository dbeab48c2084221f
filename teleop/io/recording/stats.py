"""Per-second timing statistics from the tick rows' /loop columns (computed in the recorder and live processes)."""

from __future__ import annotations

import json

import numpy as np

from teleop.io.recording.layout import Layout

LATE_US = 500.0  # a tick more than this late is a miss (docs/safety.md)
STATISTICS = ("mean", "p99", "p999", "max")  # of each stage time, per second [us]


def timing_schema(layout: Layout) -> bytes:
    """JSON schema of the per-second timing messages (`SecondStats.summary`), every key with its type: the
    recording's /loop/timing and the live view's /live/timing (Foxglove parses only schemas with properties)."""
    stat = {"type": "object", "properties": {k: {"type": "number", "description": f"{k} over the second [us]"}
                                             for k in STATISTICS}}
    props = {"second": {"type": "integer", "description": "whole second of session time [s]"},
             "ticks": {"type": "integer", "description": "ticks in that second"}}
    for name in SecondStats(layout).cols:
        props[name] = stat
        if name == "lateness_us":
            props["misses"] = {"type": "integer", "description": f"ticks more than {LATE_US:g} us late"}
    return json.dumps({"type": "object", "properties": props}).encode()


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
            vals = (v.mean(), np.percentile(v, 99), np.percentile(v, 99.9), v.max())
            out[name] = {k: round(float(x), 3) for k, x in zip(STATISTICS, vals)}
            if name == "lateness_us":
                out["misses"] = int((v > LATE_US).sum())
        return out
