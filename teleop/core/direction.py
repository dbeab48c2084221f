"""Direction of motion with a dead band (a Schmitt trigger on reversals), for n channels at once.

Used for the cables' loading/unloading decision (seed 000 eq 7: the direction of the cable length change),
the FSR branch choice (direction of the reading) and the end effector's turns (seed 000 step 3).
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.estimate import direction_update


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
        self._d, self._e, self._f = np.zeros(self.n), np.full(self.n, np.nan), np.zeros(self.n, dtype=bool)
        self.direction, self.extreme, self.flipped = self._d.copy(), self._e.copy(), self._f.copy()

    def update(self, value) -> np.ndarray:
        """(n,) direction after seeing `value` (n,) (teleop.core.kernels.friction.direction_step per channel)."""
        direction_update(self._d, self._e, self._f, np.asarray(value, dtype=float).reshape(self.n), self.deadband)
        self.direction, self.extreme, self.flipped = self._d.copy(), self._e.copy(), self._f.copy()
        return self.direction
