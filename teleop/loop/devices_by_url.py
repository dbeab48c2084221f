"""Devices by URL: the one place that picks a concrete device (the wiring: loop construction, CLI).

``sim://`` (scripted stylus, devices.simulated), ``sim://robot`` (scenes.sim_robot), ``touch://``, ``omega://``,
``serial:///dev/ttyACM0?baud=1000000`` (devices.arduino), ``replay://session.mcap``. A backend is an entry in
``BACKENDS``: scheme (and optional host) -> "module:factory", imported when a URL names it (vendor SDKs and
pybullet load only for the devices used).
"""

from __future__ import annotations

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


def open_device(url: str, **overrides):
    """Build (not open) the device a URL names; use it as a context manager to open it.

    Raises InputError for an unknown scheme or malformed URL, DeviceUnavailable when the backend cannot
    be used on this machine.
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
    return factory(parsed, options)


def process_robot(url: str, rate_hz: float = 1000.0, start_timeout: float = 30.0, rt_priority: int | None = None,
                  **options) -> ProcessRobot:
    """The robot `url` names, run in its own process at `rate_hz` (devices.wrappers.ProcessRobot); the compiled
    kernels are warmed (teleop.loop.warm) in the parent before the fork, so the child inherits them ready."""
    return ProcessRobot(functools.partial(open_device, url, **options), name=url, rate_hz=rate_hz,
                        start_timeout=start_timeout, rt_priority=rt_priority, before_fork=warm_up)
