"""Friction added to the tip load on its way to the motor: Coulomb, viscous, Stribeck and Dahl.

Each effect returns the motor-side force F_m = load + F_f, with F_f:
- coulomb_friction:  Fc sign(v)
- viscous_friction:  b v
- stribeck_friction: (Fc + (Fs - Fc) exp(-(v/vs)^2)) sign(v)   (the full Stribeck curve, Coulomb included)
- dahl_hysteresis:   dF/dx = sigma (1 - F/Fc sgn(dx)), integrated along the motor position x; for each
  sample (x monotone in between) exactly: F_k = s Fc + (F_k-1 - s Fc) exp(-sigma |dx| / Fc), s = sgn(dx),
  from F = 0 at the first sample. Smooth pre-sliding transition of initial slope sigma after reversals.
v is the motor velocity (positive while pulling); sign(0) = 0.
Each formula is one scalar kernel of teleop.core.kernels.friction; each effect's step kernel
(teleop.core.kernels.effects) adds it to the load, the array form is the catalogue's driver loop over that
step and the Step calls it per sample.
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.effects import coulomb_friction_run, coulomb_friction_step, dahl_hysteresis_run, \
    dahl_hysteresis_step, stribeck_friction_run, stribeck_friction_step, viscous_friction_run, viscous_friction_step
from teleop.core.kernels.jit import broadcast_call
from teleop.core.kernels.ufuncs import coulomb_loop, stribeck_loop, viscous_loop
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, drive_step, kernel_call, register

DAHL = Kernel(dahl_hysteresis_step, dahl_hysteresis_run, state=(np.nan, 0.0))


def coulomb(v, Fc):
    """Coulomb friction force [N] for velocity v: Fc sign(v) (kernel friction.coulomb_force)."""
    return broadcast_call(coulomb_loop, v, Fc)


def viscous(v, b):
    """Viscous friction force [N]: b v, b [N s/m] (kernel friction.viscous_force)."""
    return broadcast_call(viscous_loop, v, b)


def stribeck(v, Fc, Fs, vs):
    """Stribeck friction [N]: (Fc + (Fs - Fc) exp(-(v/vs)^2)) sign(v); vs [m/s] Stribeck velocity
    (kernel friction.stribeck_force)."""
    return broadcast_call(stribeck_loop, v, Fc, Fs, vs)


def dahl(x, sigma, Fc, F0: float = 0.0):
    """(n,) Dahl friction force [N] along the position x (n,) [m]; sigma [N/m], Fc [N] (> 0).
    F_k = a F_k-1 + s Fc (1 - a), a = exp(-sigma |dx| / Fc), s = sign(dx) (kernel friction.dahl_step; the
    dahl_hysteresis step kernel on a zero load)."""
    return kernel_call(DAHL, (sigma, Fc), x, 0.0, state=np.array([np.nan, float(F0)]))


def _moving(v: np.ndarray) -> np.ndarray:
    return np.abs(v) > 1e-3 * max(float(np.abs(v).max()), 1e-300)


def _coulomb_guess(s: Signals, y: np.ndarray) -> dict:
    m = _moving(s.v)
    return {"Fc": float(np.median(np.abs(y - s.load)[m])) if m.any() else 0.1}


def _viscous_guess(s: Signals, y: np.ndarray) -> dict:
    b = float(np.dot(s.v, y - s.load) / max(np.dot(s.v, s.v), 1e-300))
    return {"b": b if b > 0 else 1.0}


def _stribeck_guess(s: Signals, y: np.ndarray) -> dict:
    m = _moving(s.v)
    if m.sum() < 10:
        return {}
    # friction along the motion, binned by speed: Fc where fastest, Fs the low-speed peak, vs where the
    # excess over Fc has fallen to 1/e of its peak
    f, sp = ((y - s.load) * np.sign(s.v))[m], np.abs(s.v[m])
    edges = np.unique(np.percentile(sp, np.linspace(0, 100, 21)))
    which = np.clip(np.searchsorted(edges, sp, side="right") - 1, 0, max(edges.size - 2, 0))
    med = np.array([np.median(f[which == b]) if np.any(which == b) else np.nan for b in range(edges.size - 1)])
    centre = 0.5 * (edges[:-1] + edges[1:])
    ok = np.isfinite(med)
    if ok.sum() < 3:
        return {"Fc": float(np.median(np.abs(f))), "Fs": float(np.percentile(np.abs(f), 90)),
                "vs": float(np.percentile(sp, 25))}
    med, centre = med[ok], centre[ok]
    Fc = max(float(np.median(med[-max(2, med.size // 4):])), 0.0)
    peak = int(np.argmax(med))
    Fs = max(float(med[peak]), Fc)
    excess = med - Fc
    after = np.nonzero(excess[peak:] <= excess[peak] / np.e)[0]
    vs = float(centre[peak + after[0]]) if after.size else float(np.percentile(sp, 25))
    return {"Fc": Fc, "Fs": Fs if Fs > 1.2 * Fc else 2.0 * Fc, "vs": vs}


def _dahl_guess(s: Signals, y: np.ndarray) -> dict:
    f = y - s.load
    Fc = float(np.percentile(np.abs(f), 95))
    # initial slope dF/dx just after reversals ~ sigma: take the steep end of |dF/dx|
    dx, dF = np.diff(s.x), np.diff(f)
    m = np.abs(dx) > 1e-12
    sigma = float(np.percentile(np.abs(dF[m] / dx[m]), 90)) if m.sum() > 10 else 1e4
    # ... but no steeper than a transition over DAHL_MIN_TRANSITION of the travel: on a residual whose noise
    # is comparable to the friction, sample-to-sample slopes are the noise's (a near-step start from which
    # the fit ends at the Coulomb limit)
    span = float(np.ptp(s.x))
    if span > 0 and Fc > 0:
        sigma = min(sigma, Fc / (DAHL_MIN_TRANSITION * span))
    return {"Fc": Fc, "sigma": sigma}


DAHL_MIN_TRANSITION = 0.05   # the Dahl guess's shortest transition Fc / sigma, as a fraction of the travel


_FC = ParamSpec("Fc", "N", 0.0, 50.0, 0.2, "Coulomb (kinetic) friction force")

#: percentiles of the moving drive's speed a Stribeck velocity is started at from a fitted Coulomb friction,
#: and the breakaway force's start as a multiple of that friction
STRIBECK_SPEED_PERCENTILES = (5.0, 15.0, 35.0)
STRIBECK_PEAK_START = 2.0


def _stribeck_from_coulomb(p, s: Signals) -> list:
    """Stribeck starts from a fitted Coulomb friction p (its Fc [N]): the breakaway force a multiple of it,
    the Coulomb level below it (the fitted Coulomb force averages the peak in), the Stribeck velocity [m/s] at
    a few low percentiles of the drive's moving speed (the peak shows only where the drive is slow, and a
    data-driven guess from the speed bins can miss it by a decade on a short slow stretch)."""
    m = _moving(s.v)
    if m.sum() < 10:
        return []
    sp = np.abs(s.v[m])
    Fc = max(float(p["Fc"]), 1e-6)
    return [{"Fc": 0.8 * Fc, "Fs": STRIBECK_PEAK_START * Fc, "vs": max(float(np.percentile(sp, q)), 1e-7)}
            for q in STRIBECK_SPEED_PERCENTILES]


def _stribeck_wrong(p, rec) -> bool:
    """Stribeck means more friction at low speed than in sliding (Fs > Fc)."""
    return p["Fs"] <= 1.1 * p["Fc"]


def _dahl_wrong(p, rec) -> bool:
    """A Dahl transition (length Fc / sigma) shorter than the drive moves in one sample is a jump at the
    reversal: Coulomb friction, the Dahl law's limit (a near-step Dahl wins a few per cent there by
    splitting the reversal's sample, which is the rate's discretisation, not a pre-sliding regime)."""
    return rec.x is not None and p["Fc"] / p["sigma"] < drive_step(rec.x)


COULOMB_FRICTION = register(Effect(
    name="coulomb_friction", link="force", doc="constant, direction-dependent: load + Fc sign(v)",
    params=(_FC,), inputs=("v", "load"), output="load",
    guess=_coulomb_guess, kernel=Kernel(coulomb_friction_step, coulomb_friction_run, state=()),
    # constant-magnitude frictions on one channel are one effect to any data
    rules=Rules(channel="motor_force", primary=("Fc",), alike=("stribeck_friction", "dahl_hysteresis"),
                draw=lambda rng, s: {"Fc": s.friction}, rate_probe=True)))

VISCOUS_FRICTION = register(Effect(
    name="viscous_friction", link="force", doc="velocity-proportional: load + b v",
    params=(ParamSpec("b", "N s/m", 1e-6, 1e5, 10.0, "viscous friction coefficient", log=True),),
    inputs=("v", "load"), output="load",
    guess=_viscous_guess, kernel=Kernel(viscous_friction_step, viscous_friction_run, state=()),
    rules=Rules(channel="motor_force", primary=("b",),
                draw=lambda rng, s: {"b": s.friction / s.v_fast * rng.uniform(1.0, 2.0)})))

STRIBECK_FRICTION = register(Effect(
    name="stribeck_friction", link="force",
    doc="extra friction at low speed: load + (Fc + (Fs - Fc) exp(-(v/vs)^2)) sign(v)",
    params=(_FC,
            ParamSpec("Fs", "N", 0.0, 50.0, 0.3, "static (breakaway) friction force"),
            ParamSpec("vs", "m/s", 1e-7, 10.0, 1e-3, "Stribeck velocity", log=True, positive=True)),
    inputs=("v", "load"), output="load",
    guess=_stribeck_guess, kernel=Kernel(stribeck_friction_step, stribeck_friction_run, state=()),
    # the peak and its velocity scale have basins of their own (a sine's low-speed stretches are short:
    # from its data-driven guess a fit can settle on half the peak at twice the speed)
    rules=Rules(channel="motor_force", primary=("Fc", "Fs"), alike=("dahl_hysteresis",), starts=6,
                wrong_form=_stribeck_wrong, extends="coulomb_friction", nested_starts=_stribeck_from_coulomb,
                draw=lambda rng, s: {"Fc": s.friction, "Fs": s.friction * rng.uniform(1.8, 3.0),
                                     "vs": s.v_slow * rng.uniform(0.6, 1.2)})))

DAHL_HYSTERESIS = register(Effect(
    name="dahl_hysteresis", link="force",
    doc="Dahl pre-sliding: load + F, dF/dx = sigma (1 - F/Fc sgn(dx)) along the motor position",
    params=(ParamSpec("sigma", "N/m", 1.0, 1e9, 1e4, "rest stiffness (initial slope after a reversal)",
                      log=True),
            ParamSpec("Fc", "N", 1e-6, 50.0, 0.2, "Coulomb friction force reached in sliding",
                      log=True, positive=True)),
    inputs=("x", "load"), output="load",
    guess=_dahl_guess, kernel=DAHL,
    rules=Rules(channel="motor_force", primary=("Fc",), wrong_form=_dahl_wrong,
                draw=lambda rng, s: {"Fc": s.friction, "sigma": s.friction / (rng.uniform(0.05, 0.2) * s.travel)})))
