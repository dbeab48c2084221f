"""Feed-forward pre-compensation of backlash in the position command (cable-pulley seed 002).

The play operator y_k = clamp(y_k-1, x_k - w/2, x_k + w/2) is inverted by driving the motor half the
play ahead of the wanted tip position in the direction of motion: x = y_d + (w/2) s, s the held direction
of y_d; at each reversal the command crosses the dead band at once (or at `max_step` per sample). The
step is the kernel teleop.core.kernels.friction.play_inverse_step (one definition for the offline array form
`backlash_inverse` and the robot's command path `BacklashFeedforward`).

On the robot (`teleop session --compensation MODEL`, devices.wrappers.BacklashCompensatedRobot) each cable
gets the inverse of its play, x = y_d + (w/2) s, with two rules the offline form leaves out:
- a smooth side instead of the held sign: s = clip(v / v0, -1, 1), v the wanted length's rate low-passed
  with time constant `tau` (default TAU_S), v0 = `v0` (default V0_M_S). Near a reversal the wanted length
  slows down, so the command starts across the play before the reversal instead of after it; at rest s
  goes to 0 (the play centred: either direction then costs half a crossing). Noise only moves the motor
  inside the play: with x - w/2 <= y_d <= x + w/2 for every s, a wanted length that holds still holds the
  cable still, so the cable never chatters;
- the safety limits: the command's change per command period is at most v_max * period, so a reversal's
  crossing of w takes at least w / v_max (25 ms for 0.5 mm at 20 mm/s; longer while the wanted length moves
  the other way), and each command stays in [l_min, l_max] (at a limit the compensation saturates: the
  cable falls short of its wanted length by up to w/2 there, never beyond the limit).
The held sign (a Schmitt trigger on the direction) measured worse in closed loop: the operator's hand,
pushed by the rendered force, reverses each cable several times a second, and every reversal then waits
for a full rate-limited crossing after it (`teleop bench feedforward`; docs/feedforward.md).
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.errors import InputError
from teleop.core.kernels import friction as KF
from teleop.core.physics.links import LinkModel
from teleop.core.physics.pulley import PulleyChain, pulley_band, pulley_elongation


def backlash_inverse(y_d: np.ndarray, width: float, max_step: float | None = None) -> np.ndarray:
    """(n,) input x that makes a play of total `width` output y_d (n,) [same unit]; max_step limits the
    per-sample change of x while crossing the dead band (None: cross in one sample)."""
    y_d = np.ascontiguousarray(y_d, dtype=float)
    step = math.inf if max_step is None else float(max_step)
    return KF.play_inverse_run(y_d, 0.5 * float(width), step, np.empty(y_d.shape[0]))


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


def pulley_precompensate(tip_target: np.ndarray, T_tip: float, chain: PulleyChain,
                         max_step: float | None = None) -> np.ndarray:
    """Seed 002's model-based position compensation: motor command (n,) [m] making a pulley chain's tip
    (teleop.core.physics.pulley: tip = x - elongation) follow tip_target (n,) [m] under the tip tension
    T_tip [N]. Sliding, the tip trails the motor by the pulling elongation e_hi one way and by the releasing
    one e_lo the other, so the chain is a play of width e_hi - e_lo centred on their mean:
    x = backlash_inverse(tip_target + (e_hi + e_lo) / 2, e_hi - e_lo). Unlike the plain inverse its width and
    offset follow the load and the chain (friction, bending rigidity, spans, EA). The elongation is absolute
    (zero for a slack cable)."""
    lo, hi = pulley_band([T_tip], chain)
    e_lo, e_hi = pulley_elongation(lo, [T_tip], chain)[0], pulley_elongation(hi, [T_tip], chain)[0]
    return backlash_inverse(np.asarray(tip_target, dtype=float) + 0.5 * (e_hi + e_lo), e_hi - e_lo, max_step)


#: rate [m/s] at which the command drives on the full side of the play: about ten times the rate noise of
#: the operator's tremor at the robot (devices.simulated: 5 mN on a 150 N/m hand with a 50 ms correlation
#: time, ~30 um over 50 ms at the stylus, x 0.25 motion scale: ~0.2 mm/s); the best of 1, 2, 3 and 6 mm/s
#: on `teleop bench feedforward` (seeds 0 and 1)
V0_M_S = 2e-3
#: time constant [s] of the low-pass on the wanted length's rate (10 ms: five 500 Hz commands)
TAU_S = 0.01


def model_backlash_width(model, where: str = "model") -> float:
    """Total play width [m] of the backlash finding on the position link of an identified model
    (teleop.io.model_io.IdentifiedModel); InputError naming `where` when it has none."""
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
        period: time between commands [s].
        v_max: largest cable speed [m/s]: each command moves at most v_max * period.
        lo, hi: length limits [m] (scalars).
        v0: rate [m/s] from which the command drives on the full side of the play.
        tau: time constant [s] of the low-pass on the wanted rate.
    """

    def __init__(self, width, n: int, period: float, v_max: float, lo: float = -math.inf, hi: float = math.inf,
                 v0: float = V0_M_S, tau: float = TAU_S):
        w = np.broadcast_to(np.asarray(width, dtype=float), (n,))
        if not (np.isfinite(w).all() and (w >= 0).all()):
            raise InputError(f"backlash feed-forward: play widths must be finite and >= 0, got {w.tolist()}")
        if not (period > 0 and v_max > 0 and v0 > 0 and tau >= 0 and lo < hi):
            raise InputError("backlash feed-forward: need period, v_max, v0 > 0, tau >= 0 and lo < hi")
        self.r = np.ascontiguousarray(0.5 * w)
        self.period, self.max_step = float(period), float(v_max) * float(period)
        self.v0, self.tau = float(v0), float(tau)
        self.alpha = self.period / (self.tau + self.period)  # v += alpha (rate - v): first-order low-pass
        self.lo, self.hi = np.full(n, float(lo)), np.full(n, float(hi))
        self.state = np.empty((3, n))
        self.out = np.empty(n)
        self.reset()
        self.step(np.zeros(n))  # compile or load the kernel now, not in the first command
        self.reset()

    def reset(self) -> None:
        """Forget the rates and the last command (the next command starts with the play centred)."""
        self.state[0] = np.nan
        self.state[1] = 0.0
        self.state[2] = np.nan

    def step(self, lengths, dt: float | None = None) -> np.ndarray:
        """Motor-side commands (n,) [m] (a buffer overwritten by the next call) for wanted lengths (n,) [m];
        dt: time since the previous command [s] for the rate (None: `period`; a loop that runs late sends
        commands unevenly, and the wanted rate is their change over the time that really passed; at least a
        tenth of `period`)."""
        y = np.ascontiguousarray(lengths, dtype=float)
        if dt is None or dt == self.period:
            dt, alpha = self.period, self.alpha
        else:
            dt = max(float(dt), 0.1 * self.period)
            alpha = dt / (self.tau + dt)
        return KF.play_inverse_into(y, self.r, self.v0, alpha, dt, self.max_step, self.lo, self.hi, self.state,
                                    self.out)
