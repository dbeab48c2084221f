"""`teleop export FILE --csv OUT [--cable N]`: a session as the interchange CSV (docs/formats.md), one cable.

Columns (one row per robot telemetry frame): t_s (the reading's own time stamp, `t_robot`: when the robot
sampled it, which rate laws need; the loop's receive time, jittered by scheduling, where the robot's stamps do
not increase); motor_pos_mm (cable hauled in by the motor, from the step count,
+ = shortening); tip_pos_mm (cable hauled in at the end effector, from the simulator's actual tip pose when
the recording has it); motor_force_N (the FSR's calibrated tension, the sensor side of the distal sheath
segment); tip_force_N (tension at the end effector, when the recording has the simulator's truth);
bend_angle_deg (eq 6 bend at the setpoint pose plus the scaffold bend theta0); cmd_len_mm (commanded length).
A session with distal FBGs (`sim://robot?sensor=fbg|one`: the recording's /sensors/fbg channel) adds
fbg_dl1_pm, fbg_dl2_pm, fbg_force_N (the cable's FBG shifts and its eq 3 tension, when the cable carries one)
and est_tip_force_N (the loop's tip-side tension estimate: the FBG's, or for sensor one eq 7's); its
motor_force_N is the proximal FSR tension the one-sensor model read (sensor one), none for sensor fbg (whose
estimate is tip-side).

`--truth` (simulated robot only): motor_force_N is the simulator's tension at the FSR (x_t_fsr) instead of
the FSR-calibrated estimate, and motor_pos_mm the motor position its cable physics runs on (its steppers are
ideal: the commanded length, L_home - L) instead of the step count rounded to 9.8 um, so that a diagnosis sees
the transmission without the sensor chain. (On the step count a slow reversal leaves the drive flat for tens
of ms, and a Coulomb friction and a force-sensor hysteresis, which flip at the same reversal, fit alike.) A session
on the simulated robot also writes the simulation's sheath friction coefficient as the metadata line
`capstan_friction.mu = MU`: `teleop diagnose` holds it in its baseline (the simulation already has it), so
that a friction the simulated robot was given on top (`sim://robot?model=FILE`) is not refitted into it.
"""

from __future__ import annotations

import sys

import numpy as np

from devices.base import RobotSpec
from teleop.apps.argtypes import input_file
from teleop.core.errors import InputError
from teleop.core.kinematics import bending_angles, pose2cables, pose2lengths, rotation_zyx
from teleop.io.outputs import atomic_write
from teleop.io.recording import TOPIC_ROBOT, TOPIC_SETPOINT, read_session
from teleop.io.recording.sensors import TOPIC_FBG
from teleop.loop.replay import geometry_from


def register(subparsers) -> None:
    p = subparsers.add_parser("export", help="write a recorded session as the interchange CSV (one cable)")
    p.add_argument("file", type=input_file, help="session recording (.mcap)")
    p.add_argument("--csv", required=True, metavar="OUT", help="output CSV")
    p.add_argument("--cable", type=int, default=1, help="cable 1..6 (default 1)")
    p.add_argument("--truth", action="store_true",
                   help="simulated robot: motor_force_N from the simulator's tension at the FSR, not the FSR estimate, "
                        "and motor_pos_mm from the commanded length its cable physics runs on, not the step count")
    p.set_defaults(func=run)


def export_rows(session, cable: int, truth: bool = False):
    """(header, rows) of the interchange CSV for `cable` (1-based); truth: motor_force_N from the simulator's
    FSR-side tension (InputError when the recording has none)."""
    meta = session.metadata.get("session", {})
    conf = meta.get("configuration", {})
    geom = geometry_from(conf.get("geometry"))
    steps_per_m = float((conf.get("robot_spec") or {}).get("steps_per_m", RobotSpec.steps_per_m))
    home = np.array(((conf.get("loop") or {}).get("mapping") or {}).get("home", [0.0] * 6), dtype=float)
    L_home = pose2lengths(home, geom)
    i = cable - 1
    est = {m["tick"]: m for m in session.messages("/estimation")}
    sp = {m["tick"]: m for m in session.messages(TOPIC_SETPOINT)}
    fbg = {m["tick"]: m for m in session.messages(TOPIC_FBG)}  # FBG sensor kinds (module docstring)
    header = ["t_s", "motor_pos_mm", "tip_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "cmd_len_mm"]
    if fbg:
        header += ["fbg_dl1_pm", "fbg_dl2_pm", "fbg_force_N", "est_tip_force_N"]
    rows, loop_t = [], []
    last_seq = None
    for m in session.messages(TOPIC_ROBOT):
        k = m["tick"]
        if k not in est or k not in sp or m["seq"] == last_seq:
            continue  # one row per telemetry frame (the loop may see a frame on several ticks)
        last_seq = m["seq"]
        pose = home.copy()
        pose[:3] = sp[k]["setpoint_cp"]
        theta = bending_angles(pose2cables(pose, geom), geom)[i] + geom.theta0
        tip_pos = tip_force = float("nan")
        if "x_tip" in m:  # simulator truth: actual tip -> actual pose -> actual lengths
            actual = np.array(m.get("x_pose", pose), dtype=float)
            actual[:3] = np.array(m["x_tip"]) - rotation_zyx(*actual[3:]) @ geom.tip
            tip_pos = (L_home[i] - pose2lengths(actual, geom)[i]) * 1e3
        if "x_t_tip" in m:
            tip_force = float(m["x_t_tip"][i])
        if truth and "x_t_fsr" not in m:
            raise InputError("--truth: the recording has no simulator tensions (x_t_fsr): was the robot sim://robot?")
        motor_force = float(m["x_t_fsr"][i]) if truth else est[k]["tensions"][i]
        loop_t.append(m["t"])
        motor_pos = ((L_home[i] - m["commanded_lengths"][i]) if truth else m["position_steps"][i] / steps_per_m) * 1e3
        rows.append([m.get("t_robot", m["t"]), motor_pos, tip_pos, motor_force, tip_force,
                     float(np.rad2deg(theta)), m["commanded_lengths"][i] * 1e3])
        if fbg:
            s = {f: np.atleast_1d(v) for f, v in fbg.get(k, {}).items()}  # k = 1 cable: numbers, not lists
            on = np.flatnonzero(s.get("fbg_cable", np.empty(0)) == i)
            if not truth:
                rows[-1][3] = float(s["proximal"][i]) if "proximal" in s else float("nan")
            rows[-1] += [float(s[f][on[0]]) if on.size else float("nan") for f in ("fbg_dl1_pm", "fbg_dl2_pm",
                                                                                     "fbg_force")]
            rows[-1].append(est[k]["tensions"][i])
    t_robot = np.array([r[0] for r in rows], dtype=float)
    if rows and not (np.all(np.isfinite(t_robot)) and np.all(np.diff(t_robot) > 0)):
        for r, t in zip(rows, loop_t):   # the robot's stamps restart or repeat: the loop's receive times
            r[0] = t
    keep = [j for j in range(len(header)) if not all(r[j] != r[j] for r in rows)] if rows else list(range(len(header)))
    header = [header[j] for j in keep]
    rows = [[r[j] for j in keep] for r in rows]
    return header, rows


def run(args) -> int:
    if not 1 <= args.cable <= 6:
        raise InputError(f"--cable must be 1..6, got {args.cable}")
    s = read_session(args.file)
    if "session" not in s.metadata:
        damage = f" ({s.damage})" if s.damage else ""
        raise InputError(f"{args.file}: no session metadata (is this a teleop session recording?){damage}")
    if s.damage:
        print(f"teleop: warning: {args.file}: {s.damage}; exporting the intact prefix", file=sys.stderr)
    header, rows = export_rows(s, args.cable, args.truth)
    if not rows:
        raise InputError(f"{args.file}: no robot readings to export")
    conf = s.metadata["session"].get("configuration", {})
    source = ("simulator's tension at the FSR (truth)" if args.truth else
              "FSR-calibrated tension (sensor side of the distal sheath segment)")
    lines = [f"# source = teleop session {args.file}", "# load = external", f"# cable = {args.cable}",
             f"# motor_force_N = {source}"]
    mu = (conf.get("geometry") or {}).get("mu")
    if str(conf.get("robot", "")).startswith("sim://robot") and mu is not None:
        lines.append(f"# capstan_friction.mu = {float(mu)!r}")   # the simulation's own sheath friction
    lines.append(",".join(header))
    lines += [",".join(repr(float(v)) for v in r) for r in rows]
    text = "\n".join(lines) + "\n"
    atomic_write(args.csv, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    print(f"wrote {args.csv}: {len(rows)} rows, columns {', '.join(header)}")
    return 0
