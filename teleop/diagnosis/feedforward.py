"""Feed-forward pre-compensation of backlash in the position command (cable-pulley seed 002).

The play operator y_k = clamp(y_k-1, x_k - w/2, x_k + w/2) is inverted by driving the motor half the
play ahead of the wanted tip position in the direction of motion: x = y_d + (w/2) s, s the held direction
of y_d; at each reversal the command crosses the dead band at once (or at `max_step` per sample). The
step is the kernel teleop.kernels.friction.play_inverse_step (one definition for the offline array form
`backlash_inverse` and the robot's command path `BacklashFeedforward`).

On the robot (`teleop session --compensation MODEL`, devices.wrappers.BacklashCompensatedRobot) each cable
gets the inverse of its play, with two rules the offline form leaves out:
- a dead band on the direction (`deadband`, default DEADBAND_M): the wanted length must come back more
  than it from its extreme before the command crosses to the other side, so stylus tremor and sensor
  noise never make the command chatter across the play;
- the safety limits: the command's change per command period is at most v_max * period (the reversal's
  jump of w is spread over w / (v_max period) periods, less the wanted motion's own share of the speed),
  and each command stays in [l_min, l_max] (at a limit the compensation saturates: the cable falls short
  of its wanted length by up to w/2 there, never beyond the limit).
"""

from __future__ import annotations

import math

import numpy as np

from teleop.diagnosis.links import LinkModel
from teleop.kernels import friction as KF
from teleop.errors import InputError


def backlash_inverse(y_d: np.ndarray, width: float, max_step: float | None = None) -> np.ndarray:
    """(n,) input x that makes a play of total `width` output y_d (n,) [same unit]; max_step limits the
    per-sample change of x while crossing the dead band (None: cross in one sample)."""
    y_d = np.ascontiguousarray(y_d, dtype=float)
    step = math.inf if max_step is None else float(max_step)
    return KF.play_inverse_run(y_d, 0.5 * float(width), 0.0, step, np.empty(y_d.shape[0]))


def precompensate(model: LinkModel, tip_target: np.ndarray, max_step: float | None = None) -> np.ndarray:
    """Motor command (n,) [input unit] making the position link `model` (gain, offset, backlash) follow
    tip_target (n,) [output unit]: x = (backlash_inverse(tip_target) - offset) / gain."""
    if model.link.kind != "position":
        raise InputError(f"precompensate: needs a position link model, got {model.link.kind}")
    width = 0.0
    for name, p in model.effects:
        if name == "backlash":
            width = float(p["width"])
    z = backlash_inverse(tip_target, width, None if max_step is None else abs(model.gain) * max_step)
    return (z - model.offset) / model.gain


#: default dead band on the wanted length's direction [m]: well above the stylus tremor at the robot (the
#: operator model's 5 mN tremor on a 150 N/m hand, ~30 um, times the 0.25 motion scale: ~8 um) and small
#: beside a play worth compensating (0.1 mm and up)
DEADBAND_M = 20e-6


def model_backlash_width(model, where: str = "model") -> float:
    """Total play width [m] of the backlash finding on the position link of an identified model
    (teleop.diagnosis.model_io.IdentifiedModel); InputError naming `where` when it has none."""
    pos = model.links.get("position")
    widths = [float(p["width"]) for name, p in (pos.effects if pos is not None else ()) if name == "backlash"]
    if not widths:
        found = ", ".join(f"{k}: {', '.join(n for n, _ in m.effects) or 'no effects'}" for k, m in model.links.items())
        raise InputError(f"{where}: no backlash on a position link to compensate (has {found or 'no links'}); "
                         "expected a `teleop diagnose --save-model` file of a motor_pos -> tip_pos recording, or "
                         "the hand-written form in docs/feedforward.md")
    return sum(widths)


class BacklashFeedforward:
    """Per-cable backlash inverse in a command path, one command at a time (module docstring).

    Args:
        width: (n,) or scalar total play per cable [m].
        n: number of cables.
        max_step: largest change of a cable's command per call [m] (v_max * command period).
        lo, hi: length limits [m] (scalars).
        deadband: dead band of the direction rule [m].
    """

    def __init__(self, width, n: int, max_step: float, lo: float = -math.inf, hi: float = math.inf,
                 deadband: float = DEADBAND_M):
        w = np.broadcast_to(np.asarray(width, dtype=float), (n,))
        if not (np.isfinite(w).all() and (w >= 0).all()):
            raise InputError(f"backlash feed-forward: play widths must be finite and >= 0, got {w.tolist()}")
        if not (max_step > 0 and deadband >= 0 and lo < hi):
            raise InputError("backlash feed-forward: need max_step > 0, deadband >= 0 and lo < hi")
        self.r = np.ascontiguousarray(0.5 * w)
        self.max_step, self.deadband = float(max_step), float(deadband)
        self.lo, self.hi = np.full(n, float(lo)), np.full(n, float(hi))
        self.state = np.empty((3, n))
        self.out = np.empty(n)
        self.reset()
        self.step(np.zeros(n))  # compile or load the kernel now, not in the first command
        self.reset()

    def reset(self) -> None:
        """Forget the directions and the last command (the next command starts with the play centred)."""
        self.state[0] = 0.0
        self.state[1:] = np.nan

    def step(self, lengths) -> np.ndarray:
        """Motor-side commands (n,) [m] (a buffer overwritten by the next call) for wanted lengths (n,) [m]."""
        y = np.ascontiguousarray(lengths, dtype=float)
        return KF.play_inverse_into(y, self.r, self.deadband, self.max_step, self.lo, self.hi, self.state, self.out)
