"""The effect catalogue's physics (teleop.core.physics), one step kernel per effect, and the one loop that runs
any of them over a whole signal.

A step kernel is `step(s, u, p) -> y` (python-control's update function, the state held in place):
- s (m,) float64: the effect's state, updated in place; NaN in its first slot before the first sample
  (the step then starts the state from that sample, as the effect's docs say);
- u (k,) float64: one sample of the effect's input channels, in the order Effect.inputs + Effect.optional
  (a missing optional channel carries the parameter of the same name);
- p (j,) float64: the parameters, in the order of the effect's ParamSpecs unless its kernel packs them
  otherwise (physics.base.Kernel.pack; the layout is in each kernel's docstring);
- y: the sample of the effect's output channel.
Each step has its array form beside it, `<name>_run(s, U, p, out)`: the step along U (n, k) from the state s
(left at the last sample's) into out (n,), nothing else (numba inlines the step into the loop; a loop over a
step passed as a first-class function would be cached once for all, but its indirect call per sample made
the diagnosis's fits several times slower). An effect whose vectorised closed form is several times faster
than such a loop keeps the closed form as its one home instead (cable_compliance: physics.compliance), and
the sheath's capstan_friction runs the sheath's own law (kernels.sheath.capstan_rate_step).
"""

from __future__ import annotations

import math

from teleop.core.kernels.friction import clamp, coulomb_force, dahl_step, \
    stribeck_force, viscous_force
from teleop.core.kernels.jit import njit
from teleop.core.kernels.sheath import F


# ------------------------------------------------------------------ position links
@njit
def plain_play_step(s, u, p):
    """backlash's plain form (its step kernel: kernels.tension_play.backlash_step): the play of half-width
    r1, z1 = clamp(z1, x - r1, x + r1), starting at x."""
    x, r = u[0], p[0]
    s[0] = x if s[0] != s[0] else clamp(s[0], x - r, x + r)
    return s[0]


# ------------------------------------------------------------------ force links
@njit
def parallel_spring_step(s, u, p):
    """u = (x, load); p = (k, g, x_ref): load + dx (k + g dx / 2), dx = x - x_ref; no state."""
    dx = u[0] - p[2]
    return u[1] + dx * (p[0] + 0.5 * p[1] * dx)


@njit
def parallel_spring_run(s, U, p, out):
    """out (n,): parallel_spring_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = parallel_spring_step(s, U[i], p)
    return out


@njit
def coulomb_friction_step(s, u, p):
    """u = (v, load); p = (Fc,): load + Fc sign(v); no state."""
    return u[1] + coulomb_force(u[0], p[0])


@njit
def coulomb_friction_run(s, U, p, out):
    """out (n,): coulomb_friction_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = coulomb_friction_step(s, U[i], p)
    return out


@njit
def viscous_friction_step(s, u, p):
    """u = (v, load); p = (b,): load + b v; no state."""
    return u[1] + viscous_force(u[0], p[0])


@njit
def viscous_friction_run(s, U, p, out):
    """out (n,): viscous_friction_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = viscous_friction_step(s, U[i], p)
    return out


@njit
def stribeck_friction_step(s, u, p):
    """u = (v, load); p = (Fc, Fs, vs): load + the Stribeck force; no state."""
    return u[1] + stribeck_force(u[0], p[0], p[1], p[2])


@njit
def stribeck_friction_run(s, U, p, out):
    """out (n,): stribeck_friction_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = stribeck_friction_step(s, U[i], p)
    return out


@njit
def dahl_hysteresis_step(s, u, p):
    """u = (x, load); p = (sigma, Fc); s = (x_prev, F): load + the Dahl force F, which holds at the first
    sample (x_prev NaN) and follows dahl_step after."""
    if s[0] == s[0]:
        s[1] = dahl_step(s[1], u[0] - s[0], p[0], p[1])
    s[0] = u[0]
    return u[1] + s[1]


@njit
def dahl_hysteresis_run(s, U, p, out):
    """out (n,): dahl_hysteresis_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = dahl_hysteresis_step(s, U[i], p)
    return out


@njit
def driven_play(s, x, start, lo, hi, k):
    """A force F [N] dragged by the motor position x [m] at stiffness k [N/m] within its band [lo, hi] (the
    stick transitions of a cable over pulleys): F <- clamp(F + k (x - x_prev), lo, hi), held as the plain
    play of y = F - k x, y <- clamp(y, lo - k x, hi - k x); s = (x_prev, y); the first sample (x_prev NaN)
    starts at min(max(start, lo), hi) (hi where the band is empty, lo > hi: a negative load's)."""
    kx = k * x
    y = min(max(start, lo), hi) - kx if s[0] != s[0] else s[1]
    s[0], s[1] = x, clamp(y, lo - kx, hi - kx)
    return s[1] + kx


@njit
def driven_play_step(s, u, p):
    """u = (x, start, lo, hi); p = (k,); s = (x_prev, F - k x_prev): driven_play."""
    return driven_play(s, u[0], u[1], u[2], u[3], p[0])


@njit
def driven_play_run(s, U, p, out):
    """out (n,): driven_play_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = driven_play_step(s, U[i], p)
    return out


@njit
def pulley_force(s, x, load, K, B, k):
    """Motor force [N] over a lumped pulley (tension ratio K, bending loss B [N]) with stick transitions of
    stiffness k [N/m]; s = (x_prev, F - k x_prev): driven_play in the band releasing max((load - B) / K, 0), pulling
    K load + B, starting on the load."""
    return driven_play(s, x, load, max((load - B) / K, 0.0), K * load + B, k)


@njit
def pulley_friction_step(s, u, p):
    """u = (x, load); p = (mu, wrap, bend, k); s = (x_prev, F - k x_prev): pulley_force, K = e^(mu wrap)."""
    return pulley_force(s, u[0], u[1], math.exp(p[0] * p[1]), p[2], p[3])


@njit
def pulley_friction_run(s, U, p, out):
    """out (n,): pulley_friction_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = pulley_friction_step(s, U[i], p)
    return out


@njit
def pulley_elongation_step(s, u, p):
    """u = (x, load); p = (c, mu, wrap, bend, k); s = (x_prev, F - k x_prev): tip position
    x - c (load + F) / 2, F the lumped pulley's motor force."""
    F = pulley_force(s, u[0], u[1], math.exp(p[1] * p[2]), p[3], p[4])
    return u[0] - p[0] * 0.5 * (u[1] + F)


@njit
def pulley_elongation_run(s, U, p, out):
    """out (n,): pulley_elongation_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = pulley_elongation_step(s, U[i], p)
    return out


# ------------------------------------------------------------------ sensors
@njit
def hysteresis_switch(z, F, h, d):
    """(z, offset): the loading switch z, the play of the force F [N] of half-width d [N] (z NaN: none yet,
    it starts at F, neutral), and the reading's offset h (F - z) / d [N]."""
    z = F if z != z else clamp(z, F - d, F + d)
    return z, h * (F - z) / d


@njit
def hysteresis_offset_step(s, u, p):
    """u = (force,); p = (h, delta); s = (z,): the reading's offset, hysteresis_switch."""
    s[0], off = hysteresis_switch(s[0], u[0], p[0], p[1])
    return off


@njit
def hysteresis_offset_run(s, U, p, out):
    """out (n,): hysteresis_offset_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = hysteresis_offset_step(s, U[i], p)
    return out


@njit
def sensor_hysteresis_step(s, u, p):
    """u = (force,); p = (h, delta); s = (z,): force + the offset of hysteresis_switch."""
    s[0], off = hysteresis_switch(s[0], u[0], p[0], p[1])
    return u[0] + off


@njit
def sensor_hysteresis_run(s, U, p, out):
    """out (n,): sensor_hysteresis_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = sensor_hysteresis_step(s, U[i], p)
    return out


@njit
def thermal_drift_step(s, u, p):
    """u = (force, temperature); p = (c, T0): force + c (T - T0); no state."""
    return u[0] + p[0] * (u[1] - p[1])


@njit
def thermal_drift_run(s, U, p, out):
    """out (n,): thermal_drift_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = thermal_drift_step(s, U[i], p)
    return out


@njit
def thermal_drift_time_step(s, u, p):
    """u = (t, force); p = (offset, rate); s = (t0,): force + offset + rate (t - t0), t0 the first t."""
    if s[0] != s[0]:
        s[0] = u[0]
    return u[1] + p[0] + p[1] * (u[0] - s[0])


@njit
def thermal_drift_time_run(s, U, p, out):
    """out (n,): thermal_drift_time_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = thermal_drift_time_step(s, U[i], p)
    return out


# ------------------------------------------------------------------ contact
@njit
def linear_contact_step(s, u, p):
    """u = (d,); p = (k,): k max(d, 0); no state."""
    return p[0] * max(u[0], 0.0)


@njit
def linear_contact_run(s, U, p, out):
    """out (n,): linear_contact_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = linear_contact_step(s, U[i], p)
    return out


@njit
def hertz_contact_step(s, u, p):
    """u = (d,); p = (k,): k max(d, 0)^1.5; no state."""
    return p[0] * max(u[0], 0.0) ** 1.5


@njit
def hertz_contact_run(s, U, p, out):
    """out (n,): hertz_contact_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = hertz_contact_step(s, U[i], p)
    return out


@njit
def viscoelasticity_step(s, u, p):
    """u = (t, force, d), force the elastic force Fe; p = (g, tau); s = (t_prev, Fe_prev, q): the standard
    linear solid, q <- a q + (1 - g) (dFe / dt) tau (1 - a), a = e^(-dt / tau) (q = 0 at the first sample);
    max(g Fe + q, 0) in contact (d > 0), else 0."""
    t, Fe = u[0], u[1]
    g, tau = p[0], p[1]
    if s[0] != s[0]:
        s[2] = 0.0
    elif t > s[0]:
        dt = t - s[0]
        a = math.exp(-dt / tau)
        s[2] = a * s[2] + (1.0 - g) * ((Fe - s[1]) / dt) * tau * (1.0 - a)
    s[0], s[1] = t, Fe
    return max(g * Fe + s[2], 0.0) if u[2] > 0.0 else 0.0


@njit
def viscoelasticity_run(s, U, p, out):
    """out (n,): viscoelasticity_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = viscoelasticity_step(s, U[i], p)
    return out


@njit
def contact_damping_step(s, u, p):
    """u = (force, d, d_dot); p = (c,): max(force + c d_dot, 0) in contact (d > 0), else 0; no state."""
    return max(u[0] + p[0] * u[2], 0.0) if u[1] > 0.0 else 0.0


@njit
def contact_damping_run(s, U, p, out):
    """out (n,): contact_damping_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = contact_damping_step(s, U[i], p)
    return out


# ------------------------------------------------------------------ lags (position links)
@njit
def transport_delay_step(s, u, p):
    """u = (t, x); p = (delay,) [s]; s = (w, r, ring of times (N,), ring of inputs (N,)), N = (len(s) - 2) / 2:
    w the samples written so far (NaN before the first), r the index of the newest kept sample at or before
    t - delay. Returns x(t - delay), linearly interpolated between the kept samples that bracket it (a whole
    number of sample intervals reads a kept sample exactly); before the first sample the input is held at
    its first value; a delay reaching further back than the N kept samples reads the oldest one kept."""
    n = (s.shape[0] - 2) // 2
    if s[0] != s[0]:
        s[0], s[1] = 0.0, 0.0
    w = int(s[0])
    s[2 + w % n] = u[0]
    s[2 + n + w % n] = u[1]
    w += 1
    s[0] = w
    target = u[0] - p[0]
    r = max(int(s[1]), w - n)
    while r + 1 < w and s[2 + (r + 1) % n] <= target:
        r += 1
    s[1] = r
    t0, x0 = s[2 + r % n], s[2 + n + r % n]
    if r + 1 >= w or target <= t0:
        return x0
    t1, x1 = s[2 + (r + 1) % n], s[2 + n + (r + 1) % n]
    return x0 + (target - t0) / (t1 - t0) * (x1 - x0)


@njit
def transport_delay_run(s, U, p, out):
    """out (n,): transport_delay_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = transport_delay_step(s, U[i], p)
    return out


@njit
def first_order_lag_step(s, u, p):
    """u = (t, x); p = (tau,) [s]; s = (t_prev, x_prev, y): y follows x through dy/dt = (x - y) / tau, integrated
    exactly over each interval with x linear between its samples (a first-order hold):
    y <- a y + (1 - a) x_prev + (x - x_prev) (1 - tau (1 - a) / dt), a = exp(-dt / tau); y starts at the
    first sample's x (at rest)."""
    t, x = u[0], u[1]
    if s[0] != s[0]:
        s[2] = x
    elif t > s[0]:
        dt = t - s[0]
        b = -math.expm1(-dt / p[0])          # 1 - a, exact for dt << tau
        s[2] = (1.0 - b) * s[2] + b * s[1] + (x - s[1]) * (1.0 - p[0] * b / dt)
    s[0], s[1] = t, x
    return s[2]


@njit
def first_order_lag_run(s, U, p, out):
    """out (n,): first_order_lag_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = first_order_lag_step(s, U[i], p)
    return out
