"""Device protocols shared by every backend: the haptic stylus (master) and the robot (slave).

A device follows one protocol with a context manager: ``__init__`` only stores validated settings,
``open()`` touches hardware, ``close()`` releases it, and ``with`` is idempotent (pyserial style). Limits
are SI in a spec that renderers clip to (CHAI3D cHapticDeviceInfo). Each backend has a
``from_url(parsed_url, options)`` factory; only the wiring picks one by URL (teleop.loop.devices_by_url).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from teleop.core.errors import InputError


def _direct_init(cls):
    """Give the frozen dataclass `cls` an __init__ that writes the instance's __dict__ directly instead of calling
    object.__setattr__ once per field (the generated __init__ of a frozen dataclass): the same signature,
    defaults and default factories, built from the dataclass's own fields. A reading and a stylus sample are
    made every tick, so their construction is on the loop's hot path."""
    names, params, env = [], [], {"_MISSING": dataclasses.MISSING}
    for f in dataclasses.fields(cls):
        names.append(f.name)
        if f.default is not dataclasses.MISSING:
            env[f"_d_{f.name}"] = f.default
            params.append(f"{f.name}=_d_{f.name}")
        elif f.default_factory is not dataclasses.MISSING:
            env[f"_f_{f.name}"] = f.default_factory
            params.append(f"{f.name}=_MISSING")
        else:
            params.append(f.name)
    body = [f"    if {n} is _MISSING: {n} = _f_{n}()" for n in names if f"_f_{n}" in env]
    body.append("    d = self.__dict__")
    body += [f"    d['{n}'] = {n}" for n in names]
    exec(f"def __init__(self, {', '.join(params)}):\n" + "\n".join(body), env)
    init = env["__init__"]
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__doc__ = cls.__init__.__doc__
    cls.__init__ = init
    return cls


class DeviceError(RuntimeError):
    """A device failed at run time (lost link, SDK error, firmware fault)."""


class DeviceUnavailable(InputError):
    """A backend cannot be used here (SDK not installed, port missing): one clear line, exit code 2."""


@dataclass(frozen=True)
class DeviceSpec:
    """Haptic device limits (SI).

    Attributes:
        name: model name.
        workspace_min, workspace_max: (3,) axis-aligned workspace box of the stylus tip [m].
        max_force_continuous: continuous force limit [N] (renderers clamp to this).
        max_force_peak: peak force [N].
        max_stiffness: highest stable rendered stiffness [N/m].
        rate_hz: nominal servo rate [Hz].
    """

    name: str
    workspace_min: tuple = (-0.08, -0.06, -0.035)
    workspace_max: tuple = (0.08, 0.06, 0.035)
    max_force_continuous: float = 0.88
    max_force_peak: float = 3.3
    max_stiffness: float = 1260.0
    rate_hz: float = 1000.0


# Geomagic Touch datasheet (3D Systems): 431 x 348 x 165 mm workspace ... the usable box is smaller;
# continuous force 0.88 N, peak 3.3 N, stiffness x 1.26 N/mm.
TOUCH_SPEC = DeviceSpec(name="Geomagic Touch")
# Force Dimension omega.3 datasheet: workspace 160 x 110 mm, continuous force 12 N, stiffness 14.5 N/mm.
OMEGA_SPEC = DeviceSpec(name="Force Dimension omega.3", workspace_min=(-0.08, -0.08, -0.055),
                        workspace_max=(0.08, 0.08, 0.055), max_force_continuous=12.0, max_force_peak=12.0,
                        max_stiffness=14500.0, rate_hz=4000.0)


@_direct_init
@dataclass(frozen=True)
class HapticSample:
    """One stylus reading (CRTK names where they fit).

    Attributes:
        t: device timestamp [s].
        measured_cp: (3,) stylus tip position [m] in the device frame.
        orientation: (3, 3) stylus orientation (rotation matrix).
        measured_cv: (3,) tip linear velocity [m/s].
        buttons: bit mask of pressed buttons (bit 0: enable/deadman, bit 1: clutch).
        operator_present: True while the operator holds the stylus (deadman).
    """

    t: float
    measured_cp: np.ndarray
    orientation: np.ndarray = field(default_factory=lambda: np.eye(3))
    measured_cv: np.ndarray = field(default_factory=lambda: np.zeros(3))
    buttons: int = 0
    operator_present: bool = True


@runtime_checkable
class HapticDevice(Protocol):
    """The master: a stylus that is read and commanded a force."""

    spec: DeviceSpec

    def open(self) -> None: ...
    def close(self) -> None: ...
    def __enter__(self): ...
    def __exit__(self, *exc) -> None: ...
    def read(self) -> HapticSample: ...
    def servo_cf(self, force) -> None:
        """Command a Cartesian force (3,) [N] in the device frame."""


@dataclass(frozen=True)
class RobotSpec:
    """Robot limits (SI).

    Attributes:
        n_cables: number of cables (6).
        steps_per_m: stepper microsteps per metre of cable.
        l_min, l_max: cable length limits [m].
        v_max: maximum cable speed [m/s].
        adc_max: full-scale of the tension ADC [counts].
    """

    name: str = "CDPR"
    n_cables: int = 6
    steps_per_m: float = 3200 / (np.pi * 0.010)  # 1/16 microstep NEMA17 (200 full steps) on a 10 mm spool
    l_min: float = 0.005
    l_max: float = 0.060
    v_max: float = 0.020
    adc_max: int = 1023


@_direct_init
@dataclass(frozen=True)
class RobotReading:
    """One robot reading: what the hardware returns.

    Attributes:
        t: robot timestamp [s].
        seq: sequence number of the telemetry frame.
        fsr_counts: (6,) raw FSR ADC readings [counts].
        position_steps: (6,) motor positions [microsteps] relative to home.
        commanded_lengths: (6,) last accepted cable-length command [m].
        status: firmware status flags, teleop.core.robot_status.RobotStatus (bit 0 homed, bit 1 watchdog stop, bit 2
            host STOP latch).
        boot_id: firmware boot identifier (changes after a reset).
        wrench_truth: (6,) ground-truth external wrench [N, N m] when the backend has one (the seed's
            Nano17 F/T sensor; the simulator's contact), else None.
        extras: backend-specific values (e.g. true tensions in simulation).
        fbg_pm: (2, 6) Bragg wavelength shifts [pm] of the distal FBG force sensors (seed 001: row 0 FBG1,
            strain-free, temperature only; row 1 FBG2, force and temperature), NaN on a cable without one;
            None when the robot has no FBG (docs/formats.md "Robot readings: sensor kinds").
    """

    t: float
    seq: int
    fsr_counts: np.ndarray
    position_steps: np.ndarray
    commanded_lengths: np.ndarray
    status: int = 0
    boot_id: int = 0
    wrench_truth: np.ndarray | None = None
    extras: dict = field(default_factory=dict)
    fbg_pm: np.ndarray | None = None


@runtime_checkable
class Robot(Protocol):
    """The slave: takes cable-length (motor) commands and returns raw sensor readings."""

    spec: RobotSpec

    def open(self) -> None: ...
    def close(self) -> None: ...
    def __enter__(self): ...
    def __exit__(self, *exc) -> None: ...
    def command_lengths(self, lengths) -> None:
        """Command cable lengths (6,) [m]; the backend converts to motor steps."""
    def read(self) -> RobotReading: ...
    def stop(self) -> None:
        """Stop all motion now (safe state)."""


class ContextDevice:
    """Mixin giving the idempotent context-manager behaviour from `open`/`close` and `is_open`."""

    is_open: bool = False

    def __enter__(self):
        if not self.is_open:
            self.open()
        return self

    def __exit__(self, *exc) -> None:
        if self.is_open:
            self.close()
