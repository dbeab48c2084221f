"""The estimator protocol the loop calls (the force path is teleop.core.rendering.Renderer).

The default estimator is teleop.core.estimation.reading.ReadingEstimator ("dynamic": FSR branches, capstan and
turn compensation, f = -A t, steady-state Kalman).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class Estimator(Protocol):
    """Raw robot readings -> cable tensions t (6,) [N] and external wrench f (6,) [N, N m]."""

    def reset(self) -> None: ...
    def update(self, reading, pose, dt: float) -> tuple[np.ndarray, np.ndarray]: ...
    def describe(self) -> dict:
        """Calibration and settings, stored in the session metadata."""
