"""Calibrated pad contact: from a target stiffness [N/m] to pybullet's contactStiffness, by measurement.

pybullet's soft contact is an ERP/CFM constraint built from contactStiffness K and contactDamping D; what
force-indentation slope it produces depends on the solver, the time step, the indenter mass and how the
indenter is driven, and it carries a small offset (Bullet's contact slop). So nothing is assumed: a
virtual indentation (the tip pushed quasi-statically to several depths by a stiff constraint) measures the
slope dF/dd against the tip's *actual* indentation, and K is corrected by target/measured until they agree
to 0.2 %. The correction gain is measured on a log-spaced grid of targets spanning every pad (Ecoflex 00-10
to the rigid cap) and interpolated in log space. `indent` is the same measurement on any pad of a world,
used by the tests to check every pad against its material's target. The measurement runs on the world class
it is handed (scenes.world.PadWorld, which asks for its default calibration here when it opens).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from scenes.materials import RIGID_CONTACT_STIFFNESS
from scenes.pads import Pad

DEPTHS = (0.0005, 0.0010, 0.0015, 0.0020)  # [m] indentation steps of the virtual indenter
SETTLE_STEPS = 150                         # steps held at each depth before reading the force


@dataclass(frozen=True)
class ContactCalibration:
    """Measured map target stiffness -> pybullet contactStiffness.

    Attributes:
        k_targets: (n,) target slopes [N/m], increasing.
        gains: (n,) contactStiffness / target that reproduced each target slope [-].
        measured: (n,) slope measured with the final gain [N/m].
    """

    k_targets: tuple
    gains: tuple
    measured: tuple

    def pybullet_stiffness(self, k_target: float) -> float:
        """contactStiffness [N/m] giving the slope k_target [N/m] (log-interpolated gain)."""
        g = np.interp(np.log(k_target), np.log(self.k_targets), self.gains)
        return float(k_target * g)


def _uniform_probe_pad() -> Pad:
    return Pad("probe", "square", 0.02, "ecoflex_00_20")


class _FixedStiffness:
    """Calibration stand-in giving one fixed contactStiffness K whatever the target (used while measuring)."""

    def __init__(self, K: float):
        self.K = K

    def pybullet_stiffness(self, k_target: float) -> float:
        return self.K


def indent(world, xy=(0.0, 0.0), depths=DEPTHS, axis=2, settle=SETTLE_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """Push the tip of an open kinematic `world` to each depth at xy; return (indentation (n,) [m],
    force along the push (n,) [N]).

    axis 2: along +z into the top surface at xy (2,) [m]; axis 0/1: along +x/+y from xy (a point in the hole,
    depth measured from the first contact found by a sweep).
    """
    p = world.params
    xy = np.asarray(xy, dtype=float)
    d_act, F = [], []
    if axis == 2:
        for d in depths:
            target = np.array([xy[0], xy[1], p.surface_z + d])
            for _ in range(settle):
                world.step(target)
            d_act.append(world.indentation())
            F.append(-world.contact_force()[2])
        return np.array(d_act), np.array(F)
    # lateral: start half-way down the hole, find the wall, then push into it
    z = p.surface_z + world.pad.thickness / 2 + world.proxy_radius  # sphere centre at mid-thickness
    u = np.zeros(3)
    u[axis] = 1.0
    start = np.array([xy[0], xy[1], z])
    # wall at the hole radius: free travel = hole radius - |start| - tip radius along the axis
    contact = world.pad.hole_radius - world.proxy_radius - float(start[axis])
    for d in depths:
        target = start + u * (contact + d)
        for _ in range(settle):
            world.step(target)
        d_act.append(float(world.centre()[axis] - start[axis] - contact))
        F.append(-world.contact_force()[axis])
    return np.array(d_act), np.array(F)


def slope(d: np.ndarray, F: np.ndarray) -> float:
    """Least-squares slope dF/dd [N/m]."""
    return float(np.polyfit(d, F, 1)[0])


def measure(K: float, params, world_cls) -> float:
    """Slope [N/m] measured on a uniform probe pad whose contactStiffness is K, in a `world_cls` world
    (scenes.world.PadWorld) with WorldParams `params`."""
    with world_cls(_uniform_probe_pad(), params, calibration=_FixedStiffness(K)) as w:
        return slope(*indent(w))


def calibrate(params, world_cls, k_targets=None, tol: float = 2e-3, max_iter: int = 6) -> ContactCalibration:
    """Measure the gain contactStiffness/target for each target slope (fixed-point on the ratio) in
    `world_cls` worlds (`measure`)."""
    if k_targets is None:
        k_targets = np.geomspace(100.0, RIGID_CONTACT_STIFFNESS, 7)
    gains, meas = [], []
    for k in k_targets:
        g = 1.0
        s = measure(k * g, params, world_cls)
        for _ in range(max_iter):
            if abs(s / k - 1.0) <= tol:
                break
            g *= k / s
            s = measure(k * g, params, world_cls)
        gains.append(g)
        meas.append(s)
    return ContactCalibration(tuple(float(k) for k in k_targets), tuple(gains), tuple(meas))


@functools.lru_cache(maxsize=8)
def default_calibration(params, world_cls) -> ContactCalibration:
    """The calibration for these WorldParams, measured in `world_cls` worlds (once per process)."""
    return calibrate(params, world_cls)
