"""The position link's static transmission error (teleop.core.physics.transmission): a step kernel of the
catalogue's form (kernels.effects' docstring) and its array form beside it."""

from __future__ import annotations

import math

from teleop.core.kernels.jit import njit


@njit
def transmission_error_step(s, u, p):
    """u = (x,); p = (a1, b1, a2, b2, period): x + sum_k a_k sin(2 pi k x / period) + b_k cos(2 pi k x / period),
    k = 1, 2 (x, the a's and b's and the period in the link's position unit); no state."""
    w = 2.0 * math.pi * u[0] / p[4]
    return u[0] + p[0] * math.sin(w) + p[1] * math.cos(w) + p[2] * math.sin(2.0 * w) + p[3] * math.cos(2.0 * w)


@njit
def transmission_error_run(s, U, p, out):
    """out (n,): transmission_error_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = transmission_error_step(s, U[i], p)
    return out
