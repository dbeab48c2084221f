"""Direction of motion with a dead band (a Schmitt trigger on reversals), for n channels at once.

Used for the cables' loading/unloading decision (seed 000 eq 7: the direction of the cable length change),
the FSR branch choice (direction of the reading) and the end effector's turns (seed 000 step 3).
"""

from __future__ import annotations

import numpy as np


class DirectionTracker:
    """Per-channel direction +1 (increasing), -1 (decreasing) or 0 (not yet moved).

    A channel's direction flips only when its value has come back more than `deadband` from the extreme
    reached since the last flip; with deadband 0 any decrease after an increase flips it. `flipped` holds
    which channels reversed on the last update.
    """

    def __init__(self, n: int, deadband: float = 0.0):
        self.n = int(n)
        self.deadband = float(deadband)
        self.reset()

    def reset(self) -> None:
        self._d = [0.0] * self.n
        self._e = [float("nan")] * self.n
        self.direction = np.zeros(self.n)
        self.extreme = np.full(self.n, np.nan)
        self.flipped = np.zeros(self.n, dtype=bool)

    def update(self, value) -> np.ndarray:
        """(n,) direction after seeing `value` (n,). (A float loop: faster than numpy for a few channels.)"""
        vals = value.tolist() if isinstance(value, np.ndarray) else [float(v) for v in value]
        d, e, db = self._d, self._e, self.deadband
        flipped = [False] * self.n
        for i, v in enumerate(vals):
            di, ei = d[i], e[i]
            if ei != ei:  # first value: the reference
                ei = v
            if di <= 0.0 and v > ei + db:      # rising past the dead band
                flipped[i], di, ei = di < 0.0, 1.0, v
            elif di >= 0.0 and v < ei - db:    # falling past the dead band
                flipped[i], di, ei = di > 0.0, -1.0, v
            elif di > 0.0 and v > ei:          # the extreme follows the motion
                ei = v
            elif di < 0.0 and v < ei:
                ei = v
            d[i], e[i] = di, ei
        self.direction = np.array(d)
        self.extreme = np.array(e)
        self.flipped = np.array(flipped)
        return self.direction
