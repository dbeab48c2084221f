"""Loop parameters: rates, force rendering, safety thresholds (SI, frozen)."""

from __future__ import annotations

from dataclasses import InitVar, dataclass, field, fields, replace
from functools import cached_property

import numpy as np

from teleop.core.errors import InputError
from teleop.core.mapping import MappingParams
from teleop.core.rendering import RenderParams

# the loop's rendering defaults: CHAI3D engage (0.2 N for 3 ticks), 0.25 s ramp-in, passivity damper off (the
# seed's force path; through the blind-test rig the observer damps many of a poke's ticks and lowers the
# rendered loading stiffness, so it is opt-in: render.alpha_max, `teleop session --passivity-damping`)
LOOP_RENDER = RenderParams(scale=1.0, zero_negative_z=False, engage_N=0.2, engage_ticks=3, ramp_s=0.25,
                           alpha_max=0.0)

# older keyword names (and keys of recorded configurations) -> RenderParams field
_RENDER_ALIASES = {"force_scale": "scale", "zero_neg_z": "zero_negative_z", "ramp_time": "ramp_s",
                   "engage_force": "engage_N", "engage_ticks": "engage_ticks"}


@dataclass(frozen=True)
class LoopParams:
    """Master-slave loop settings.

    Attributes:
        rate_hz: haptic loop rate [Hz] (1 kHz default, OpenHaptics' servo rate).
        robot_rate_hz: robot link rate [Hz] (command + read every rate_hz / robot_rate_hz ticks); None: every tick.
        render: the force rendering (teleop.core.rendering.RenderParams), the one home of force scale, -z zeroing
            (device frame, seed 000 blind test), ramp-in time, passivity damping and the engage test (ALIGNING
            waits until the mapped force stays below engage_N for engage_ticks ticks). Its R_dev_B is always
            mapping.R_reg^T (one registration for motion and force) and the loop clamps to the device's
            continuous limit (spec.max_force_continuous), not to render.max_force.
        stale_limit: telemetry older than this is a FAULT [s] (RELIABILITY: <= 20 ms).
        startup_timeout: the first telemetry of each source must arrive within this [s] of the loop's start
            (or of an operator reset), else FAULT "telemetry missing"; None (default): the staleness limit, so
            a robot that never answers faults one tick after stale_limit, like one that stops answering. The
            device's own boot time is spent in its open() (HELLO handshake, robot process start), before the
            loop starts; the loop is DISABLED with zero force until then.
        tension_max: over-range tension [N].
        tension_slack: slack tension [N] (below it the cable is slack).
        tension_window: over-range/slack must persist this long to FAULT [s].
        stuck_window: a cable paying out with rising tension for this long is stuck [s].
        stuck_rise: tension rise over the stuck window that counts as rising [N].
        payout_eps: per-tick commanded length increase that counts as paying out [m].
        auto_enable: request teleoperation at start (the operator's enable pedal in a real session).
        mapping: master -> slave mapping.

    Constructor aliases (older callers and recorded configurations): force_scale, zero_neg_z, ramp_time,
    engage_force, engage_ticks set render.scale, zero_negative_z, ramp_s, engage_N, engage_ticks; the same
    names read back as properties.
    """

    rate_hz: float = 1000.0
    robot_rate_hz: float | None = None
    render: RenderParams = LOOP_RENDER
    stale_limit: float = 0.020
    startup_timeout: float | None = None
    tension_max: float = 6.0
    tension_slack: float = 0.02
    tension_window: float = 0.010
    stuck_window: float = 0.020
    stuck_rise: float = 1.0
    payout_eps: float = 2e-7
    auto_enable: bool = True
    mapping: MappingParams = field(default_factory=MappingParams)
    force_scale: InitVar[float | None] = None
    zero_neg_z: InitVar[bool | None] = None
    ramp_time: InitVar[float | None] = None
    engage_force: InitVar[float | None] = None
    engage_ticks: InitVar[int | None] = None

    def __post_init__(self, force_scale, zero_neg_z, ramp_time, engage_force, engage_ticks):
        given = dict(zip(_RENDER_ALIASES, (force_scale, zero_neg_z, ramp_time, engage_force, engage_ticks)))
        if isinstance(self.render, dict):  # a recorded configuration
            try:
                object.__setattr__(self, "render", RenderParams(**self.render))
            except TypeError as exc:
                raise InputError(f"loop: render settings not understood ({exc})") from None
        changes = {_RENDER_ALIASES[k]: v for k, v in given.items() if v is not None}
        object.__setattr__(self, "render", replace(self.render, R_dev_B=self.mapping.R_reg.T, **changes))
        positive = ("rate_hz", "stale_limit", "tension_max", "tension_window",
                    "stuck_window", "stuck_rise")
        for name in positive:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise InputError(f"loop: {name} must be a finite number > 0, got {v!r}")
        v = self.startup_timeout
        if v is not None and not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise InputError(f"loop: startup_timeout must be None or a finite number > 0, got {v!r}")
        r = self.render
        if not (r.scale > 0 and r.engage_N > 0 and r.engage_ticks >= 1):
            raise InputError(f"loop: force scale and engage force must be > 0 and engage ticks >= 1, got "
                             f"{r.scale}, {r.engage_N}, {r.engage_ticks}")
        if self.robot_rate_hz is not None and not (0 < self.robot_rate_hz <= self.rate_hz):
            raise InputError(f"loop: robot_rate_hz must be in (0, rate_hz], got {self.robot_rate_hz}")
        if self.tension_slack < 0 or self.payout_eps < 0:
            raise InputError("loop: tension_slack and payout_eps must be >= 0")

    @cached_property  # read every tick (frozen: computed once)
    def dt(self) -> float:
        """Tick period [s]."""
        return 1.0 / self.rate_hz

    @cached_property
    def robot_every(self) -> int:
        """Ticks per robot-link exchange."""
        return 1 if self.robot_rate_hz is None else max(1, int(round(self.rate_hz / self.robot_rate_hz)))

    def as_dict(self) -> dict:
        """JSON-able view (for session metadata); LoopParams(**d) with d["mapping"] rebuilt reads it back."""
        m, r = self.mapping, self.render
        d = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("mapping", "render")}
        d["render"] = {f.name: getattr(r, f.name) for f in fields(r)}
        d["render"]["R_dev_B"] = [list(row) for row in r.R_dev_B]
        d["mapping"] = {"motion_scale": m.motion_scale, "R_reg": m.R_reg.tolist(),
                        "workspace_min": m.workspace_min.tolist(), "workspace_max": m.workspace_max.tolist(),
                        "home": m.home.tolist(), "align_tol": m.align_tol}
        return d


# read-only views under the older names (the InitVar defaults above are replaced, the __init__ keeps them)
for _alias, _name in _RENDER_ALIASES.items():
    setattr(LoopParams, _alias, property(lambda self, _n=_name: getattr(self.render, _n),
                                         doc=f"render.{_name} (alias)"))
del _alias, _name
