"""Loop parameters: rates, force path, safety thresholds (SI, frozen)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from teleop.errors import InputError
from teleop.mapping import MappingParams


@dataclass(frozen=True)
class LoopParams:
    """Master-slave loop settings.

    Attributes:
        rate_hz: haptic loop rate [Hz] (1 kHz default, OpenHaptics' servo rate).
        robot_rate_hz: robot link rate [Hz] (command + read every rate_hz / robot_rate_hz ticks); None: every tick.
        force_scale: stylus force per newton of estimated tip force [-].
        zero_neg_z: zero the stylus force component along -z of the stylus frame (seed 000 blind test).
        ramp_time: force ramp-in duration after engaging [s].
        engage_force: the computed force must stay below this for `engage_ticks` ticks to engage [N]
            (CHAI3D: 0.2 N for 3 ticks).
        engage_ticks: ticks of small force required before engaging.
        stale_limit: telemetry older than this is a FAULT [s] (RELIABILITY: <= 20 ms).
        startup_timeout: first telemetry must arrive within this [s].
        tension_max: over-range tension [N].
        tension_slack: slack tension [N] (below it the cable is slack).
        tension_window: over-range/slack must persist this long to FAULT [s].
        stuck_window: a cable paying out with rising tension for this long is stuck [s].
        stuck_rise: tension rise over the stuck window that counts as rising [N].
        payout_eps: per-tick commanded length increase that counts as paying out [m].
        auto_enable: request teleoperation at start (the operator's enable pedal in a real session).
        mapping: master -> slave mapping.
    """

    rate_hz: float = 1000.0
    robot_rate_hz: float | None = None
    force_scale: float = 1.0
    zero_neg_z: bool = False
    ramp_time: float = 0.25
    engage_force: float = 0.2
    engage_ticks: int = 3
    stale_limit: float = 0.020
    startup_timeout: float = 0.5
    tension_max: float = 6.0
    tension_slack: float = 0.02
    tension_window: float = 0.010
    stuck_window: float = 0.020
    stuck_rise: float = 1.0
    payout_eps: float = 2e-7
    auto_enable: bool = True
    mapping: MappingParams = field(default_factory=MappingParams)

    def __post_init__(self):
        positive = ("rate_hz", "force_scale", "stale_limit", "startup_timeout", "tension_max", "tension_window",
                    "stuck_window", "stuck_rise", "engage_force")
        for name in positive:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise InputError(f"loop: {name} must be a finite number > 0, got {v!r}")
        if self.robot_rate_hz is not None and not (0 < self.robot_rate_hz <= self.rate_hz):
            raise InputError(f"loop: robot_rate_hz must be in (0, rate_hz], got {self.robot_rate_hz}")
        if self.ramp_time < 0 or self.engage_ticks < 1 or self.tension_slack < 0 or self.payout_eps < 0:
            raise InputError("loop: ramp_time, tension_slack, payout_eps must be >= 0 and engage_ticks >= 1")

    @property
    def dt(self) -> float:
        """Tick period [s]."""
        return 1.0 / self.rate_hz

    @property
    def robot_every(self) -> int:
        """Ticks per robot-link exchange."""
        return 1 if self.robot_rate_hz is None else max(1, int(round(self.rate_hz / self.robot_rate_hz)))

    def as_dict(self) -> dict:
        """JSON-able view (for session metadata)."""
        m = self.mapping
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k != "mapping"}
        d["mapping"] = {"motion_scale": m.motion_scale, "R_reg": m.R_reg.tolist(),
                        "workspace_min": m.workspace_min.tolist(), "workspace_max": m.workspace_max.tolist(),
                        "home": m.home.tolist(), "align_tol": m.align_tol}
        return d
