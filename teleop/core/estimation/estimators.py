"""The estimators' names (docs/formats.md) and the `dynamic` estimator's friction parameters.

- non_compensated: f = -A t_fsr.
- single: capstan compensation per cable (seed 000 eq 7), Theta_i = theta_i (eq 6) + theta0, direction from
  the cable length change: shortening = pulling, t_tip = t_fsr exp(-mu Theta); lengthening: exp(+mu Theta).
- double: single + the turn compensation of step 3 (`turn.py`), the seed's strategy.
- dynamic: velocity- and reversal-aware. Per cable, the sheath friction the physics library models is
  removed in order: viscous b v and the Dahl pre-sliding state (both along the cable's own motion), then
  the capstan with stick transitions (physics capstan_friction, stick stiffness k) is inverted through its
  friction state phi in [-1, 1], the sensor tension being t e^(phi mu Theta): phi follows the cable's own
  travel, d phi = k dx / (mu Theta t_sensor), clipped at +-1 where it slips (phi = +1 hauling, -1 paying
  out: the seed's direction rule). So nothing jumps at a reversal and the transition lasts the cable travel
  the physics says.
The per-tick code of each is one kernel of teleop.core.kernels.estimate, run by `tick.TickComputer`.
"""

from __future__ import annotations

from dataclasses import dataclass

from teleop.core.kernels.sheath import Sheath

ESTIMATOR_NAMES = ("non_compensated", "single", "double", "dynamic")


@dataclass(frozen=True)
class DynamicParams:
    """Sheath friction removed by the `dynamic` estimator, per cable (physics-library parameters).

    Attributes:
        b: viscous coefficient [N s/m] (viscous_friction).
        dahl_sigma: Dahl rest stiffness [N/m]; dahl_Fc: Dahl sliding force [N] (dahl_hysteresis; 0 = off).
        v_smooth: time constant of the cable-velocity estimate [s].
        capstan_k: stick stiffness of the capstan transitions [N/m] (teleop.core.kernels.sheath; default the
            seed robot's, `Sheath.stick_k`).
    """

    b: float = 0.0
    dahl_sigma: float = 1e4
    dahl_Fc: float = 0.0
    v_smooth: float = 0.0
    capstan_k: float = Sheath.stick_k
