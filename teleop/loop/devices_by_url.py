"""Devices by URL: the one place that picks a concrete device (the wiring: loop construction, CLI).

``sim://`` (scripted stylus, devices.simulated), ``sim://robot`` (scenes.sim_robot), ``touch://``, ``omega://``,
``serial:///dev/ttyACM0?baud=1000000`` (devices.arduino), ``replay://session.mcap``. A backend is an entry in
``BACKENDS``: scheme (and optional host) -> "module:factory", imported when a URL names it (vendor SDKs and
pybullet load only for the devices used).

A robot is built for a geometry (teleop.core.geometry.Geometry, `--geometry`) with ``open_device(url,
geometry=g)``: the simulated robot's `SimRobotParams.geometry`, the serial robot's length and speed limits
(checked against its firmware's); a stylus or a replayed robot has none to take.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
from typing import Callable
from urllib.parse import parse_qs, urlparse

from devices.base import DeviceUnavailable
from devices.wrappers import ProcessRobot
from teleop.core.errors import InputError
from teleop.loop.warm import warm_up

# scheme[/host] -> "module:factory"; factory(parsed_url, options: dict[str, str]) -> device
BACKENDS: dict[str, str] = {
    "sim": "devices.simulated:from_url",
    "sim/robot": "scenes.sim_robot:from_url",
    "touch": "devices.touch:from_url",
    "omega": "devices.omega:from_url",
    "serial": "devices.arduino.robot:from_url",
    "replay": "devices.replay:from_url",
}


# backends that build a robot for a given geometry (open_device's `geometry`)
GEOMETRY_BACKENDS = ("sim/robot", "serial")


def open_device(url: str, geometry=None, **overrides):
    """Build (not open) the device a URL names; use it as a context manager to open it.

    `geometry` (teleop.core.geometry.Geometry; None: the backend's default, the seed robot) is the robot's:
    accepted by the backends of GEOMETRY_BACKENDS only. Raises InputError for an unknown scheme, a malformed
    URL or a geometry the device cannot take, DeviceUnavailable when the backend cannot be used on this machine.
    """
    parsed = urlparse(url)
    if not parsed.scheme:
        raise InputError(f"device URL '{url}': expected scheme://..., e.g. sim://, sim://robot, touch://")
    key = f"{parsed.scheme}/{parsed.netloc}" if f"{parsed.scheme}/{parsed.netloc}" in BACKENDS else parsed.scheme
    if key not in BACKENDS:
        raise InputError(f"device URL '{url}': unknown scheme '{parsed.scheme}' "
                         f"(expected one of: {', '.join(sorted(BACKENDS))})")
    module_name, factory_name = BACKENDS[key].split(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        raise DeviceUnavailable(f"device URL '{url}': backend module {module_name} missing ({exc})") from None
    factory: Callable = getattr(module, factory_name)
    options = {k: v[-1] for k, v in parse_qs(parsed.query).items()}
    options.update(overrides)
    if geometry is not None and key not in GEOMETRY_BACKENDS:
        raise InputError(f"device URL '{url}': a geometry applies to a robot built here "
                         f"({', '.join(GEOMETRY_BACKENDS)}), not to {key}")
    if geometry is not None and key == "serial":
        options["geometry"] = geometry  # devices.arduino.robot.from_url: the limits, checked against the firmware's
    device = factory(parsed, options)
    if geometry is not None and key == "sim/robot":
        device = _sim_robot_on(device, geometry)
    return device


def _sim_robot_on(robot, geometry):
    """The simulated robot `robot` (scenes.sim_robot.SimRobot, built, not opened) rebuilt with `geometry` in its
    params (SimRobotParams.geometry, whose checks run again: a pretension or play the geometry cannot hold is
    an InputError); its pad, seed, FSR calibration and link model kept."""
    params = dataclasses.replace(robot.params, geometry=geometry)
    return type(robot)(robot.pad, params, seed=robot.seed, calibration=robot.cal, model=robot.model)


def process_robot(url: str, rate_hz: float = 1000.0, start_timeout: float = 30.0, rt_priority: int | None = None,
                  **options) -> ProcessRobot:
    """The robot `url` names, run in its own process at `rate_hz` (devices.wrappers.ProcessRobot); the compiled
    kernels are warmed (teleop.loop.warm) in the parent before the fork, so the child inherits them ready."""
    return ProcessRobot(functools.partial(open_device, url, **options), name=url, rate_hz=rate_hz,
                        start_timeout=start_timeout, rt_priority=rt_priority, before_fork=warm_up)
