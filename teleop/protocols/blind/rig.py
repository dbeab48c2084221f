"""The blind-test rig: the four-area pad of seed 000 Fig 14g and the chain the participants feel it through.

This is wiring (it picks concrete devices), so pybullet, scenes and devices are imported inside functions.
"""

from __future__ import annotations

from dataclasses import dataclass

from teleop.protocols.blind.study import Area


def blind_areas() -> tuple:
    """The four areas hardest first with their target contact stiffness [N/m] (scenes.materials)."""
    from scenes.materials import contact_stiffness, get_material
    from scenes.pads import BLIND_LABELS, BLIND_MATERIALS

    return tuple(Area(name, BLIND_LABELS[name], contact_stiffness(get_material(name))) for name in BLIND_MATERIALS)


@dataclass(frozen=True)
class RigOptions:
    """How the chain is set up for the study.

    Attributes:
        compensation: render the compensated, Kalman-filtered wrench (False: the raw FSR wrench, ablation).
        force_scale: stylus force per newton of estimated tip force [-].
    """

    compensation: bool = True
    force_scale: float = 1.0
