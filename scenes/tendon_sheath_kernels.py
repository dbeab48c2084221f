"""Compiled step of the distributed tendon-sheath cable (scenes.tendon_sheath): one implicit step of c cables,
the per-tick step (all cables, sub-steps, input interpolation, the sensor taps) and the batch that calls that
step for each tick of a trajectory (one source for the loop and the batch: the loop's tick is one compiled
call for all cables and sub-steps).

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

Arrays of c cables (the TendonSheath's, written in place):
    S (S_ROWS, c, N+1)   rows S_U, S_V, S_Z: u, v, z; S_W0..S_W2 the bend weights; the rest the step's scratch
    cab (c, CAB_COLS)    columns C_T0 (t0 [N]), C_TIP (the last tick's tip input), C_THETA0, C_THETA1 (the
                         scaffold and route bends [rad]), C_X0, C_XS, C_TH_OFF (the inputs' map: motor travel
                         x0 + s x_in [m], kinematic bend |theta_in - offset| [rad]); from C_DU0 on the scratch
    p (P_COUNT + taps,)  the parameters, then the taps: p[P_ETAPS] indices of tapped elements, then the
                         indices of tapped nodes
    out (O_ROWS + taps, c)  a tick's motor force [N], tip load force [N], tip travel [m], Newton iterations,
                         then the tension [N] at each tap (a sensor there): an element's tension, or at a node
                         the tension between its two elements' (`node_tension`)
How the cables share a step: each iterates until its own convergence (a cable's numbers do not depend on the
others'), GROUP cables at a time through the same Newton sweeps, node by node, each one's carried values in
registers (`cables_step`: the CPU overlaps the group's chains of dependent operations; the numbers are those of
one cable after the other, operation for operation). A lockstep over all cables whose carried values went
through memory was slower.
Compiled with IEEE division (jit.njit ieee_division: no zero test per division in the Newton sweeps; every
divisor here is nonzero by construction, and a non-finite tension would reach the loop's finiteness checks).
"""

from __future__ import annotations

import math

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
P_MODE = 12  # MODE_SPRING or MODE_POSITION
P_TICK = 13  # the tick [s]
P_NSUB = 14  # implicit steps a tick [-]
P_ETAPS = 15  # how many of the taps after P_COUNT are elements (the rest are nodes)
P_COUNT = 16

MODE_SPRING = 0  # tip load F = k_load (u_N - rest) + f_ext, f_ext the tip input [N]
MODE_POSITION = 1  # tip travel prescribed, the tip input [m]; F the reaction

# rows of S: the state; the step's scratch (du, 1 / zs, the eliminated Jacobian's upper diagonal and
# right-hand side, the element bends b in the first N columns); the share of theta0, theta1 and |theta| in each
# element (first N columns; TendonSheathParams.bend_weights)
S_U, S_V, S_Z, S_DU, S_IZS, S_CP, S_R, S_B, S_W0, S_W1, S_W2 = range(11)
S_ROWS = 11
# columns of cab: t0, the last tick's tip input, the fixed bends, the motor input's map x = x0 + s x_in and
# the kinematic bend's offset; then the step's scratch per cable: motor travel over the step, the step's tip
# input, Newton iterations, motor force, tip load force, the tick's motor travel
C_T0, C_TIP, C_THETA0, C_THETA1, C_X0, C_XS, C_TH_OFF, C_DU0, C_A, C_IT, C_FM, C_FL, C_XT = range(13)
CAB_COLS = 13
# rows of out
O_MOTOR, O_TIP, O_X_TIP, O_ITER = range(4)
O_ROWS = 4


STRIBECK_SPAN = 7.5  # g(v) = mu_c past |v| = 7.5 v_s (the peak's share exp(-56) is below rounding)


@njit(ieee_division=True)
def stribeck_curve(v, mu_c, mu_s, v_s):
    """g(v) [-] at speed v [m/s]."""
    if mu_s == mu_c or v_s <= 0.0:
        return mu_c
    r = v / v_s
    if abs(r) > STRIBECK_SPAN:
        return mu_c
    return mu_c + (mu_s - mu_c) * math.exp(-r * r)


@njit(ieee_division=True)
def bristle(z, du, izs):
    """(z', dz'/du): the LuGre state after travel du [m] by backward Euler, izs = sigma0 / g = 1 / zs [1/m]
    (0: no friction)."""
    if izs <= 0.0:
        return 0.0, 0.0
    ia = 1.0 / (1.0 + abs(du) * izs)
    zn = (z + du) * ia
    if du > 0.0:
        dz = (1.0 - z * izs) * ia * ia
    elif du < 0.0:
        dz = (1.0 + z * izs) * ia * ia
    else:
        dz = 1.0
    return zn, dz


@njit(ieee_division=True)
def taut(t0, k, stretch):
    """(T, dT/dstretch) of an element [N, N/m]: t0 + k stretch, 0 when slack."""
    s = t0 + k * stretch
    if s > 0.0:
        return s, k
    return 0.0, 0.0


@njit(ieee_division=True)
def node_tension(Tl, Tr, bl, br):
    """Tension [N] at a node between its proximal and distal elements (tensions Tl, Tr [N], bends bl, br
    [rad]). The node's friction comes from the bends of its two half elements, so the tension there lies
    between Tl and Tr: Tr (Tl / Tr)^w, w = br / (bl + br), the capstan split of the node's friction by bend
    (Tr alone would have lost half of the distal element's bend); Tr with no bend on either side, 0 when
    the distal element is slack."""
    if bl + br <= 0.0:
        return Tr
    if not Tr > 0.0:
        return 0.0
    lo = max(Tr, 1e-12)
    hi = max(Tl, 1e-12)
    return lo * (hi / lo) ** (br / (bl + br))


@njit(ieee_division=True)
def node_tension_rows(T, j, bl, br, out):
    """out (m,) = node_tension of node j of each row of element tensions T (m, N) [N] with bends bl, br
    [rad] of elements j - 1 and j (node 0: T[:, 0])."""
    for r in range(T.shape[0]):
        out[r] = T[r, 0] if j == 0 else node_tension(T[r, j - 1], T[r, j], bl, br)


@njit(ieee_division=True)
def node_row(Tl, al, Tr, ar, bl, br, mi, x, zi, izs, vi, h, cf, s1h, s2h):
    """A node's residual R_i [N], its Jacobian's diagonal d [N/m] and friction coefficient phi [-] (without a
    tip load): tensions Tl, Tr [N] and stiffnesses al, ar [N/m] of the elements before and after it, their
    bends bl, br [rad], the node's inertia mi [N/m], step x = du_i [m], bristle state zi [m], 1 / zs izs
    [1/m], last step's velocity vi [m/s]."""
    zn, dz = bristle(zi, x, izs)
    phi = cf * zn - s1h * zi + s2h * x
    dphi = cf * max(dz, 0.0) + s2h
    n = 0.5 * (Tl * bl + Tr * br)  # normal force n'_i
    res = mi * (x - h * vi) - Tl + Tr + n * phi
    d = mi + al + ar + n * dphi + 0.5 * phi * (br * ar - bl * al)
    return res, d, phi


@njit(ieee_division=True)
def eliminate(res, d, phi, al, ar, bl, br, cp, rp):
    """The node's row eliminated against the row before it (Thomas algorithm, forward): (cp, rp) of this
    row from the last row's (cp, rp)."""
    lo = -al * (1.0 - 0.5 * phi * bl)
    iden = 1.0 / (d - lo * cp)
    return -ar * (1.0 + 0.5 * phi * br) * iden, (-res - lo * rp) * iden


@njit(ieee_division=True)
def kinked(x, dn):
    """The Newton step s [m] of a node at step x [m] whose solved delta is dn [m]: dn, or -x when dn would
    carry x across 0 (friction's kink: it stops on it)."""
    if (x > 0.0 and x + dn < 0.0) or (x < 0.0 and x + dn > 0.0):
        return -x
    return dn


GROUP = 3  # cables whose Newton sweeps run interleaved (independent chains of operations for the CPU to overlap)


@njit(ieee_division=True, inline=True)
def sweep_node(S, c, i, t0, k, Tl, al, cp, rp, mh, h, cf, s1h, s2h):
    """One interior node i of cable c in a forward sweep: (Tr, ar, cp, rp), the right element's tension and
    tautness carried to the next node and the elimination's running pair, also written to S."""
    Tr, ar = taut(t0, k, S[S_U, c, i] + S[S_DU, c, i] - S[S_U, c, i + 1] - S[S_DU, c, i + 1])
    bl, br = S[S_B, c, i - 1], S[S_B, c, i]
    res, d, phi = node_row(Tl, al, Tr, ar, bl, br, mh, S[S_DU, c, i], S[S_Z, c, i], S[S_IZS, c, i],
                           S[S_V, c, i], h, cf, s1h, s2h)
    cp, rp = eliminate(res, d, phi, al, ar, bl, br, cp, rp)
    S[S_CP, c, i] = cp
    S[S_R, c, i] = rp
    return Tr, ar, cp, rp


@njit(ieee_division=True, inline=True)
def back_node(S, c, i, dn, big):
    """One node i of cable c in a back substitution: (dn, big), its Newton update and the largest so far."""
    dn = S[S_R, c, i] - S[S_CP, c, i] * dn
    x = S[S_DU, c, i]
    s = kinked(x, dn)
    S[S_DU, c, i] = x + s
    return dn, max(big, abs(s))


@njit(ieee_division=True)
def cables_step(S, cab, p, h):
    """One backward-Euler step h [s] of every cable: cab[:, C_DU0] the motor's travel over the step [m],
    cab[:, C_A] f_ext [N] (MODE_SPRING) or the tip's travel over the step [m] (MODE_POSITION), S[S_B] the
    bends. Updates u, v, z in place; leaves the element tensions in S[S_R] (first N columns), the motor force
    and tip load force [N] in cab[:, C_FM], cab[:, C_FL] and adds the Newton iterations to cab[:, C_IT].

    A Newton iteration is two sweeps over the nodes: the first evaluates node i's tensions, friction and
    residual (`node_row`) and eliminates its row at once (Thomas algorithm, forward: `eliminate`), the second
    substitutes back and updates du (`kinked`). The Stribeck curve, fixed over the step, is evaluated once a
    node and step (as 1 / zs). After the last update one sweep takes the tensions and bristle states at the
    converged du.
    Each cable iterates until its own convergence (a cable's numbers do not depend on the others'). The cables
    go GROUP at a time through the same sweeps, node by node, each one's carried values in registers: a
    cable's sweep is one chain of dependent operations (a division a node), and the CPU overlaps the chains
    of the group's cables; a cable that has converged sits out its group's further iterations. The arrays are
    indexed in place (S[row, c, i]; no views: a view costs two reference count updates)."""
    nc = S.shape[1]
    N = S.shape[2] - 1
    k = p[P_K]
    kl = p[P_K_LOAD]
    rest = p[P_REST]
    s0 = p[P_SIGMA0]
    s1h = p[P_SIGMA1] / h
    s2h = p[P_SIGMA2] / h
    cf = s0 + s1h
    ih = 1.0 / h
    mh = p[P_M] / (h * h)  # an interior node's inertia per travel over the step [N/m]
    mt = 0.5 * mh  # the tip node's
    mu_c, mu_s, v_s = p[P_MU_C], p[P_MU_S], p[P_V_S]
    izs_c = s0 / mu_c if mu_c > 0.0 else 0.0
    v_peak = STRIBECK_SPAN * v_s  # past it g(v) = mu_c (stribeck_curve)
    tol = p[P_TOL]
    max_iter = int(p[P_ITER])
    spring = int(p[P_MODE]) == MODE_SPRING
    last = N if spring else N - 1
    for c in range(nc):
        S[S_DU, c, 0] = cab[c, C_DU0]
        if not spring:
            S[S_DU, c, N] = cab[c, C_A]
        for i in range(N + 1):
            vi = S[S_V, c, i]
            if 0 < i <= last:
                S[S_DU, c, i] = h * vi  # predictor: the last step's velocity
            # 1 / zs: sigma0 / mu_c past the Stribeck peak (no division there: most nodes, most steps)
            if abs(vi) > v_peak:
                S[S_IZS, c, i] = izs_c
            else:
                g = stribeck_curve(vi, mu_c, mu_s, v_s)
                S[S_IZS, c, i] = s0 / g if g > 0.0 else 0.0
    for c0 in range(0, nc, GROUP):
        # the group's cables (a missing one repeats the first and is never active)
        c1 = c0 + 1 if c0 + 1 < nc else c0
        c2 = c0 + 2 if c0 + 2 < nc else c0
        a0, a1, a2 = True, c0 + 1 < nc, c0 + 2 < nc
        t00, t01, t02 = cab[c0, C_T0], cab[c1, C_T0], cab[c2, C_T0]
        it0 = it1 = it2 = 0
        while a0 or a1 or a2:
            # forward sweeps: the first element's tension starts each
            Tl0, al0 = taut(t00, k, S[S_U, c0, 0] + S[S_DU, c0, 0] - S[S_U, c0, 1] - S[S_DU, c0, 1])
            Tl1, al1 = taut(t01, k, S[S_U, c1, 0] + S[S_DU, c1, 0] - S[S_U, c1, 1] - S[S_DU, c1, 1])
            Tl2, al2 = taut(t02, k, S[S_U, c2, 0] + S[S_DU, c2, 0] - S[S_U, c2, 1] - S[S_DU, c2, 1])
            cp0 = rp0 = cp1 = rp1 = cp2 = rp2 = 0.0
            for i in range(1, N):  # interior nodes
                if a0:
                    Tl0, al0, cp0, rp0 = sweep_node(S, c0, i, t00, k, Tl0, al0, cp0, rp0, mh, h, cf, s1h, s2h)
                if a1:
                    Tl1, al1, cp1, rp1 = sweep_node(S, c1, i, t01, k, Tl1, al1, cp1, rp1, mh, h, cf, s1h, s2h)
                if a2:
                    Tl2, al2, cp2, rp2 = sweep_node(S, c2, i, t02, k, Tl2, al2, cp2, rp2, mh, h, cf, s1h, s2h)
            if spring:  # the tip node, the load on it: k_load (u_N - rest) + f_ext
                for c, a, Tl, al in ((c0, a0, Tl0, al0), (c1, a1, Tl1, al1), (c2, a2, Tl2, al2)):
                    if a:
                        x = S[S_DU, c, N]
                        res, d, phi = node_row(Tl, al, 0.0, 0.0, S[S_B, c, N - 1], 0.0, mt, x, S[S_Z, c, N],
                                               S[S_IZS, c, N], S[S_V, c, N], h, cf, s1h, s2h)
                        res += kl * (S[S_U, c, N] + x - rest) + cab[c, C_A]
                        d += kl
                        cp = S[S_CP, c, N - 1]
                        rp = S[S_R, c, N - 1]
                        cp, rp = eliminate(res, d, phi, al, 0.0, S[S_B, c, N - 1], 0.0, cp, rp)
                        S[S_CP, c, N] = cp
                        S[S_R, c, N] = rp
            # back substitutions (the ends' travel is known: their delta is 0)
            dn0 = dn1 = dn2 = big0 = big1 = big2 = 0.0
            for i in range(last, 0, -1):
                if a0:
                    dn0, big0 = back_node(S, c0, i, dn0, big0)
                if a1:
                    dn1, big1 = back_node(S, c1, i, dn1, big1)
                if a2:
                    dn2, big2 = back_node(S, c2, i, dn2, big2)
            if a0:
                it0 += 1
                a0 = not (big0 < tol or it0 >= max_iter)
            if a1:
                it1 += 1
                a1 = not (big1 < tol or it1 >= max_iter)
            if a2:
                it2 += 1
                a2 = not (big2 < tol or it2 >= max_iter)
        cab[c0, C_IT] += it0
        if c1 != c0:
            cab[c1, C_IT] += it1
        if c2 != c0:
            cab[c2, C_IT] += it2
    for c in range(nc):
        # the converged step: tensions, friction of the motor node (it adds to the motor's force: the proximal
        # gauge between motor and sheath) and of the tip node (the reaction of a held tip), the state
        t0 = cab[c, C_T0]
        for j in range(N):
            S[S_R, c, j] = taut(t0, k, S[S_U, c, j] + S[S_DU, c, j] - S[S_U, c, j + 1] - S[S_DU, c, j + 1])[0]
        du0, zm = S[S_DU, c, 0], S[S_Z, c, 0]
        z0 = bristle(zm, du0, S[S_IZS, c, 0])[0]
        cab[c, C_FM] = S[S_R, c, 0] * (1.0 + 0.5 * S[S_B, c, 0] * (cf * z0 - s1h * zm + s2h * du0))
        duN, zN = S[S_DU, c, N], S[S_Z, c, N]
        if spring:
            cab[c, C_FL] = kl * (S[S_U, c, N] + duN - rest) + cab[c, C_A]
        else:
            zt = bristle(zN, duN, S[S_IZS, c, N])[0]
            phiN = cf * zt - s1h * zN + s2h * duN
            Tt = S[S_R, c, N - 1]
            cab[c, C_FL] = Tt - 0.5 * Tt * S[S_B, c, N - 1] * phiN - 0.5 * mh * (duN - h * S[S_V, c, N])
        for i in range(N + 1):
            x = S[S_DU, c, i]
            S[S_Z, c, i] = bristle(S[S_Z, c, i], x, S[S_IZS, c, i])[0]
            S[S_V, c, i] = x * ih
            S[S_U, c, i] += x


@njit(ieee_division=True)
def step(S, cab, p, x_in, tip_in, theta_in, T, out):
    """One tick of c cables, one call: x_in (c,) the motor input, motor travel x = x0 + s x_in [m] at the
    tick's end (cab's C_X0, C_XS); tip_in (c,) f_ext [N] or tip travel [m] at the tick's end (by p[P_MODE]);
    theta_in (c,) kinematic bend theta_in - cab[C_TH_OFF] [rad] (abs taken); the tick p[P_TICK] [s] in
    p[P_NSUB] steps, the motor and tip inputs interpolated linearly. Writes T (c, N) element tensions [N] and
    out (O_ROWS + taps, c): motor force [N], tip load force [N], tip travel [m], Newton iterations of the tick,
    then the tension [N] at each tap (p[P_COUNT:]: p[P_ETAPS] elements, then nodes, `node_tension` with the
    tick's bends)."""
    nc = S.shape[1]
    N = S.shape[2] - 1
    n_sub = int(p[P_NSUB])
    h = p[P_TICK] / n_sub
    spring = int(p[P_MODE]) == MODE_SPRING
    u, b, W0, W1, W2 = S[S_U], S[S_B], S[S_W0], S[S_W1], S[S_W2]
    for c in range(nc):
        a = abs(theta_in[c] - cab[c, C_TH_OFF])
        t0, t1 = cab[c, C_THETA0], cab[c, C_THETA1]
        for j in range(N):
            b[c, j] = W0[c, j] * t0 + W1[c, j] * t1 + W2[c, j] * a
        cab[c, C_IT] = 0.0
        cab[c, C_XT] = cab[c, C_X0] + cab[c, C_XS] * x_in[c]
    for s in range(n_sub):
        for c in range(nc):
            cab[c, C_DU0] = (cab[c, C_XT] - u[c, 0]) / (n_sub - s)
            if spring:
                cab[c, C_A] = cab[c, C_TIP] + (tip_in[c] - cab[c, C_TIP]) * (s + 1) / n_sub
            else:
                cab[c, C_A] = (tip_in[c] - u[c, N]) / (n_sub - s)
        cables_step(S, cab, p, h)
    R = S[S_R]
    n_etaps = int(p[P_ETAPS])
    for c in range(nc):
        cab[c, C_TIP] = tip_in[c]
        for j in range(N):
            T[c, j] = R[c, j]
        out[O_MOTOR, c] = cab[c, C_FM]
        out[O_TIP, c] = cab[c, C_FL]
        out[O_X_TIP, c] = u[c, N]
        out[O_ITER, c] = cab[c, C_IT]
        for q in range(out.shape[0] - O_ROWS):
            j = int(p[P_COUNT + q])
            if q < n_etaps or j == 0:
                out[O_ROWS + q, c] = R[c, j]
            else:
                out[O_ROWS + q, c] = node_tension(R[c, j - 1], R[c, j], b[c, j - 1], b[c, j])


@njit(ieee_division=True)
def run(S, cab, p, X, TIP, THETA, OUT, TT):
    """`step` for each tick m of X, TIP, THETA (m, c): OUT (m, O_ROWS + taps, c); TT (m, c, N) the element
    tensions of every tick, or (1, c, N) to keep the last tick's only."""
    keep = TT.shape[0] == X.shape[0]
    for m in range(X.shape[0]):
        step(S, cab, p, X[m], TIP[m], THETA[m], TT[m] if keep else TT[0], OUT[m])
