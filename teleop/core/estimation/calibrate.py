"""Calibrating the estimators on a no-load back-and-forth run (the seed's step-3 protocol, seed 000 Fig 13).

With no load the true wrench is zero, so whatever an estimator reports is its error. `double` fits its turn
polynomials on that run (turn.fit_turn_compensation); `dynamic` fits its sheath-friction parameters
(viscous b, Dahl sigma and Fc, the capstan stick stiffness k) by least squares of the forces it reports on the same run. b and Fc are
only separable when the run holds more than one speed (b v versus a constant); a run at one speed fixes
their sum only, and the fit then keeps b at its initial value.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares

from teleop.core.errors import InputError
from teleop.core.estimation.estimators import DynamicParams
from teleop.core.estimation.tick import TickComputer
from teleop.core.geometry import Geometry


def no_load_forces(geom: Geometry, poses, tensions, dt: float, params: DynamicParams) -> np.ndarray:
    """(n, 3) forces [N] the unfiltered `dynamic` estimator reports on a run (poses (n, 6), tensions (n, 6))."""
    tc = TickComputer(geom, "dynamic", dynamic=params, kalman=None)
    out = np.empty((len(poses), 3))
    for k, (q, t) in enumerate(zip(np.asarray(poses).tolist(), np.asarray(tensions).tolist())):
        out[k] = tc.estimate(q, t, dt)[1][:3]
    return out


def fit_dynamic_params(geom: Geometry, poses, tensions, dt: float, init: DynamicParams = DynamicParams(
        b=1.0, dahl_sigma=1e4, dahl_Fc=0.02), fit_b: bool = True) -> DynamicParams:
    """Fit b [N s/m], dahl_sigma [N/m], dahl_Fc [N] and capstan_k [N/m] so the no-load run reads zero force.

    poses (n, 6), tensions (n, 6) [N] sensor tensions, dt [s]. Parameters are fitted in log scale; a run
    with a single speed should use fit_b=False (see module docstring).
    """
    poses = np.asarray(poses, dtype=float)
    tensions = np.asarray(tensions, dtype=float)
    if poses.shape != tensions.shape or poses.ndim != 2 or poses.shape[1] != 6 or len(poses) < 50:
        raise InputError("fit_dynamic_params: poses and tensions must both be (n, 6) with n >= 50")
    if min(init.b, init.dahl_sigma, init.dahl_Fc, init.capstan_k) <= 0:
        raise InputError("fit_dynamic_params: initial b, dahl_sigma, dahl_Fc and capstan_k must be > 0")

    def unpack(z):
        b = float(np.exp(z[0])) if fit_b else init.b
        return replace(init, b=b, dahl_sigma=float(np.exp(z[-3])), dahl_Fc=float(np.exp(z[-2])),
                       capstan_k=float(np.exp(z[-1])))

    def resid(z):
        return no_load_forces(geom, poses, tensions, dt, unpack(z)).ravel()

    # physical ranges (log-scale bounds): b [N s/m], Dahl sigma [N/m] and Fc [N] (a Dahl force the run does
    # not need goes to the Fc floor, i.e. off), stick stiffness k [N/m]
    lo = ([1e-3] if fit_b else []) + [10.0, 1e-4, 1e2]
    hi = ([1e3] if fit_b else []) + [1e7, 2.0, 1e6]
    z0 = np.log(([init.b] if fit_b else []) + [init.dahl_sigma, init.dahl_Fc, init.capstan_k])
    sol = least_squares(resid, np.clip(z0, np.log(lo), np.log(hi)), bounds=(np.log(lo), np.log(hi)),
                        diff_step=1e-3, x_scale=1.0, max_nfev=60)
    return unpack(sol.x)
