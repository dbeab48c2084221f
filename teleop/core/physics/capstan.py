"""Capstan (tendon-sheath) friction: T_load = T_hold exp(mu Theta) (seed 000 eqs 3, 7; seed 001 eqs 4-7).

Conventions: the motor (proximal) force F_m and the tip (distal) force F_t; x increasing means the motor
hauls the cable in (pulling phase, seed 001 xi > 0), decreasing means it pays out (releasing phase).
While pulling F_m = F_t exp(+mu Theta); while releasing F_m = F_t exp(-mu Theta). During a reversal
the cable sticks in the sheath: the tip force stays constant while the motor force travels between the
two lines (seed 001 Fig 2b, "flat transitions"). This is modelled as a play operator in force: the motor
force follows the cable stretch, F_m <- F_m + k dx, clamped to the band
[F_t exp(-mu Theta), F_t exp(+mu Theta)]; k [N/m] is the stick stiffness seen at the motor. k -> inf
gives the plain sign(dx) switch. The inverse (compensation) needs no k: the tip force is the play of the
motor force, F_t <- clamp(F_t, F_m exp(-mu Theta), F_m exp(+mu Theta)). The law, its state and its start
on the tip force are the sheath's kernels (teleop.core.kernels.sheath), shared with the simulated robot and
the estimators (`tip2motor_transitions` runs the sheath's forward law itself). The catalogue effect, fitted to
recordings, runs it on the recorded drive (kernel sheath.capstan_rate_step): the direction is the sign of the
drive's rate in the convention the diagnosis picked (central or backward), and k at its upper bound
(K_INSTANT) is the instant switch, so that a fit can reach the limit a sampled stiff stick only approaches.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from teleop.core.kernels.sheath import (INSTANT, N_RATE_CONST, PRELOAD, STICK_K, STICK_N, STICK_SPREAD, STIFF_STICK_K,
                                        Sheath,
                                        capstan_band_loop, capstan_rate_run, capstan_rate_step, capstan_tip_run,
                                        motor_force_run, new_state)
from teleop.core.kernels.jit import broadcast_call
from teleop.core.kernels.ufuncs import hold_loop, tip_loop
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, register


def capstan_out(T_in, mu, theta):
    """Output tension of a capstan driven by T_in: T_out = T_in exp(-mu theta). Broadcasts (e.g. (6,) cables)."""
    return motor2tip(T_in, mu, theta, True)


def capstan_in(T_out, mu, theta):
    """Inverse of `capstan_out`: the driving tension that holds T_out, T_in = T_out exp(mu theta)."""
    return motor2tip(T_out, mu, theta, False)


def _pulling(pulling):
    """1.0 for pulling, 0.0 for releasing; accepts bools or signed numbers (0 counts as pulling, seed 001 eq 5)."""
    p = np.asarray(pulling)
    return p.astype(float) if p.dtype == bool else (p >= 0).astype(float)


def _mu_theta(mu, theta):
    return np.asarray(mu, dtype=float) * np.asarray(theta, dtype=float)


def tip2motor(F_tip, mu, theta, pulling):
    """Motor force [N] from tip force [N]: F_m = F_t exp(+/- mu theta), + while pulling (sign(dx) switch)."""
    # F_t exp(+mu theta) pulling = capstan_hold of a releasing cable (exp(+mu Theta)), and the other way round
    return broadcast_call(hold_loop, F_tip, 1.0 - _pulling(pulling), _mu_theta(mu, theta))


def motor2tip(F_motor, mu, theta, pulling):
    """Compensation, inverse of `tip2motor`: F_t = F_m exp(-/+ mu theta), - while pulling.

    Seed 000 eq 7 (T_hold = T_load e^-mu theta) with the load/hold sides picked by the motion (kernel
    friction.capstan_hold).
    """
    return broadcast_call(hold_loop, F_motor, _pulling(pulling), _mu_theta(mu, theta))


def capstan_band(F_tip, mu, theta):
    """(lo, hi) motor forces reachable for tip force F_tip: the releasing and pulling lines F e^-mu theta and
    F e^+mu theta, lo <= hi (kernel sheath.capstan_band, the band the sheath's motor force is clamped into),
    array-broadcast."""
    f, mt = np.broadcast_arrays(np.asarray(F_tip, dtype=float), _mu_theta(mu, theta))
    flat_f, flat_mt = np.ascontiguousarray(f).reshape(-1), np.ascontiguousarray(mt).reshape(-1)
    lo, hi = np.empty(flat_f.shape[0]), np.empty(flat_f.shape[0])
    capstan_band_loop(flat_f, flat_mt, lo, hi)
    return lo.reshape(f.shape), hi.reshape(f.shape)


def tip2motor_transitions(x, F_tip, mu, theta, k, F0=None):
    """(n,) motor force [N] with stick transitions at reversals.

    x (n,) motor position [m], F_tip (n,) tip force [N], theta scalar or (n,) [rad], k stick stiffness
    [N/m], mu scalar; F0 initial motor force (default: the sheath's start on the tip force).
    F_m,k = clamp(F_m,k-1 + k (x_k - x_k-1), F_t,k e^-mu theta, F_t,k e^+mu theta) (kernel
    sheath.motor_force).
    """
    x, F_tip, theta = (np.ascontiguousarray(a, dtype=float).reshape(-1)
                       for a in np.broadcast_arrays(np.asarray(x, dtype=float), F_tip, theta))
    st = new_state(1)
    if F0 is not None:  # a given motor force at the first position
        st[:2, 0] = float(x[0]), float(F0)
    return motor_force_run(x, F_tip, theta, Sheath(mu=float(mu), stick_k=float(k)).constants(), st, 0,
                           np.empty(x.shape[0]))


def _pack(p: Mapping[str, float]) -> np.ndarray:
    """The step kernel's parameters (kernels.sheath.capstan_rate_step): the sheath's kernel constants for
    friction mu [-] and stick stiffness k [N/m] (the wrap comes with the signals), then the preload [N] and
    the stick stiffness of an instant switch (k's fit bound), the transitions' exponent n and their spread."""
    c = np.empty(N_RATE_CONST)
    c[:PRELOAD] = Sheath(mu=float(p["mu"]), stick_k=float(p["k"])).constants()
    c[STICK_K] = stick_stiffness(float(p["k"]))
    n = float(p.get("n", 1.0))
    c[PRELOAD], c[INSTANT], c[STICK_N] = p.get("preload", 0.0), math.inf, 1.0 if abs(n - 1.0) < N_LINEAR else n
    c[STICK_SPREAD] = p.get("spread", 0.0)
    return c


#: the transitions' exponent n within this of 1 is the linear stick itself (a fit of a linear stick's
#: recording ends next to 1, not on it, and the plain law is then reproduced to the recording's precision)
N_LINEAR = 1e-3

#: the stick stiffness [N/m] of an instant switch, the fit's upper bound on k: on sampled data a stiff but
#: finite stick still crosses the band a sample late at a slow turn, where the motor moves least. Over k's
#: top decade the kernel's stiffness grows without bound (`stick_stiffness`), so that a fit ending near the
#: bound (a sin-mapped bound is reached only to rounding) is the switch.
K_INSTANT = 1e12


#: the part of k's top decade that is the instant switch itself: a fit's bounded parameter reaches its bound
#: only to rounding (a fit started on the bound starts 0.05 % of its range below it, 0.6 % of the top decade),
#: and a finite stick, however stiff, crosses the band late where the drive leaves a turn slowly (a
#: jerk-limited turn, the rate rising as the square of the time: a sample 0.3 of an interval after it has moved
#: 1e-13 m the new way)
INSTANT_TOP = 0.99


def stick_stiffness(k: float) -> float:
    """The kernel's stick stiffness [N/m] for the parameter k [N/m]: k itself below K_INSTANT / 10, then
    k / (1 - top), top = log10(10 k / K_INSTANT), infinite from top = INSTANT_TOP on (continuous below it and
    increasing, so that a fit approaching the bound is not left a decade of a slower switch short of
    it)."""
    top = math.log10(10.0 * k / K_INSTANT)
    if top <= 0.0:
        return k
    return k / (1.0 - top) if top < INSTANT_TOP else math.inf
KERNEL = Kernel(capstan_rate_step, capstan_rate_run, state=(math.nan, math.nan, 0.0, 0.0), pack=_pack)


def motor2tip_transitions(F_motor, mu, theta, F0=None):
    """(n,) tip force [N] estimated from motor force (n,) [N] with flat transitions (direction-free).

    F_t,k = clamp(F_t,k-1, F_m,k e^-mu theta, F_m,k e^+mu theta); F0 default F_motor[0] (kernel
    friction.capstan_tip_step). Inverts `tip2motor_transitions` whenever the tip force is constant during
    reversals.
    """
    F_motor = np.ascontiguousarray(F_motor, dtype=float)
    mt = np.ascontiguousarray(np.broadcast_to(_mu_theta(mu, theta), F_motor.shape))
    y0 = float(F_motor.ravel()[0]) if F0 is None else float(F0)
    return capstan_tip_run(F_motor, mt, y0, np.empty(F_motor.shape[0]))


def _theta(signals: Signals, params: Mapping[str, float]):
    return signals.theta if signals.theta is not None else params["theta"]


def _guess(signals: Signals, y: np.ndarray) -> dict:
    th = _theta(signals, {"theta": PARAMS[1].default})
    ok = (np.abs(signals.load) > 1e-3 * max(np.abs(signals.load).max(), 1e-12)) & (np.abs(y) > 0)
    ratio = np.abs(np.log(np.abs(y[ok]) / np.abs(signals.load[ok]))) if ok.any() else np.array([0.1])
    mu = float(np.percentile(ratio, 90) / np.mean(th)) if np.mean(th) > 0 else 0.1
    # stick stiffness: band width over the motor travel needed to cross it, from the largest dF/dx
    dx = np.diff(signals.x)
    dF = np.diff(y)
    moving = np.abs(dx) > 1e-12
    k = float(np.percentile(np.abs(dF[moving] / dx[moving]), 95)) if moving.sum() > 10 else PARAMS[2].default
    return {"mu": mu, "theta": float(np.mean(th)), "k": k}


PARAMS = (
    ParamSpec("mu", "1", 0.0, 1.5, Sheath.mu, "sheath friction coefficient"),
    ParamSpec("theta", "rad", 0.0, 8 * np.pi, Sheath.theta0,
              "total wrap angle Theta (ignored when the signals carry a 'theta' channel; "
              "mu and theta are identifiable only as a product: fix one when fitting)"),
    ParamSpec("k", "N/m", 1.0, K_INSTANT, STIFF_STICK_K, "stick stiffness during reversals (motor force per motor "
              "travel; the upper bound is an instant switch on the rate's sign)",
              log=True),
    ParamSpec("preload", "N", 0.0, 50.0, 0.0, "pretension the cable carries beside the load (an antagonistic "
              "pair's, or a load sensor zeroed under tension): the sheath grips load + preload, the motor "
              "force is read from the preload (general form; 0: the plain law)", shape=True),
    ParamSpec("n", "1", 0.2, 2.0, 1.0, "exponent of the stick transitions: the part of the band crossed grows "
              "as (travel / travel across it)^n (1: a linear stick; 1/2: a friction distributed along the "
              "sheath; kernel sheath.stick_transition)"),
    ParamSpec("spread", "1", 0.0, 2.0, 0.0, "the transitions' curve beyond the power of the travel: the part of "
              "the band's own ratio in it (0: u = (travel / travel across it)^n; 1 with n = 1/2: Kaneko's friction "
              "spread uniformly along the sheath, steeper leaving the high line than the low one; above 1 more "
              "curved; kernel sheath.stick_transition). The baseline's own choice, kept off 0 only where it pays "
              "on its own (a shape parameter that never makes a finding)",
              shape=True, alone=True),
)


class CapstanCompensator:
    """Per-sample tip-force estimate from the motor (proximal) force with flat transitions.

    Same math as `motor2tip_transitions`; works per cable on arrays: mu, theta scalars or (c,), and
    step(F_motor (c,) [N], theta=None (c,) [rad]) -> F_tip (c,) [N] (floats in, float out).
    """

    def __init__(self, mu, theta, F0=None):
        self.mu, self.theta = np.asarray(mu, dtype=float), np.asarray(theta, dtype=float)
        self.F = None if F0 is None else np.asarray(F0, dtype=float)

    def reset(self, F0=None) -> None:
        """Forget the held tip force (the next step starts from its motor force, or from F0)."""
        self.F = None if F0 is None else np.asarray(F0, dtype=float)

    def step(self, F_motor, theta=None):
        F_motor = np.asarray(F_motor, dtype=float)
        mt = self.mu * (self.theta if theta is None else np.asarray(theta, dtype=float))
        prev = F_motor if self.F is None else self.F
        # F_t = clamp(F_t_prev, lower line, upper line): kernel friction.capstan_tip_step per cable
        F = broadcast_call(tip_loop, prev, F_motor, mt)
        self.F = np.asarray(F, dtype=float)
        return float(F) if self.F.ndim == 0 else self.F.copy()


def _hold(rec, known, direction) -> dict:
    """theta with mu: only the product shows; a known mu (the user's simulation has it) and no recorded
    bend leave the wrap to be fitted."""
    return {} if rec.theta is None and "mu" in known else {"theta": PARAMS[1].default}


def _baseline_starts(rec, index, gain, offset, direction) -> list:
    """[(direction, gain, offset, params)]: the capstan's mu Theta and stick stiffness span decades, so a
    baseline with it also starts from the record's own two lines. Within one direction of motion the
    capstan is proportional, F_m = g e^(+-mu Theta) F_t + c, so the pulling and releasing samples alone give
    the gain and mu Theta (the whole record's least squares can even turn the gain's sign when the
    hysteresis loop is fat); the pulling side carries the higher motor force and sets the direction."""
    th = float(np.mean(rec.theta)) if rec.theta is not None else PARAMS[1].default
    span = max(float(np.ptp(rec.x)), 1e-12) if rec.x is not None else 1.0
    sgn = np.sign(np.gradient(rec.x))[index] * direction if rec.x is not None else np.zeros(index.size)
    lines = []
    for side in (1.0, -1.0):
        sel = index[sgn == side]
        if sel.size > 20:
            A = np.column_stack([rec.u[sel], np.ones(sel.size)])
            (g_side, c_side), *_ = np.linalg.lstsq(A, rec.y[sel], rcond=None)
            lines.append((g_side, c_side))
    starts = [(abs(gain), offset)]
    if len(lines) == 2:
        ubar = float(np.mean(rec.u[index]))
        if lines[0][0] * ubar + lines[0][1] < lines[1][0] * ubar + lines[1][1]:
            direction = -direction
            lines = lines[::-1]
    if len(lines) == 2 and lines[0][0] * lines[1][0] > 0:
        g_mid = math.sqrt(lines[0][0] * lines[1][0]) * math.copysign(1.0, lines[0][0])
        ratio = abs(lines[0][0] / lines[1][0])
        mt = 0.5 * abs(math.log(ratio)) if ratio > 0 else 0.1
        # a preload P beside the load moves the lines apart by P (e^mu Theta - e^-mu Theta) (the general form;
        # held at 0 unless the baseline fits it)
        pre = PARAMS[3].clip((lines[0][1] - lines[1][1]) / (2.0 * math.sinh(max(mt, 0.02))))
        c_mid = 0.5 * (lines[0][1] + lines[1][1]) - pre * (math.cosh(mt) - 1.0)
        starts = [(g_mid, c_mid, mt, pre)]
    else:
        starts = [(g, c, mt, 0.0) for g, c in starts for mt in (0.1, 0.3)]
    out = []
    for g_s, c_s, mu_theta, pre in starts:
        band = 2.0 * float(np.mean(np.abs(g_s * rec.u + pre))) * math.sinh(max(mu_theta, 0.02))
        # every parameter present (a start's missing one is its default in the fit, but a report lists each)
        p0 = {**{s.name: s.default for s in PARAMS}, "mu": min(mu_theta / th, 1.4), "theta": PARAMS[1].default,
              "preload": float(pre), "n": 0.5}
        # a stick crossing the band over 5 % of the travel on a distributed friction's curve (the linear
        # stick is the baseline's plain start), and the instant switch (k's upper bound: from a finite start a
        # fit stalls short of it where a few samples at the turns still cross the band late)
        out.append((direction, float(g_s), float(c_s), {**p0, "k": max(band / (0.05 * span), 1.0)}))
        out.append((direction, float(g_s), float(c_s), {**p0, "k": K_INSTANT}))
    return out


CAPSTAN_FRICTION = register(Effect(
    name="capstan_friction",
    link="force",
    doc="motor force from tip load: F_t exp(+mu Theta) pulling, exp(-mu Theta) releasing, "
        "stick transitions of stiffness k at reversals",
    params=PARAMS,
    inputs=("t", "x", "v", "load"),
    optional=("theta",),
    output="load",
    guess=_guess,
    kernel=KERNEL,
    # the project's simulation of a cable setup: the sheath's capstan friction on the force link
    rules=Rules(channel="motor_force", primary=("mu",), hold=_hold, baseline_starts=_baseline_starts,
                baseline=True),
))
