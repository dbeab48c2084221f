"""The FBG channel of a session recording (teleop.io.recording.sensors.TOPIC_FBG): its columns in the tick row
and the tap that fills them before the session's RowTap (teleop.loop.tap) fills the rest and pushes the row.

Used by teleop.loop.session for an estimator of the FBG sensor kinds
(teleop.core.estimation.sensor_reading.FbgReadingEstimator: `kind`, `cable`, `tensions`, `proximal`, `at_rest`,
`rest_ratio`).
"""

from __future__ import annotations

import numpy as np

from teleop.io.recording import Layout
from teleop.io.recording.sensors import GATE, TOPIC_FBG, fbg_signals


def fbg_cables_of(estimator) -> list | None:
    """The cables an estimator reads an FBG on (fbg: all, one: its `cable`); None for any other estimator."""
    kind = getattr(estimator, "kind", None)
    if kind == "fbg":
        return list(range(estimator.n))
    if kind == "one":
        return [int(estimator.cable)]
    return None


def with_fbg_channel(layout: Layout, estimator) -> Layout:
    """`layout` plus the TOPIC_FBG columns for `estimator` (unchanged when it reads no FBG)."""
    cables = fbg_cables_of(estimator)
    if cables is None:
        return layout
    sig = fbg_signals(len(cables), estimator.kind == "one")
    return Layout(tuple(layout.signals) + tuple(sig), {**layout.gates, TOPIC_FBG: GATE})


class FbgTap:
    """Callable for Teleop.tap: writes this tick's FBG columns into `tap.row` (a teleop.loop.tap.RowTap on a
    `with_fbg_channel` layout), then calls `tap` (which fills its own columns and pushes the row)."""

    def __init__(self, tap, layout: Layout, estimator):
        self.tap, self.est = tap, estimator
        self.row = tap.row
        cols = layout.columns()
        self.cables = np.array(fbg_cables_of(estimator), dtype=np.int64)
        self.one = estimator.kind == "one"
        self.sl = {k: cols[k] for k in (GATE, "fbg_cable", "fbg_dl1_pm", "fbg_dl2_pm", "fbg_force")}
        if self.one:
            self.sl.update({k: cols[k] for k in ("proximal", "rest", "rest_ratio")})
        self.row[self.sl["fbg_cable"]] = self.cables
        self.row[self.sl[GATE]] = 0.0

    def __call__(self, tp) -> None:
        r, sl, rd = self.row, self.sl, tp.x.reading
        fbg = None if rd is None else rd.fbg_pm
        r[sl[GATE]] = 0.0 if fbg is None else 1.0
        if fbg is not None:
            dl = np.asarray(fbg, dtype=float)[:, self.cables]
            r[sl["fbg_dl1_pm"]] = dl[0]
            r[sl["fbg_dl2_pm"]] = dl[1]
            r[sl["fbg_force"]] = self.est.tensions[self.cables]  # the estimate's seed 001 eq 3, not again
            if self.one:
                r[sl["proximal"]] = self.est.proximal
                r[sl["rest"]] = float(self.est.at_rest)
                r[sl["rest_ratio"]] = self.est.rest_ratio
        self.tap(tp)
