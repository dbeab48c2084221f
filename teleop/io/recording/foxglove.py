"""A tick row in Foxglove's well-known schemas (protobuf, foxglove-sdk's encoders).

Shared by the recording (its /teleop/log and /tf views) and the live view (teleop.loop.live.channels).
"""

from __future__ import annotations

from foxglove.messages import (FrameTransform, FrameTransforms, Log, LogLevel, Quaternion, Timestamp, Vector3)

STATE_NAMES = ("DISABLED", "ALIGNING", "ENABLED", "CLUTCHED", "FAULT")  # teleop.loop.states.State values
WORLD = "world"  # the robot's base frame {B}


def stamp(t_ns: int) -> Timestamp:
    return Timestamp(sec=t_ns // 1_000_000_000, nsec=t_ns % 1_000_000_000)


def frame_transforms(ee: list, stylus: list, t_ns: int) -> bytes:
    """The end effector and the stylus as a foxglove.FrameTransforms: positions (3,) [m] in {B}, no rotation."""
    ts = stamp(t_ns)
    q = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
    return FrameTransforms(transforms=[
        FrameTransform(timestamp=ts, parent_frame_id=WORLD, child_frame_id="end_effector",
                       translation=Vector3(x=ee[0], y=ee[1], z=ee[2]), rotation=q),
        FrameTransform(timestamp=ts, parent_frame_id=WORLD, child_frame_id="stylus",
                       translation=Vector3(x=stylus[0], y=stylus[1], z=stylus[2]), rotation=q)]).encode()


def fault_log(event: dict, t_ns: int) -> bytes:
    """A state change as a foxglove.Log (ERROR for FAULT, WARNING for leaving ENABLED, INFO otherwise)."""
    dst = str(event.get("dst", ""))
    level = LogLevel.Error if dst == "FAULT" else (LogLevel.Warning if event.get("src") == "ENABLED" else
                                                   LogLevel.Info)
    text = f"{event.get('src', '')} -> {dst}" + (f": {event['reason']}" if event.get("reason") else "")
    return Log(timestamp=stamp(t_ns), level=level, message=text, name="teleop.loop", file="", line=0).encode()
