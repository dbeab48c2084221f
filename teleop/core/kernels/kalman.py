"""Kernel of the steady-state wrench Kalman update (estimation.kalman): the one definition of the step.

Per axis k, state (w, w_dot), steady gain K = (K0, K1), period dt [s] (the gain's nominal period):
    w_p = w + dt w_dot            # x = F x
    y = z - w_p                   # y = z - H x
    w = w_p + K0 y; w_dot += K1 y # x = x + K y
The first measurement initialises the state to (z, 0).
"""

from __future__ import annotations

from teleop.core.kernels.jit import njit

# rows of the filter array kf (5, n): state, gains, and [started, dt, ...]
W, W_DOT, K0, K1, META = 0, 1, 2, 3, 4


@njit
def kalman_update(kf, z):
    """Filter the measurement z (n,) in place (z becomes the estimate w) with the filter array kf (5, n)."""
    n = z.shape[0]
    if kf[META, 0] == 0.0:
        for k in range(n):
            kf[W, k] = z[k]
            kf[W_DOT, k] = 0.0
        kf[META, 0] = 1.0
        return
    dt = kf[META, 1]
    for k in range(n):
        wp = kf[W, k] + dt * kf[W_DOT, k]
        y = z[k] - wp
        kf[W, k] = wp + kf[K0, k] * y
        kf[W_DOT, k] += kf[K1, k] * y
        z[k] = kf[W, k]
