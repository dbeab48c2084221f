"""Teleoperation state machine (dVRK mtsTeleOperationPSM style): one object per state with enter / command /
force / transition, no global run flags.

    DISABLED --enable requested, telemetry fresh, robot homed--> ALIGNING
    ALIGNING --operator present, stylus aligned, telemetry fresh, computed force small N ticks--> ENABLED
    ENABLED  --clutch--> CLUTCHED --clutch released--> ENABLED (re-anchored, force ramps in again)
    ENABLED/CLUTCHED --operator gone--> ALIGNING;  any --disable--> DISABLED
    any --fault--> FAULT (latched: only operator_reset() leaves it, to DISABLED)

`command` returns the cable lengths to send this tick (or None: no motion command). Only ENABLED moves the
robot or pushes on the operator: the loop enables its teleop.core.rendering.Renderer when entering ENABLED (the
force ramps in) and disables it when leaving (zero force), so the states decide WHEN and the Renderer HOW.
"""

from __future__ import annotations

from enum import IntEnum

from teleop.core.mapping import is_aligned


class State(IntEnum):
    DISABLED = 0
    ALIGNING = 1
    ENABLED = 2
    CLUTCHED = 3
    FAULT = 4


class Behaviour:
    """Default behaviour: no motion, stay."""

    state: State

    def enter(self, tp, now: float) -> None:
        pass

    def command(self, tp, x):
        return None

    def transition(self, tp, x) -> State | None:
        return None


class Disabled(Behaviour):
    state = State.DISABLED

    def transition(self, tp, x):
        if tp.enable_requested and tp.telemetry_fresh(x.now) and tp.robot_homed:
            return State.ALIGNING
        return None


class Aligning(Behaviour):
    state = State.ALIGNING

    def enter(self, tp, now):
        tp.small_force_ticks = 0

    def transition(self, tp, x):
        if not tp.enable_requested:
            return State.DISABLED
        s = x.sample
        ready = (s is not None and s.operator_present and not (s.buttons & 2) and tp.telemetry_fresh(x.now)
                 and tp.robot_homed and is_aligned(s.orientation, tp.params.mapping))
        if ready and tp.small_force_ticks >= tp.params.render.engage_ticks:
            return State.ENABLED
        return None


def _leave(tp, x) -> State | None:
    """ENABLED/CLUTCHED: DISABLED when enable is withdrawn, ALIGNING when the operator or homing is gone."""
    if not tp.enable_requested:
        return State.DISABLED
    if not x.sample.operator_present or not tp.robot_homed:
        return State.ALIGNING
    return None


class Enabled(Behaviour):
    state = State.ENABLED

    def enter(self, tp, now):
        tp.anchor(now)

    def command(self, tp, x):
        return tp.follow(x)

    def transition(self, tp, x):
        nxt = _leave(tp, x)
        if nxt is None and x.sample.buttons & 2:
            return State.CLUTCHED
        return nxt


class Clutched(Behaviour):
    state = State.CLUTCHED

    def transition(self, tp, x):
        nxt = _leave(tp, x)
        if nxt is None and not x.sample.buttons & 2:
            return State.ENABLED
        return nxt


class Fault(Behaviour):
    state = State.FAULT

    def enter(self, tp, now):
        tp.stop_robot()

    def transition(self, tp, x):
        if tp.reset_requested:
            return State.DISABLED
        return None


BEHAVIOURS = {b.state: b for b in (Disabled(), Aligning(), Enabled(), Clutched(), Fault())}
