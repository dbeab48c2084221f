"""LuGre friction (Canudas de Wit et al. 1995) without its damping terms: a Dahl pre-sliding transition whose
sliding level follows the Stribeck curve of the rate.

F_m = load + F, dF/dx = sigma (1 - F sgn(dx) / g(v)), g(v) = Fc + (Fs - Fc) exp(-(v/vs)^2): the bristle
deflection z = F / sigma of the LuGre model (dz/dt = v - sigma |v| z / g(v), F = sigma z) integrated along the
motor position x, exact over each sample's travel at that sample's level (kernel lugre.lugre_friction_step).
After a reversal F leaves the opposite level with slope 2 sigma and settles at g(v): where the drive turns
slowly the transition ends near the breakaway force Fs and the force then falls to Fc as the drive speeds up,
a loop whose shape changes with the rate (a faster stroke ends its transition at a lower level). Fs = Fc is
the Dahl law (dahl_hysteresis); sigma -> inf is the Stribeck friction (stribeck_friction) switched at once.
Units as the catalogue's: x [m], v [m/s], forces [N], sigma [N/m].
"""

from __future__ import annotations

import numpy as np

from teleop.core.kernels.lugre import lugre_friction_run, lugre_friction_step
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, drive_step, register

#: the Stribeck velocity's starts from a fitted Dahl friction: these percentiles of the moving drive's speed
#: (the peak shows only where the drive is slow), and the breakaway force's start as a multiple of its level
SPEED_PERCENTILES = (5.0, 15.0, 35.0)
PEAK_START = 2.0
#: the guess's transition length Fc / sigma as a fraction of the drive's travel
GUESS_TRANSITION = 0.05


def _moving(v: np.ndarray) -> np.ndarray:
    return np.abs(v) > 1e-3 * max(float(np.abs(v).max()), 1e-300)


def _guess(s: Signals, y: np.ndarray) -> dict:
    """Fc the friction's median magnitude in the fastest quarter of the motion, Fs its 95th percentile at
    any speed, vs the moving drive's 25th speed percentile, sigma a transition over GUESS_TRANSITION of the
    travel."""
    m = _moving(s.v)
    if m.sum() < 10:
        return {}
    f, sp = np.abs(y - s.load)[m], np.abs(s.v[m])
    Fc = float(np.median(f[sp >= np.percentile(sp, 75)]))
    Fs = max(float(np.percentile(f, 95)), 1.2 * Fc)
    span = float(np.ptp(s.x))
    return {"Fc": Fc, "Fs": Fs, "vs": max(float(np.percentile(sp, 25)), 1e-7),
            "sigma": Fc / (GUESS_TRANSITION * span) if span > 0 and Fc > 0 else 1e4}


def _from_dahl(p, s: Signals) -> list:
    """Starts from a fitted Dahl friction p (its sigma [N/m] and Fc [N]): the breakaway force PEAK_START
    times its level, the sliding level a little below it (the Dahl level averages the peak in), the Stribeck
    velocity at SPEED_PERCENTILES of the moving drive's speed."""
    m = _moving(s.v)
    if m.sum() < 10:
        return []
    sp = np.abs(s.v[m])
    Fc = max(float(p["Fc"]), 1e-6)
    return [{"Fc": 0.8 * Fc, "Fs": PEAK_START * Fc, "vs": max(float(np.percentile(sp, q)), 1e-7)}
            for q in SPEED_PERCENTILES]


def _wrong(p, rec) -> bool:
    """A LuGre friction has a breakaway peak (Fs > 1.1 Fc; else it is the Dahl law) and a transition longer
    than the drive moves in a sample (Fs / sigma; else it is the Stribeck law switched at once)."""
    return p["Fs"] <= 1.1 * p["Fc"] or (rec.x is not None and p["Fs"] / p["sigma"] < drive_step(rec.x))


def _draw(rng: np.random.Generator, s) -> dict:
    """The rig's friction level, a breakaway peak 1.8-3x it at a Stribeck velocity about the slow speeds',
    and a transition over 1-4 % of the travel (short enough for the peak to show after a turn)."""
    Fc = s.friction
    return {"Fc": Fc, "Fs": Fc * rng.uniform(1.8, 3.0), "vs": s.v_slow * rng.uniform(0.8, 1.5),
            "sigma": Fc / (rng.uniform(0.01, 0.04) * s.travel)}


LUGRE_FRICTION = register(Effect(
    name="lugre_friction", link="force",
    doc="LuGre pre-sliding with a Stribeck level: load + F, dF/dx = sigma (1 - F sgn(dx) / g(v)), "
        "g(v) = Fc + (Fs - Fc) exp(-(v/vs)^2)",
    params=(ParamSpec("sigma", "N/m", 1e-3, 1e9, 1e4, "rest stiffness (initial slope after a reversal, halved)",
                      log=True),
            ParamSpec("Fc", "N", 1e-6, 50.0, 0.2, "Coulomb (kinetic) friction level in fast sliding",
                      log=True, positive=True),
            ParamSpec("Fs", "N", 1e-6, 50.0, 0.3, "static (breakaway) friction level at rest", log=True,
                      positive=True),
            ParamSpec("vs", "m/s", 1e-7, 10.0, 1e-3, "Stribeck velocity", log=True, positive=True)),
    inputs=("x", "v", "load"), output="load",
    guess=_guess, kernel=Kernel(lugre_friction_step, lugre_friction_run, state=(np.nan, 0.0)),
    # its limits are the Dahl law (no peak) and the Stribeck law (an instant transition): on one channel
    # where the load follows the drive a generator does not conceal it beside either
    rules=Rules(channel="motor_force", primary=("Fc", "Fs"), alike=("dahl_hysteresis", "stribeck_friction"),
                starts=3, wrong_form=_wrong, extends="dahl_hysteresis", nested_starts=_from_dahl, draw=_draw)))
