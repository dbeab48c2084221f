"""Wrench -> stylus force: frame map, force scale, blind-test -z zeroing, ramp-in, passivity, clamp.

Pure functions on plain floats (the kernels of teleop.core.kernels.render, re-exported here) and a small
stateful `Renderer` holding the kernel's state.
Order in one tick (`Renderer.render_xyz`):
  1. the force part of the wrench in {B}; any NaN/inf -> zero force and a latched fault;
  2. frame map f_dev = scale * R_dev_B f_B;
  3. optional zeroing of negative z IN THE DEVICE FRAME (seed 000 sec 5.2, blind test: "all forces generated
     in the negative direction of the z-axis were set to zero" - the Geomagic Touch's frame, whose z axis
     points toward the user, so a -z force pulls the hand toward the pad; the pad's reaction, along -z of
     {B}, arrives as +z on the device with the loop's registration R_dev_B = diag(1, -1, -1) and is kept);
  4. ramp-in (CHAI3D style): after enable(), output stays zero until the computed force has stayed below
     `engage_N` for `engage_ticks` ticks, then it ramps linearly from 0 to 1 over `ramp_s`;
  5. passivity guard: a time-domain passivity observer (Hannaford & Ryu 2002) on the stylus port,
     E_k = E_{k-1} - f_k . v_k dt (energy absorbed from the hand); when the step would make E negative a
     damper alpha = -E / (|v|^2 dt), alpha <= alpha_max [N s/m], adds -alpha v so E stays >= 0 (its -z
     part in the device frame is zeroed too when zero_negative_z is set);
  6. clamp the norm to the device's continuous limit (direction kept).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from teleop.core.errors import InputError
from teleop.core.kernels import render as KR
from teleop.core.kernels.jit import bind
from teleop.core.kernels.render import clamp_norm, engage_count, frame_map, is_finite3, is_small, render_step

DISABLED, WAITING, RAMPING, ENGAGED = "disabled", "waiting", "ramping", "engaged"
_STATES = (DISABLED, WAITING, RAMPING, ENGAGED)  # by the kernel's state code
_TRIPS = {KR.TRIP_FORCE: "non-finite force", KR.TRIP_VELOCITY: "non-finite stylus velocity or dt"}
_STATE, _RAMP, _FAULT, _OFF = KR.STATE, KR.RAMP, KR.FAULT, KR.DISABLED  # render_tick's reads of the kernel state


def _identity():
    return ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@dataclass(frozen=True)
class RenderParams:
    """Force rendering settings (SI).

    Attributes:
        max_force: continuous force limit of the device [N] (DeviceSpec.max_force_continuous).
        R_dev_B: rotation from robot frame {B} to the device frame (3x3, rows), the same one the motion
            mapping uses the other way.
        scale: force scale device/robot [-].
        zero_negative_z: set the -z force component of the DEVICE frame (after the frame map) to zero
            (seed 000 blind test).
        engage_N, engage_ticks: force must stay below engage_N for engage_ticks ticks before engaging.
        ramp_s: ramp-in duration after engaging [s].
        alpha_max: largest passivity damping [N s/m] (0 switches the passivity guard off).
    """

    max_force: float = 0.88
    R_dev_B: tuple = field(default_factory=_identity)
    scale: float = 1.0
    zero_negative_z: bool = False
    engage_N: float = 0.2
    engage_ticks: int = 3
    ramp_s: float = 0.5
    alpha_max: float = 5.0

    def __post_init__(self):
        R = np.asarray(self.R_dev_B, dtype=float)
        if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
            raise InputError(f"render: R_dev_B must be a 3x3 rotation matrix, got {R.tolist()}")
        object.__setattr__(self, "R_dev_B", tuple(tuple(map(float, row)) for row in R))
        for name in ("max_force", "scale", "engage_N", "ramp_s", "alpha_max"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InputError(f"render: {name} must be a finite number >= 0, got {v}")
        if self.engage_ticks < 0:
            raise InputError(f"render: engage_ticks must be >= 0, got {self.engage_ticks}")

    @classmethod
    def for_device(cls, spec, **kw) -> "RenderParams":
        """Settings clamped to a devices.base.DeviceSpec's continuous force."""
        return cls(max_force=float(spec.max_force_continuous), **kw)


class Renderer:
    """Stateful force renderer: `render(wrench, velocity, dt)` -> (3,) stylus force [N] in the device frame.

    Starts DISABLED (zero force). `enable()` arms the ramp-in; `fault` latches on non-finite input until
    `reset()`. `state` is one of disabled, waiting, ramping, engaged. `mapped` holds the last finite input
    after steps 2-3 (device frame, scaled, -z zeroed if asked) in every state, before ramp, passivity, clamp.
    """

    def __init__(self, params: RenderParams = RenderParams()):
        self.params = params
        self.R = np.array(params.R_dev_B, dtype=float)
        self.rp = np.array([params.max_force, params.scale, float(params.zero_negative_z), params.engage_N,
                            params.engage_ticks, params.ramp_s, params.alpha_max], dtype=float)
        self.rs = np.zeros(5)  # the kernel's state: teleop.core.kernels.render
        self._step_call = None  # render_step bound to its argument types (render_tick)
        self.out = np.zeros(6)
        self.reset()

    def __getstate__(self) -> dict:
        """Pickled without the bound kernel (compiled code does not pickle; bound again at the next call)."""
        return {**self.__dict__, "_step_call": None}

    def reset(self) -> None:
        """Back to DISABLED, fault cleared, passivity energy zero."""
        self.rs[:] = 0.0
        self.out[:] = 0.0
        self.fault_reason = ""

    state = property(lambda self: _STATES[int(self.rs[KR.STATE])], doc="disabled, waiting, ramping or engaged")
    fault = property(lambda self: bool(self.rs[KR.FAULT]), doc="latched on non-finite input until reset()")
    small_ticks = property(lambda self: int(self.rs[KR.SMALL]), doc="ticks the engage rule has counted")
    ramp = property(lambda self: float(self.rs[KR.RAMP]), doc="ramp-in gain in [0, 1]")
    energy = property(lambda self: float(self.rs[KR.ENERGY]), doc="passivity observer's energy [J]")
    mapped = property(lambda self: tuple(self.out[3:6].tolist()),
                      doc="last finite input after the frame map, scale and -z zeroing (device frame) [N]")

    def enable(self) -> None:
        """Arm the ramp-in (no effect while faulted or already engaged)."""
        if not self.fault and self.rs[KR.STATE] == KR.DISABLED:
            self.rs[KR.STATE], self.rs[KR.SMALL], self.rs[KR.RAMP] = KR.WAITING, 0.0, 0.0

    def disable(self) -> None:
        """Zero force from now on; `enable()` restarts the ramp-in."""
        self.rs[KR.STATE] = KR.DISABLED

    def _trip(self, reason: str) -> tuple:
        self.out[:] = 0.0
        self.rs[KR.FAULT], self.rs[KR.STATE] = 1.0, KR.DISABLED
        self.fault_reason = reason
        return 0.0, 0.0, 0.0

    def render_xyz(self, fx: float, fy: float, fz: float, dt: float,
                   vx: float = 0.0, vy: float = 0.0, vz: float = 0.0) -> tuple:
        """The hot-path form: force (fx, fy, fz) [N] in {B}, stylus velocity [m/s] in the device frame
        (kernel render.render_step)."""
        out = self.out
        trip = render_step(self.rs, self.rp, self.R, float(fx), float(fy), float(fz), float(dt), float(vx), float(vy),
                           float(vz), out)
        if trip:
            self.fault_reason = _TRIPS[trip]
        return out[0], out[1], out[2]

    def render_tick(self, fx: float, fy: float, fz: float, dt: float, vx: float, vy: float, vz: float) -> tuple:
        """The loop's render stage in one call: render_xyz (floats as it takes them), then what the loop reads
        after it: (force (3,) [N] device frame (a fresh array), `mapped` (3 floats), `ramp` (0.0 while
        disabled), `fault`)."""
        rs, out, call = self.rs, self.out, self._step_call
        if call is None:  # bound at the first tick (jit.bind): the renderer's arrays and floats
            call = self._step_call = bind(render_step, rs, self.rp, self.R, float(fx), float(fy), float(fz), float(dt),
                                          float(vx), float(vy), float(vz), out)
        trip = call(rs, self.rp, self.R, fx, fy, fz, dt, vx, vy, vz, out)
        if trip:
            self.fault_reason = _TRIPS[trip]
        st, o = rs.tolist(), out.tolist()  # Python floats: one conversion each, not one per element
        ramp = st[_RAMP] if st[_STATE] != _OFF else 0.0
        return out[:3].copy(), (o[3], o[4], o[5]), ramp, st[_FAULT] != 0.0

    def render(self, wrench, dt: float, velocity=None) -> np.ndarray:
        """(3,) force [N] in the device frame from a wrench (6,) or force (3,) in {B}."""
        w = np.asarray(wrench, dtype=float).ravel()
        if w.size < 3:
            return np.asarray(self._trip("wrench has fewer than 3 components"))
        v = (0.0, 0.0, 0.0) if velocity is None else tuple(float(c) for c in np.asarray(velocity).ravel()[:3])
        return np.array(self.render_xyz(float(w[0]), float(w[1]), float(w[2]), float(dt), *v))
