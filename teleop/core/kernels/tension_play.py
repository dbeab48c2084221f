"""Step kernel of the catalogue's backlash (teleop.core.physics.backlash) with the main play's dead zone
growing with the tension the cable carries (Kaneko's tendon-sheath transmission): the tension measured as
the tip load T where the link records it (an external force), or proxied by the tip's own position where it
does not (under a spring the tip's position is its tension). It follows teleop.core.kernels.effects'
convention, `step(s, u, p) -> y` with `run(s, U, p, out)` its array form beside it:

    u = (x, T) the motor position referred to the tip [m or rad] (the link's gain and offset applied) and
        the tip load [N or N m] (physics.backlash's `load` parameter standing in where none is recorded)
    p = (r1, r2, w1, w2, grow, start, x_ref, plain, b, c, T_ref) (physics.backlash.pack): the general play's
        layout (kernels.effects.backlash_step), b = r1 tension, c [1/N] and T_ref [N] (load_tension / load
        and load): the main play's half-width r1 (a + tension z1) with a = 1 + c (|T| - T_ref), growing with
        the load's magnitude and with the play's own position z1 (about x_ref)
    s = (z1, z2) the main and the wide play; NaN before the first sample

The main play z1 follows x - x_ref between the envelopes where x - z1 = +-r1 (a + tension z1), in closed form

    z1 = clamp(z1, (x - r1 a) / (1 + b), (x + r1 a) / (1 - b))    (|b| < 1)

and beyond the zero-width point (the envelopes crossed: a slack cable) z1 = x. The wide play and the output
are kernels.friction.play_mix_step's. With b = c = 0 it is kernels.effects.general_play_step, bit for bit.
"""

from __future__ import annotations

import math

from teleop.core.kernels.effects import plain_play_step
from teleop.core.kernels.friction import play_mix_start, play_mix_step
from teleop.core.kernels.jit import njit


@njit
def tension_play_step(s, u, p):
    """backlash's general form with the main play's width growing with its position (p[8] = b) and with
    the load's magnitude (p[9] = c about p[10] = T_ref)."""
    xr, r1, b = u[0] - p[6], p[0], p[8]
    ra = r1 * (1.0 + p[9] * (abs(u[1]) - p[10])) if p[9] != 0.0 else r1
    if s[0] != s[0]:
        s[0], s[1] = play_mix_start(xr, ra, p[1], p[5])
    lo = (xr - ra) / (1.0 + b)
    hi = (xr + ra) / (1.0 - b)
    if lo > hi:            # past the zero-width point: no play left
        lo = xr
        hi = xr
    z1 = s[0]
    z1 = hi if z1 > hi else (lo if z1 < lo else z1)
    # the main play clamped already: play_mix_step's own clamp of it is open (r1 = inf)
    s[0], s[1], y = play_mix_step(z1, s[1], xr, math.inf, p[1], p[2], p[3], p[4])
    return y + p[6]


@njit
def backlash_step(s, u, p):
    """kernels.effects.plain_play_step where p[7] (plain) = 1, else tension_play_step."""
    return plain_play_step(s, u, p) if p[7] != 0.0 else tension_play_step(s, u, p)


@njit
def backlash_run(s, U, p, out):
    """out (n,): backlash_step along U (n, k) from the state s (the form chosen once, outside the loop)."""
    if p[7] != 0.0:
        for i in range(U.shape[0]):
            out[i] = plain_play_step(s, U[i], p)
    else:
        for i in range(U.shape[0]):
            out[i] = tension_play_step(s, U[i], p)
    return out
