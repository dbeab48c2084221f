"""What the live view shows: channels, their rates, and how each message is built from a tick row.

Rates are on the rows' session time (teleop.io.recording.pacing.Pacer: the first row at or after each
deadline, the deadlines 1/rate apart), so they hold whatever the loop rate. Plots (JSON with a JSON schema) at 100 Hz, the 3D scene
(foxglove.FrameTransforms, foxglove.SceneUpdate) at 50 and 10 Hz, faults (foxglove.Log) when they happen,
per-second timing and the live view's own counters at 1 Hz.

Sessions of the FBG sensor kinds (`sim://robot?sensor=fbg|one`, whose row layout carries the recording's FBG
channel, teleop.io.recording.sensors) add one plot channel, TOPIC_FBG_LIVE at RATE_FBG: the fields of
/sensors/fbg, paced over the rows that carry a new FBG reading (its gate). Its per-FBG fields (`fbg_cable`,
`fbg_dl1_pm`, `fbg_dl2_pm`, `fbg_force`) are lists even for one instrumented cable (the recording writes a
number there), so one layout's paths (`fbg_force[0]`) serve both kinds. `plots(layout)` and `rates(layout)`
are a layout's channels; PLOTS and RATES those of every session.
"""

from __future__ import annotations

import json

import orjson
import math

from foxglove.messages import (ArrowPrimitive, Color, CubePrimitive, CylinderPrimitive, LinePrimitive,
                               LinePrimitiveLineType, Point3, Pose, Quaternion, SceneEntity, SceneUpdate,
                               SpherePrimitive, Vector3)

from teleop.io.recording.foxglove import STATE_NAMES, WORLD, frame_transforms, stamp
from teleop.io.recording.layout import Layout
from teleop.io.recording.pacing import Pacer
from teleop.io.recording.sensors import GATE as FBG_GATE, TOPIC_FBG

# topic: (rate [Hz] on session time, row fields) for the JSON plot channels
PLOTS = {
    "/live/stylus": (100.0, ("measured_cp", "measured_cv", "force_raw", "servo_cf", "buttons", "operator_present")),
    "/live/cables": (100.0, ("servo_jp", "commanded_lengths", "position_steps", "measured_lengths")),
    "/live/tensions": (100.0, ("fsr_counts", "tensions", "compensated_tensions")),
    "/live/wrench": (100.0, ("measured_cf", "wrench_truth")),
    "/live/loop": (100.0, ("state", "lateness_us", "tick_us", "read_us", "map_us", "robot_us", "estimate_us",
                           "render_us", "write_us", "record_us")),
}
TOPIC_TF, RATE_TF = "/live/tf", 50.0
TOPIC_SCENE, RATE_SCENE = "/live/scene", 10.0
TOPIC_FAULTS = "/live/faults"
TOPIC_TIMING, TOPIC_STATS = "/live/timing", "/live/stats"
RATES = {**{k: v[0] for k, v in PLOTS.items()}, TOPIC_TF: RATE_TF, TOPIC_SCENE: RATE_SCENE, TOPIC_TIMING: 1.0,
         TOPIC_STATS: 1.0}
# the FBG sensors (module docstring): the plots' rate, on the rows with a new FBG reading
TOPIC_FBG_LIVE, RATE_FBG = "/live/fbg", 100.0
FBG_PER_SENSOR = ("fbg_cable", "fbg_dl1_pm", "fbg_dl2_pm", "fbg_force")  # one entry per FBG: always a list


def plots(layout: Layout) -> dict:
    """{topic: (rate [Hz], row fields)} of the plot channels for a session's row `layout`: PLOTS, and
    TOPIC_FBG_LIVE (the recording's FBG fields but its gate) when the layout carries the FBG channel."""
    fbg = tuple(s.name for s in layout.signals if s.topic == TOPIC_FBG and s.name != FBG_GATE)
    return {**PLOTS, TOPIC_FBG_LIVE: (RATE_FBG, fbg)} if fbg else dict(PLOTS)


def rates(layout: Layout) -> dict:
    """{topic: rate [Hz]} of the paced channels for `layout` (RATES, and TOPIC_FBG_LIVE with an FBG channel)."""
    p = plots(layout)
    return {**RATES, TOPIC_FBG_LIVE: p[TOPIC_FBG_LIVE][0]} if TOPIC_FBG_LIVE in p else dict(RATES)


def gate_columns(layout: Layout) -> dict:
    """{topic: row column} for the paced channels published only on rows where that column is nonzero."""
    sl = layout.slices()
    return {TOPIC_FBG_LIVE: sl[(TOPIC_FBG, FBG_GATE)][0]} if (TOPIC_FBG, FBG_GATE) in sl else {}


class Schedule:
    """Which paced channels of `layout` (rates(layout) but the per-second timing, sent when a second is
    complete) a row publishes: each channel's Pacer on the rows' session time; a gated channel
    (gate_columns) counts only the rows that carry its data."""

    def __init__(self, layout: Layout):
        self.pacers = {topic: Pacer(rate) for topic, rate in rates(layout).items() if topic != TOPIC_TIMING}
        self.gates = gate_columns(layout)

    def due(self, row, t: float) -> list:
        """The topics due at the row `row` of session time `t` [s] (their pacers move on)."""
        out = []
        for topic, pacer in self.pacers.items():
            g = self.gates.get(topic)
            if (g is None or row[g]) and pacer.due(t):
                out.append(topic)
        return out

# the 3D scene (RGBA): a colour nothing else in the scene has for the end effector, red while in FAULT
EE_COLOR, EE_FAULT_COLOR = (0.9, 0.1, 0.8, 1.0), (0.9, 0.1, 0.1, 1.0)
EE_DIAMETER = 0.008  # [m]
CABLE_COLOR, CABLE_PX = (0.5, 0.5, 0.55, 1.0), 3.0  # cables: mid grey (light and dark themes), width on screen [px]
FORCE_COLOR, FORCE_M_PER_N = (1.0, 0.6, 0.0, 1.0), 0.01  # the force arrow: 1 cm per newton


def x_onto(ux: float, uy: float, uz: float) -> tuple:
    """Quaternion (x, y, z, w) of the shortest rotation taking +x onto the unit vector u (Foxglove's arrows
    point along their pose's +x): axis x cross u = (0, -uz, uy), half-angle form."""
    w = 1.0 + ux
    if w < 1e-9:  # u = -x: half a turn about z
        return 0.0, 0.0, 1.0, 0.0
    k = math.sqrt(2.0 * w)
    return 0.0, -uz / k, uy / k, w / k


def _arrow(origin, f) -> list:
    """A foxglove ArrowPrimitive for force f (3,) [N] at `origin` (3,) [m] (FORCE_M_PER_N), [] for no force."""
    n = math.sqrt(f[0] ** 2 + f[1] ** 2 + f[2] ** 2)
    length = FORCE_M_PER_N * n
    if not length > 1e-4:
        return []
    qx, qy, qz, qw = x_onto(f[0] / n, f[1] / n, f[2] / n)
    q = Quaternion(x=qx, y=qy, z=qz, w=qw)
    head = min(0.004, 0.4 * length)
    return [ArrowPrimitive(pose=Pose(position=Vector3(x=origin[0], y=origin[1], z=origin[2]), orientation=q),
                           shaft_length=length - head, shaft_diameter=0.0015, head_length=head, head_diameter=0.004,
                           color=Color(r=FORCE_COLOR[0], g=FORCE_COLOR[1], b=FORCE_COLOR[2], a=FORCE_COLOR[3]))]


def plot_schema(layout: Layout, topic: str) -> bytes:
    """JSON schema of a plot channel (numbers and arrays of numbers, with `t` [s] and `tick`)."""
    widths = {s.name: s.width for s in layout.signals}
    if "position_steps" in widths:
        widths["measured_lengths"] = widths["position_steps"]   # derived from the steps (RowMessages.plot)
    props = {"tick": {"type": "integer"}, "t": {"type": "number", "description": "session time [s]"}}
    for name in plots(layout)[topic][1]:
        if name in widths:
            listed = widths[name] > 1 or (topic == TOPIC_FBG_LIVE and name in FBG_PER_SENSOR)
            props[name] = {"type": "array", "items": {"type": "number"}} if listed else {"type": "number"}
    if topic == "/live/loop":
        props["state_name"] = {"type": "string"}
    return json.dumps({"type": "object", "properties": props}).encode()


# the live view's own counters on /live/stats: key -> (JSON type, description)
STATS_FIELDS = {"t": ("number", "session time [s]"),
                "rows_skipped": ("integer", "rows of the ring the live view fell behind on and skipped"),
                "frames_dropped": ("integer", "frames dropped for viewers that read too slowly"),
                "frames_sent": ("integer", "frames sent to viewers"),
                "viewers": ("integer", "viewers connected")}


def stats_schema() -> bytes:
    """JSON schema of /live/stats (every key of `stats_message`)."""
    props = {k: {"type": tp, "description": d} for k, (tp, d) in STATS_FIELDS.items()}
    return json.dumps({"type": "object", "properties": props}).encode()


def stats_message(t: float, rows_skipped: int, frames_dropped: int, frames_sent: int, viewers: int) -> bytes:
    """One /live/stats message (t [s] of session time, counters since the start)."""
    return json.dumps({"t": float(t), "rows_skipped": int(rows_skipped), "frames_dropped": int(frames_dropped),
                       "frames_sent": int(frames_sent), "viewers": int(viewers)}).encode()


class RowMessages:
    """Builds the live messages from a row (the column names of teleop.loop.tap.session_layout).

    Args:
        layout: the session's row layout.
        geometry: {"B": (6, 3) base anchors [m], "r": (6, 3) platform anchors [m]} or None.
        pads: [{"name", "center": (3,) [m], "size": (2,) [m], "outline": "disc" | "square", "thickness" [m],
            "color": (r, g, b, a)}] drawn in the scene (teleop.loop.session.pad_scene).
    """

    def __init__(self, layout: Layout, geometry: dict | None = None, pads: list | None = None):
        self.cols = layout.columns()
        self.plots = {topic: [n for n in names if n in self.cols] for topic, (_, names) in plots(layout).items()}
        self.listed = {(TOPIC_FBG_LIVE, n) for n in FBG_PER_SENSOR}  # lists whatever their width
        # the lengths the motors measure: home lengths minus the steps hauled in (needs both from the session)
        self.L_home = (geometry or {}).get("L_home")
        self.steps_per_m = (geometry or {}).get("steps_per_m")
        if self.L_home is not None and self.steps_per_m and "position_steps" in self.cols:
            self.plots["/live/cables"].append("measured_lengths")
        self.B = (geometry or {}).get("B")
        self.r = (geometry or {}).get("r")
        self.pads = list(pads or [])

    def plot(self, topic: str, row) -> bytes:
        c = self.cols
        msg = {"tick": int(row[c["tick"]][0]), "t": float(row[c["t"]][0])}
        for name in self.plots[topic]:
            if name == "measured_lengths":
                steps = row[c["position_steps"]]
                msg[name] = [float(L - n / self.steps_per_m) for L, n in zip(self.L_home, steps)]
                continue
            v = row[c[name]].tolist()
            msg[name] = v[0] if len(v) == 1 and (topic, name) not in self.listed else v
        if topic == "/live/loop":
            s = int(msg["state"])
            msg["state_name"] = STATE_NAMES[s] if 0 <= s < len(STATE_NAMES) else str(s)
        return orjson.dumps(msg, option=orjson.OPT_SERIALIZE_NUMPY)

    def transforms(self, row, t_ns: int) -> bytes:
        c = self.cols
        return frame_transforms(row[c["setpoint_cp"]].tolist(), row[c["measured_cp"]].tolist(), t_ns)

    def scene(self, row, t_ns: int) -> bytes:
        c = self.cols
        ts = stamp(t_ns)
        ee = row[c["setpoint_cp"]].tolist()
        state = int(row[c["state"]][0])
        rgba = EE_FAULT_COLOR if state == 4 else EE_COLOR
        ident = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
        d = EE_DIAMETER
        entities = [SceneEntity(timestamp=ts, frame_id=WORLD, id="end_effector", spheres=[SpherePrimitive(
            pose=Pose(position=Vector3(x=ee[0], y=ee[1], z=ee[2]), orientation=ident),
            size=Vector3(x=d, y=d, z=d), color=Color(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3]))])]
        entities.append(SceneEntity(timestamp=ts, frame_id=WORLD, id="force",
                                    arrows=_arrow(ee, row[c["measured_cf"]].tolist()[:3])))
        if self.B is not None and self.r is not None:
            pts = []
            for b, r in zip(self.B, self.r):
                pts += [Point3(x=b[0], y=b[1], z=b[2]), Point3(x=ee[0] + r[0], y=ee[1] + r[1], z=ee[2] + r[2])]
            entities.append(SceneEntity(timestamp=ts, frame_id=WORLD, id="cables", lines=[LinePrimitive(
                type=LinePrimitiveLineType.LineList, thickness=CABLE_PX, scale_invariant=True, points=pts,
                color=Color(r=CABLE_COLOR[0], g=CABLE_COLOR[1], b=CABLE_COLOR[2], a=CABLE_COLOR[3]))]))
        for pad in self.pads:
            x, y, z = pad["center"]
            sx, sy = pad["size"]
            col = pad.get("color") or (0.8, 0.5, 0.6, 0.8)
            color = Color(r=col[0], g=col[1], b=col[2], a=col[3])
            pose = Pose(position=Vector3(x=x, y=y, z=z), orientation=ident)
            size = Vector3(x=sx, y=sy, z=float(pad.get("thickness", 0.01)))
            shape = {"cylinders": [CylinderPrimitive(pose=pose, size=size, bottom_scale=1.0, top_scale=1.0,
                                                     color=color)]} if pad.get("outline") == "disc" else \
                {"cubes": [CubePrimitive(pose=pose, size=size, color=color)]}
            entities.append(SceneEntity(timestamp=ts, frame_id=WORLD, id=f"pad/{pad['name']}", **shape))
        return SceneUpdate(entities=entities).encode()
