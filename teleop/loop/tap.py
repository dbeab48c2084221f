"""The recorder's tap on every arrow of the tick's data flow: one row of numbers per tick.

`session_layout(extras)` names the columns (topics with CRTK names where one fits); `RowTap` fills a
preallocated row from the Teleop state after the WRITE stage and pushes it to the recorder's ring.
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels import tap as KT
from teleop.loop.core import STAGES
from teleop.io.recording import INT, TOPIC_FORCE, TOPIC_ROBOT, TOPIC_SETPOINT, Layout, Signal


def numeric_extras(reading) -> dict:
    """{key: width} of a reading's extras that are finite-size numeric arrays (<= 16 numbers)."""
    out = {}
    for k, v in sorted((reading.extras or {}).items()):
        try:
            a = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            continue
        if a.ndim <= 1 and 0 < a.size <= 16:
            out[str(k)] = int(a.size)
    return out


def session_layout(extras: dict | None = None) -> Layout:
    """Columns of one tick row; `extras` ({key: width}) adds the robot backend's extra signals."""
    sig = [Signal("/loop", "tick", 1, INT), Signal("/loop", "t"), Signal("/loop", "state", 1, INT),
           Signal("/loop", "lateness_us"), Signal("/loop", "tick_us")]
    sig += [Signal("/loop", f"{s}_us") for s in STAGES]
    sig += [Signal("/stylus", "t_device"), Signal("/stylus", "measured_cp", 3), Signal("/stylus", "measured_cv", 3),
            Signal("/stylus", "orientation", 9), Signal("/stylus", "buttons", 1, INT),
            Signal("/stylus", "operator_present", 1, INT)]
    sig += [Signal(TOPIC_SETPOINT, "commanded", 1, INT), Signal(TOPIC_SETPOINT, "setpoint_cp", 3),
            Signal(TOPIC_SETPOINT, "servo_jp", 6)]
    sig += [Signal(TOPIC_ROBOT, "new", 1, INT), Signal(TOPIC_ROBOT, "t_robot"),
            Signal(TOPIC_ROBOT, "seq", 1, INT), Signal(TOPIC_ROBOT, "fsr_counts", 6),
            Signal(TOPIC_ROBOT, "position_steps", 6), Signal(TOPIC_ROBOT, "commanded_lengths", 6),
            Signal(TOPIC_ROBOT, "status", 1, INT), Signal(TOPIC_ROBOT, "boot_id", 1, INT),
            Signal(TOPIC_ROBOT, "wrench_truth", 6)]
    sig += [Signal(TOPIC_ROBOT, f"x_{k}", w) for k, w in (extras or {}).items()]
    sig += [Signal("/estimation", "tensions", 6), Signal("/estimation", "measured_cf", 6),
            Signal("/estimation", "compensated_tensions", 6)]
    sig += [Signal(TOPIC_FORCE, "force_raw", 3), Signal(TOPIC_FORCE, "ramp"),
            Signal(TOPIC_FORCE, "servo_cf", 3)]
    return Layout(tuple(sig), {TOPIC_ROBOT: "new"})


# the columns the tap kernel fills, in the order of its indices (teleop.core.kernels.tap); "read_us" stands for the
# stage block (read_us .. record_us)
COLUMNS = ("tick", "t", "state", "lateness_us", "tick_us", "read_us", "t_device", "measured_cp", "measured_cv",
           "orientation", "buttons", "operator_present", "commanded", "setpoint_cp", "servo_jp", "new", "t_robot",
           "seq", "fsr_counts", "position_steps", "commanded_lengths", "status", "boot_id", "wrench_truth",
           "tensions", "measured_cf", "force_raw", "ramp", "servo_cf")


def _arr(a) -> np.ndarray:
    return a if type(a) is np.ndarray else np.asarray(a, dtype=float)


class RowTap:
    """Callable given to Teleop.tap: fills the row (one kernel call, teleop.core.kernels.tap.tap_row; the backend's
    extras per key) and pushes it (`push(row)` -> bool)."""

    def __init__(self, layout: Layout, push, extras: dict | None = None):
        self.row = np.zeros(layout.width)
        self.push = push
        self.sl = layout.columns()  # raises unless signal names are unique across topics
        self.stage_sl = slice(self.sl["read_us"].start, self.sl["record_us"].stop)
        self.extras = dict(extras or {})
        self._x_sl = [(k, self.sl[f"x_{k}"]) for k in self.extras]
        self._comp_sl = self.sl.get("compensated_tensions")
        self.o = np.array([self.sl[c].start for c in COLUMNS], dtype=np.int64)
        self.w = np.array([self.sl[c].stop - self.sl[c].start for c in COLUMNS], dtype=np.int64)
        self.w[KT.STAGES] = self.stage_sl.stop - self.stage_sl.start
        self._z = np.zeros(max(16, int(self.w.max())))  # stands in for what is absent this tick (not written)
        self._R0 = np.zeros((3, 3))

    def __call__(self, tp) -> None:
        r, x, z = self.row, tp.x, self._z
        s, rd = x.sample, x.reading
        cmd = x.L_cmd is not None
        if s is not None:
            s_args = (s.t, _arr(s.measured_cp), _arr(s.measured_cv), _arr(s.orientation), s.buttons,
                      s.operator_present)
        else:
            s_args = (0.0, z[:3], z[:3], self._R0, 0, False)
        if rd is not None:
            wt = rd.wrench_truth
            r_args = (rd.t, rd.seq, _arr(rd.fsr_counts), _arr(rd.position_steps), _arr(rd.commanded_lengths),
                      int(rd.status), int(rd.boot_id), wt is not None, z[:6] if wt is None else _arr(wt))
        else:
            r_args = (0.0, 0, z[:6], z[:6], z[:6], 0, 0, False, z[:6])
        fx, fy, fz = x.F_raw
        bad = KT.tap_row(r, self.o, self.w, x.k, x.now, int(tp.state), tp.lateness_ns, tp.prev_tick_ns,
                         tp.stage_ns, s is not None, *s_args, cmd, tp.pose, _arr(x.L_cmd) if cmd else z[:6],
                         rd is not None, *r_args, _arr(tp.tensions), _arr(tp.wrench), fx, fy, fz, x.ramp, _arr(x.F))
        if bad >= 0:
            raise ValueError(f"signal {COLUMNS[bad]}: expected {self.w[bad]} numbers")
        comp = getattr(tp, "compensated", None)
        if self._comp_sl is not None and comp is not None:
            r[self._comp_sl] = comp
        if rd is not None:
            ex = rd.extras
            for k, sl in self._x_sl:
                v = ex.get(k, np.nan)
                r[sl] = v if type(v) is np.ndarray else np.asarray(v, dtype=float)
        self.push(r)
