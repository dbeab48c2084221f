"""Step kernel of the catalogue's backlash (teleop.core.physics.backlash) with the main play's dead zone
growing with the tension the cable carries (Kaneko's tendon-sheath transmission): the tension measured as
the tip load T where the link records it (an external force), or proxied by the tip's own position where it
does not (under a spring the tip's position is its tension). It follows teleop.core.kernels.effects'
convention, `step(s, u, p) -> y` with `run(s, U, p, out)` its array form beside it:

    u = (x, T) the motor position referred to the tip [m or rad] (the link's gain and offset applied) and
        the tip load [N or N m] (physics.backlash's `load` parameter standing in where none is recorded)
    p = (r1, r2, w1, w2, grow, start, x_ref, plain, b, c, T_ref, lam) (physics.backlash.pack): the general
        play's layout (kernels.effects.backlash_step), b = r1 tension, c [1/N] and T_ref [N] (load_tension /
        load and load): the main play's half-width r1 (a + tension z1) with a = 1 + c (|T| - T_ref), growing
        with the load's magnitude and with the play's own position z1 (about x_ref); lam [m or rad] the
        take-up length (r1 take_up; 0: the sharp take-up)
    s = (z1, z2, lo, hi) the main and the wide play and the main play's envelopes at the last sample; NaN
        before the first sample

The main play z1 follows x - x_ref between the envelopes where x - z1 = +-r1 (a + tension z1), in closed form

    lo, hi = (x - r1 a) / (1 + b), (x + r1 a) / (1 - b)    (|b| < 1),    z1 = clamp(z1, lo, hi)

and beyond the zero-width point (the envelopes crossed: a slack cable) z1 = x. The wide play and the output
are kernels.friction.play_mix_step's. With b = c = 0 it is the general play, bit for bit.

A rounded take-up (lam > 0; pre-sliding along the sheath: Dahl's exponential approach, the partial-sliding
zone of Kaneko's transmission): the play moves before its envelope reaches it, at the envelope's rate times
e^(-D / lam), D >= 0 its distance to the envelope that closes in on it, so that dD = -(1 - e^(-D / lam)) dE
over the envelope's travel dE towards it: over the dead zone (D >> lam) the tip all but stands, and it
joins the envelope over a travel of a few lam (D ~ e^(-E / lam)) instead of at a corner. Exact over a
sample's envelope travel (`take_up_gap`); lam -> 0 is the sharp play, and lam = 0 is it bit for bit.
"""

from __future__ import annotations

import math

from teleop.core.kernels.effects import plain_play_step
from teleop.core.kernels.friction import play_mix_start, play_mix_step
from teleop.core.kernels.jit import njit


@njit
def take_up_gap(gap, travel, lam):
    """The play's distance [m or rad] to the envelope closing in on it after that envelope's travel >= 0,
    from `gap` >= 0, under dD = -(1 - e^(-D / lam)) dE (lam > 0 the take-up length): e^(D / lam) - 1 decays
    as e^(-E / lam), D = lam ln(1 + (e^(gap / lam) - 1) e^(-travel / lam)), in a form that cannot overflow."""
    a = gap / lam
    e = travel / lam
    if a >= e:
        return lam * ((a - e) + math.log1p(math.exp(e - a) - math.exp(-a)))
    return lam * math.log1p(math.exp(a - e) - math.exp(-e))


@njit
def tension_play_step(s, u, p):
    """backlash's general form with the main play's width growing with its position (p[8] = b) and with
    the load's magnitude (p[9] = c about p[10] = T_ref), its take-up rounded over p[11] = lam (0: sharp)."""
    xr, r1, b, lam = u[0] - p[6], p[0], p[8], p[11]
    ra = r1 * (1.0 + p[9] * (abs(u[1]) - p[10])) if p[9] != 0.0 else r1
    if s[0] != s[0]:
        s[0], s[1] = play_mix_start(xr, ra, p[1], p[5])
    lo = (xr - ra) / (1.0 + b)
    hi = (xr + ra) / (1.0 - b)
    if lo > hi:            # past the zero-width point: no play left
        lo = xr
        hi = xr
    z1 = s[0]
    if lam > 0.0:
        if s[2] == s[2]:
            # each envelope that closed in on the play since the last sample drew it along, rounded
            if lo > s[2]:
                z1 = lo + take_up_gap(max(z1 - s[2], 0.0), lo - s[2], lam)
            if hi < s[3]:
                z1 = hi - take_up_gap(max(s[3] - z1, 0.0), s[3] - hi, lam)
        s[2], s[3] = lo, hi
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
