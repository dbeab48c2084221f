"""Kernels of the friction laws and the direction rule, per sample on floats: the one definition of each (the
sheath's capstan law: teleop.core.kernels.sheath).

Conventions of teleop.core.physics: x increasing = the motor hauls its cable in (pulling); a motor travel dx > 0
pulls. Each returns the new state; the callers (the physics Steps and array forms, the estimators, the
simulated robot, the loop's tick) keep the state.

- `direction_step`: the Schmitt trigger on reversals (estimation.direction): direction d (+1 rising, -1
  falling, 0 not yet moved) flips only once the value has come back more than the dead band from the
  extreme reached since the last flip.
- `dahl_step`: Dahl pre-sliding friction, exact over a monotone step: F = s Fc + (F - s Fc) e^(-sigma |dx| / Fc).
- `play_inverse_step`: the inverse of the play operator (backlash feed-forward, seed 002): the command
  x = y_d + r s leads the wanted output y_d by up to the half-width r on the side s of its motion,
  rate-limited and kept within limits.
- `play_mix_step`: the general play (backlash) of a tendon in a sheath: an elastic part, a main play and a
  wide play, the lag scaling with the position (physics.backlash).
"""

from __future__ import annotations

import math

from teleop.core.kernels.jit import njit


@njit
def sgn(v):
    """sign(v) as a float, sign(0) = 0."""
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@njit
def clamp(y, lo, hi):
    """min(max(y, lo), hi) (the play operator's step; needs lo <= hi)."""
    return hi if y > hi else (lo if y < lo else y)


@njit
def direction_step(d, e, v, deadband):
    """(d, e, flipped): direction and extreme after value v; e NaN = no value yet (v becomes the reference)."""
    if e != e:
        e = v
    if d <= 0.0 and v > e + deadband:      # rising past the dead band
        return 1.0, v, d < 0.0
    if d >= 0.0 and v < e - deadband:      # falling past the dead band
        return -1.0, v, d > 0.0
    if d > 0.0 and v > e:                  # the extreme follows the motion
        e = v
    elif d < 0.0 and v < e:
        e = v
    return d, e, False


@njit
def dahl_step(F, dx, sigma, Fc):
    """Dahl force [N] after a motor travel dx [m] from force F; sigma [N/m], Fc [N] > 0."""
    a = math.exp(-sigma * abs(dx) / Fc)
    return a * F + sgn(dx) * Fc * (1.0 - a)


@njit
def play_inverse_step(y_d, r, s, max_step, lo, hi, x_prev):
    """The command x [m] making a play of half-width r [m] output y_d [m]: x = y_d + r s, s in [-1, 1] the
    side of the play to drive on (+1 while y_d rises), its change from x_prev limited to +-max_step (x_prev
    NaN: none yet) and x clamped into [lo, hi]. Since x - r <= y_d <= x + r, a y_d that holds still keeps
    the output still whatever s does."""
    x = y_d + r * s
    if x_prev == x_prev:
        x = clamp(x, x_prev - max_step, x_prev + max_step)
    return clamp(x, lo, hi)


@njit
def coulomb_force(v, Fc):
    """Coulomb friction [N]: Fc sign(v)."""
    return Fc * sgn(v)


@njit
def viscous_force(v, b):
    """Viscous friction [N]: b v, b [N s/m]."""
    return b * v


@njit
def stribeck_force(v, Fc, Fs, vs):
    """Stribeck friction [N]: (Fc + (Fs - Fc) exp(-(v/vs)^2)) sign(v); vs [m/s] the Stribeck velocity."""
    return (Fc + (Fs - Fc) * math.exp(-(v / vs) ** 2)) * sgn(v)


@njit
def play_mix_step(z1, z2, x, r1, r2, w1, w2, grow):
    """One sample of the general play at position x: plays of half-widths r1 and r2 (states z1, z2, clamped
    into [x - r, x + r]) lag x by (z - x); the output is x + e^(grow x) (w1 (z1 - x) + w2 (z2 - x)), weights w
    of the two plays (1 - w1 - w2: the elastic part that follows x at once). Returns (z1, z2, y)."""
    z1 = clamp(z1, x - r1, x + r1)
    z2 = clamp(z2, x - r2, x + r2)
    return z1, z2, x + math.exp(grow * x) * (w1 * (z1 - x) + w2 * (z2 - x))


@njit
def play_mix_start(x0, r1, r2, start):
    """(z1, z2): the general play's states at the first position x0, start in [-1, 1] (where in its band each
    play was when the record began)."""
    return x0 + start * r1, x0 + start * r2


@njit
def play_inverse_into(y_d, r, v0, alpha, dt, max_step, lo, hi, state, out):
    """out (n,): play_inverse_step on n channels (cables) at one command, the side s = clip(v / v0, -1, 1)
    from the low-passed rate v of y_d (v += alpha ((y_d - y_prev) / dt - v), dt [s] between commands, v0
    [m/s]); y_d, r, lo, hi (n,) [m]; state (3, n): previous y_d (NaN: none), v [m/s], previous command x
    (NaN: none), updated in place."""
    for i in range(y_d.shape[0]):
        y_prev = state[0, i]
        if y_prev == y_prev:
            state[1, i] += alpha * ((y_d[i] - y_prev) / dt - state[1, i])
        x = play_inverse_step(y_d[i], r[i], clamp(state[1, i] / v0, -1.0, 1.0), max_step, lo[i], hi[i], state[2, i])
        state[0, i], state[2, i] = y_d[i], x
        out[i] = x
    return out


@njit
def play_inverse_run(y_d, r, max_step, out):
    """out (n,): play_inverse_step along the samples y_d (n,) [m] of one channel from rest, on the side of
    y_d's held direction (direction_step without dead band: the exact inverse of the play operator)."""
    d, e, x = 0.0, math.nan, math.nan
    for k in range(y_d.shape[0]):
        d, e, _ = direction_step(d, e, y_d[k], 0.0)
        x = play_inverse_step(y_d[k], r, d, max_step, -math.inf, math.inf, x)
        out[k] = x
    return out
