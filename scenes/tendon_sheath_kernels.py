"""Compiled step of the distributed tendon-sheath cable (scenes.tendon_sheath): one implicit step of every
cable, the per-tick step (all cables, sub-steps, input interpolation) and the batch that calls that step for
each tick of a trajectory (one source for the loop and the batch).

Symbols (one cable, N elements, nodes i = 0..N from the motor to the tip; travel u hauling in is positive):
    u, v (N+1,)   node travel [m] from the initial configuration and velocity [m/s]; u[0] is the motor
    z (N+1,)      LuGre bristle state of each node [m]
    t0            tension of the initial configuration [N] (uniform, no friction)
    b (N,)        bend angle of each element [rad]
    T (N,)        element tension [N]: T_j = max(0, t0 + k (u_j - u_{j+1})), k = EA / l
    p (P_COUNT,)  parameter vector (indices P_*)

Per node (i = 1..N), backward Euler over a step h, unknowns du_i = u_i' - u_i:
    m_i (du_i - h v_i) / h^2 = T'_{i-1} - T'_i - n'_i phi_i - [i = N] F_load'
    n'_i = (T'_{i-1} b_{i-1} + T'_i b_i) / 2                      normal force [N] (T'_N = 0)
    z'_i = (z_i + du_i) / (1 + |du_i| / zs),  zs = g(v_i) / sigma0    LuGre dz/dt = v - sigma0 |v| z / g(v)
    phi_i = sigma0 z'_i + sigma1 (z'_i - z_i) / h + sigma2 du_i / h  friction coefficient [-]
    g(v) = mu_c + (mu_s - mu_c) exp(-(v / v_s)^2)                  Stribeck curve [-], at the last step's v
solved by Newton's method on the tridiagonal Jacobian (Thomas algorithm). With g taken at the last step's
velocity every node's friction is a nondecreasing function of its own travel du_i (z' is, for |z| <= zs), and
Newton converges; a Newton step that would carry du_i across 0 (the bristle law's kink) stops on it.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.core.kernels.jit import njit

# parameter vector p
P_K = 0  # element stiffness EA / l [N/m]
P_M = 1  # interior node mass rho_l l [kg]
P_MU_C = 2  # Coulomb coefficient [-]
P_MU_S = 3  # static (Stribeck peak) coefficient [-]
P_V_S = 4  # Stribeck velocity [m/s]
P_SIGMA0 = 5  # bristle stiffness per unit normal force [1/m]
P_SIGMA1 = 6  # bristle damping per unit normal force [s/m]
P_SIGMA2 = 7  # viscous coefficient per unit normal force [s/m]
P_K_LOAD = 8  # load spring stiffness [N/m]
P_REST = 9  # load spring rest position of the tip [m]
P_TOL = 10  # Newton tolerance on du [m]
P_ITER = 11  # Newton iteration limit [-]
P_COUNT = 12

MODE_SPRING = 0  # tip load F = k_load (u_N - rest) + f_ext, f_ext the tip input [N]
MODE_POSITION = 1  # tip travel prescribed, the tip input [m]; F the reaction

WORK_ROWS = 10  # rows of the scratch array (WORK_ROWS, N+1)


@njit
def stribeck_curve(v, mu_c, mu_s, v_s):
    """g(v) [-] at speed v [m/s]."""
    if mu_s == mu_c or v_s <= 0.0:
        return mu_c
    r = v / v_s
    if r * r > 50.0:
        return mu_c
    return mu_c + (mu_s - mu_c) * math.exp(-r * r)


@njit
def bristle(z, du, zs):
    """(z', dz'/du): the LuGre state after travel du [m] by backward Euler, zs = g / sigma0 [m] (0: no
    friction)."""
    if zs <= 0.0:
        return 0.0, 0.0
    a = 1.0 + abs(du) / zs
    zn = (z + du) / a
    if du > 0.0:
        dz = (1.0 - z / zs) / (a * a)
    elif du < 0.0:
        dz = (1.0 + z / zs) / (a * a)
    else:
        dz = 1.0
    return zn, dz


@njit
def friction_coefficient(z, du, v, h, p):
    """(phi, dphi/du, z'): friction coefficient [-] of a node travelling du [m] over h [s] from state z, the
    Stribeck curve at the last step's velocity v [m/s]."""
    g = stribeck_curve(v, p[P_MU_C], p[P_MU_S], p[P_V_S])
    s0 = p[P_SIGMA0]
    zn, dz = bristle(z, du, g / s0)
    c = s0 + p[P_SIGMA1] / h
    phi = c * zn - p[P_SIGMA1] * z / h + p[P_SIGMA2] * du / h
    return phi, c * max(dz, 0.0) + p[P_SIGMA2] / h, zn


@njit
def cable_step(u, v, z, t0, b, p, h, du0, mode, tip, T, w):
    """One backward-Euler step h [s] of one cable: motor travel du0 [m]; tip = f_ext [N] (MODE_SPRING) or
    the tip's travel over the step [m] (MODE_POSITION). Updates u, v, z (N+1,) and T (N,) in place; w
    (WORK_ROWS, N+1) scratch. Returns (motor force, tip load force, Newton iterations) [N, N, -]."""
    N = T.shape[0]
    k = p[P_K]
    m = p[P_M]
    kl = p[P_K_LOAD]
    du = w[0]
    zn = w[1]
    phi = w[2]
    dphi = w[3]
    act = w[4]
    lo = w[5]
    di = w[6]
    up = w[7]
    r = w[8]
    cp = w[9]
    last = N if mode == MODE_SPRING else N - 1
    du[0] = du0
    if mode == MODE_POSITION:
        du[N] = tip
    for i in range(1, last + 1):
        du[i] = h * v[i]  # predictor: the last step's velocity
    h2 = h * h
    max_iter = int(p[P_ITER])
    it = 0
    while True:
        for j in range(N):  # T'_j and its slope (0 when slack)
            s = t0 + k * (u[j] + du[j] - u[j + 1] - du[j + 1])
            if s > 0.0:
                T[j] = s
                act[j] = k
            else:
                T[j] = 0.0
                act[j] = 0.0
        for i in range(1, N + 1):
            phi[i], dphi[i], zn[i] = friction_coefficient(z[i], du[i], v[i], h, p)
        for i in range(1, last + 1):
            Tl = T[i - 1]
            al = act[i - 1]
            bl = b[i - 1]
            if i < N:
                Tr = T[i]
                ar = act[i]
                br = b[i]
                mi = m
            else:
                Tr = 0.0
                ar = 0.0
                br = 0.0
                mi = 0.5 * m
            n = 0.5 * (Tl * bl + Tr * br)  # normal force n'_i
            res = mi * (du[i] - h * v[i]) / h2 - Tl + Tr + n * phi[i]
            d = mi / h2 + al + ar + n * dphi[i] + 0.5 * phi[i] * (br * ar - bl * al)
            if i == N:  # MODE_SPRING: the load on the tip node
                res += kl * (u[N] + du[N] - p[P_REST]) + tip
                d += kl
            lo[i] = -al * (1.0 - 0.5 * phi[i] * bl)
            up[i] = -ar * (1.0 + 0.5 * phi[i] * br)
            di[i] = d
            r[i] = -res
        if it >= max_iter:
            break
        # Thomas algorithm: J delta = -R over i = 1..last (delta of the known ends is 0)
        cp[1] = up[1] / di[1]
        r[1] = r[1] / di[1]
        for i in range(2, last + 1):
            den = di[i] - lo[i] * cp[i - 1]
            cp[i] = up[i] / den
            r[i] = (r[i] - lo[i] * r[i - 1]) / den
        for i in range(last - 1, 0, -1):
            r[i] -= cp[i] * r[i + 1]
        big = 0.0
        for i in range(1, last + 1):  # a step that crosses du = 0 (friction's kink) stops on it
            d = r[i]
            if (du[i] > 0.0 and du[i] + d < 0.0) or (du[i] < 0.0 and du[i] + d > 0.0):
                d = -du[i]
            du[i] += d
            big = max(big, abs(d))
        it += 1
        if big < p[P_TOL]:
            max_iter = it  # one more evaluation at the converged du, then stop
    # the motor node: its friction adds to the motor's force (the proximal gauge between motor and sheath)
    phi0, _, z0 = friction_coefficient(z[0], du0, v[0], h, p)
    f_motor = T[0] * (1.0 + 0.5 * b[0] * phi0)
    n_tip = 0.5 * T[N - 1] * b[N - 1]
    if mode == MODE_SPRING:
        f_load = kl * (u[N] + du[N] - p[P_REST]) + tip
    else:
        f_load = T[N - 1] - n_tip * phi[N] - 0.5 * m * (du[N] - h * v[N]) / h2
    z[0] = z0
    for i in range(N + 1):
        if i > 0:
            z[i] = zn[i]
        v[i] = du[i] / h
        u[i] += du[i]
    return f_motor, f_load, it


@njit
def element_bends(W, theta_fixed, theta, b):
    """b (N,) [rad] = W[0] theta0 + W[1] theta1 + W[2] |theta|; W (3, N) the bend's share of each element."""
    a = abs(theta)
    for j in range(b.shape[0]):
        b[j] = W[0, j] * theta_fixed[0] + W[1, j] * theta_fixed[1] + W[2, j] * a


@njit
def step(u, v, z, t0, tip_prev, x_motor, tip_in, theta, theta_fixed, W, p, mode, tick, n_sub, T, out, w, b):
    """One tick of c cables: u, v, z (c, N+1) state; t0 (c,) initial tensions [N]; tip_prev (c,) the last
    tick's tip input; x_motor (c,) motor travel [m] at the tick's end; tip_in (c,) f_ext [N] or tip travel
    [m] at the tick's end (by `mode`); theta (c,) kinematic bend [rad]; theta_fixed (c, 2) scaffold and route
    bends [rad]; W (3, N); tick [s] in n_sub steps, the motor and tip inputs interpolated linearly.
    Writes T (c, N) element tensions [N], out (c, 4): motor force, tip load force [N], tip travel [m], Newton
    iterations of the tick. w (WORK_ROWS, N+1) and b (N,) scratch."""
    N = T.shape[1]
    h = tick / n_sub
    for c in range(u.shape[0]):
        element_bends(W, theta_fixed[c], theta[c], b)
        dm = (x_motor[c] - u[c, 0]) / n_sub
        f_m = 0.0
        f_l = 0.0
        its = 0
        for s in range(n_sub):
            if mode == MODE_SPRING:
                a = tip_prev[c] + (tip_in[c] - tip_prev[c]) * (s + 1) / n_sub
            else:
                a = (tip_in[c] - u[c, N]) / (n_sub - s)
            f_m, f_l, n_it = cable_step(u[c], v[c], z[c], t0[c], b, p, h, dm, mode, a, T[c], w)
            its += n_it
        tip_prev[c] = tip_in[c]
        out[c, 0] = f_m
        out[c, 1] = f_l
        out[c, 2] = u[c, N]
        out[c, 3] = its


@njit
def run(u, v, z, t0, tip_prev, X, TIP, THETA, theta_fixed, W, p, mode, tick, n_sub, OUT, TT):
    """`step` for each tick k of X, TIP, THETA (m, c): OUT (m, c, 4); TT (m, c, N) the element tensions of
    every tick, or (1, c, N) to keep the last tick's only."""
    N = TT.shape[2]
    w = np.empty((WORK_ROWS, N + 1))
    b = np.empty(N)
    keep = TT.shape[0] == X.shape[0]
    for k in range(X.shape[0]):
        T = TT[k] if keep else TT[0]
        step(u, v, z, t0, tip_prev, X[k], TIP[k], THETA[k], theta_fixed, W, p, mode, tick, n_sub, T, OUT[k], w, b)
