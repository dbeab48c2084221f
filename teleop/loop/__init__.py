"""The master-slave loop: state machine, safety monitors, rendering through teleop.core.rendering, pacing and timing
statistics."""

from teleop.loop.core import STAGES, Event, Teleop, TickData
from teleop.loop.params import LoopParams
from teleop.loop.states import State

__all__ = ["STAGES", "Event", "LoopParams", "State", "Teleop", "TickData"]
