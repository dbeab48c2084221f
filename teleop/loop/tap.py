"""The recorder's tap on every arrow of the tick's data flow: one row of numbers per tick.

`session_layout(extras)` names the columns (topics with CRTK names where one fits); `RowTap` fills a
preallocated row from the Teleop state after the WRITE stage and pushes it to the recorder's ring.
"""

from __future__ import annotations

import numpy as np

from teleop.loop.core import STAGES
from teleop.recording import INT, TOPIC_FORCE, TOPIC_ROBOT, TOPIC_SETPOINT, Layout, Signal


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
    sig += [Signal("/estimation", "tensions", 6), Signal("/estimation", "measured_cf", 6)]
    sig += [Signal(TOPIC_FORCE, "force_raw", 3), Signal(TOPIC_FORCE, "ramp"),
            Signal(TOPIC_FORCE, "servo_cf", 3)]
    return Layout(tuple(sig), {TOPIC_ROBOT: "new"})


class RowTap:
    """Callable given to Teleop.tap: fills the row and pushes it (`push(row)` -> bool)."""

    def __init__(self, layout: Layout, push, extras: dict | None = None):
        self.row = np.zeros(layout.width)
        self.push = push
        self.sl = layout.columns()  # raises unless signal names are unique across topics
        self.stage_sl = slice(self.sl["read_us"].start, self.sl["record_us"].stop)
        self.extras = dict(extras or {})

    def __call__(self, tp) -> None:
        r, sl, x = self.row, self.sl, tp.x
        r[sl["tick"]] = x.k
        r[sl["t"]] = x.now
        r[sl["state"]] = int(tp.state)
        r[sl["lateness_us"]] = tp.lateness_ns * 1e-3
        r[sl["tick_us"]] = tp.prev_tick_ns * 1e-3  # the previous tick's duration
        r[self.stage_sl] = tp.stage_ns * 1e-3  # this tick's stages; record_us is the previous tick's
        s = x.sample
        if s is not None:
            r[sl["t_device"]] = s.t
            r[sl["measured_cp"]] = s.measured_cp
            r[sl["measured_cv"]] = s.measured_cv
            r[sl["orientation"]] = np.ravel(s.orientation)
            r[sl["buttons"]] = s.buttons
            r[sl["operator_present"]] = s.operator_present
        cmd = x.L_cmd is not None
        r[sl["commanded"]] = cmd
        r[sl["setpoint_cp"]] = tp.pose[:3]
        if cmd:
            r[sl["servo_jp"]] = x.L_cmd
        rd = x.reading
        r[sl["new"]] = rd is not None
        if rd is not None:
            r[sl["t_robot"]] = rd.t
            r[sl["seq"]] = rd.seq
            r[sl["fsr_counts"]] = rd.fsr_counts
            r[sl["position_steps"]] = rd.position_steps
            r[sl["commanded_lengths"]] = rd.commanded_lengths
            r[sl["status"]] = rd.status
            r[sl["boot_id"]] = rd.boot_id
            r[sl["wrench_truth"]] = np.nan if rd.wrench_truth is None else rd.wrench_truth
            for k in self.extras:
                r[sl[f"x_{k}"]] = np.asarray(rd.extras.get(k, np.nan), dtype=float)
        r[sl["tensions"]] = tp.tensions
        r[sl["measured_cf"]] = tp.wrench
        r[sl["force_raw"]] = x.F_raw
        r[sl["ramp"]] = x.ramp
        r[sl["servo_cf"]] = x.F
        self.push(r)
