"""Element-wise loops of the scalar friction kernels, the array forms' compiled core (`jit.broadcast_call`
broadcasts their arguments): each applies its kernel, nothing else."""

from __future__ import annotations

from teleop.core.kernels.friction import coulomb_force, stribeck_force, viscous_force
from teleop.core.kernels.jit import njit
from teleop.core.kernels.sheath import capstan_hold, capstan_tip_step


@njit
def coulomb_loop(v, Fc, out):
    for i in range(out.shape[0]):
        out[i] = coulomb_force(v[i], Fc[i])


@njit
def viscous_loop(v, b, out):
    for i in range(out.shape[0]):
        out[i] = viscous_force(v[i], b[i])


@njit
def stribeck_loop(v, Fc, Fs, vs, out):
    for i in range(out.shape[0]):
        out[i] = stribeck_force(v[i], Fc[i], Fs[i], vs[i])


@njit
def hold_loop(t, pulling, mu_theta, out):
    """capstan_hold with pulling[i] > 0 meaning pulling."""
    for i in range(out.shape[0]):
        out[i] = capstan_hold(t[i], pulling[i] > 0.0, mu_theta[i])


@njit
def tip_loop(F_tip, F_motor, mu_theta, out):
    """capstan_tip_step element-wise."""
    for i in range(out.shape[0]):
        out[i] = capstan_tip_step(F_tip[i], F_motor[i], mu_theta[i])
