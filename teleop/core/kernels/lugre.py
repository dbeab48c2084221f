"""Kernel of the LuGre friction's bristle law without its damping terms (physics.lugre), per sample on floats.

Conventions of teleop.core.physics: x increasing = the motor hauls its cable in (pulling). The step's layout
is teleop.core.kernels.effects' (s the state, u one sample of the effect's channels, p its parameters); the
array form `lugre_friction_run` is that step along a whole signal (numba inlines it into the loop).
"""

from __future__ import annotations

from teleop.core.kernels.friction import dahl_step, stribeck_force
from teleop.core.kernels.jit import njit


@njit
def lugre_level(v, Fc, Fs, vs):
    """The friction level g(v) [N] the bristles settle at, the Stribeck curve's magnitude: Fs at rest, Fc in
    fast sliding (kernel friction.stribeck_force); vs [m/s] > 0."""
    return Fs if v == 0.0 else stribeck_force(abs(v), Fc, Fs, vs)


@njit
def lugre_friction_step(s, u, p):
    """u = (x, v, load); p = (sigma, Fc, Fs, vs); s = (x_prev, F): load + the friction force F, which holds
    at the first sample (x_prev NaN) and after follows dF/dx = sigma (1 - F sgn(dx) / g(v)), integrated
    exactly over the sample's travel dx at the sample's level g(v) (kernel friction.dahl_step with Fc = g)."""
    if s[0] == s[0]:
        s[1] = dahl_step(s[1], u[0] - s[0], p[0], lugre_level(u[1], p[1], p[2], p[3]))
    s[0] = u[0]
    return u[2] + s[1]


@njit
def lugre_friction_run(s, U, p, out):
    """out (n,): lugre_friction_step along U (n, k) from the state s."""
    for i in range(U.shape[0]):
        out[i] = lugre_friction_step(s, U[i], p)
    return out
