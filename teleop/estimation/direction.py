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
        self.direction = np.zeros(self.n)
        self.extreme = np.full(self.n, np.nan)
        self.flipped = np.zeros(self.n, dtype=bool)

    def update(self, value) -> np.ndarray:
        """(n,) direction after seeing `value` (n,)."""
        v = np.asarray(value, dtype=float)
        first = np.isnan(self.extreme)
        self.extreme[first] = v[first]
        d, e, db = self.direction, self.extreme, self.deadband
        rise = v > e + db
        fall = v < e - db
        # unknown or decreasing channels start rising past the dead band; likewise falling
        to_up = (d <= 0) & rise
        to_down = (d >= 0) & fall
        self.flipped = (to_up & (d < 0)) | (to_down & (d > 0))
        new_d = np.where(to_up, 1.0, np.where(to_down, -1.0, d))
        # the extreme follows the motion: max while rising, min while falling, reset at a flip
        new_e = np.where(to_up | to_down, v, np.where(new_d > 0, np.maximum(e, v), np.where(new_d < 0, np.minimum(e, v), e)))
        self.direction, self.extreme = new_d, new_e
        return new_d
