"""The sheath between each cable's FSR and the end effector, in one place: its parameters (`Sheath`), the
layout of its friction state, and the kernels of its law. The simulated robot applies the law (kernel
sim.cable_sensor, scenes.sim_robot), the estimators remove it (kernel estimate), the diagnosis catalogue's
capstan_friction fits it (teleop.core.physics.capstan); the benches read the same parameters.

The law (capstan friction with stick transitions; seed 000 eqs 3, 7; seed 001 eqs 4-7). x increasing = the
motor hauls its cable in (pulling); Theta [rad] is the cable's total wrap, its pose-dependent bend (eq 6) plus
theta0. While the cable slides the FSR-side (motor-side) force F sits on one of the lines t e^(+-mu Theta) of
the tip tension t; at a reversal the cable sticks and F travels between them at the stick stiffness k:
    F <- clamp(F + k dx, t e^-mu Theta, t e^+mu Theta)                    (`motor_force`, the forward law)
and at a cable's first sample F starts on the tip tension (`start_on_tip`). The inverse, for the `dynamic`
estimator, holds the same state as phi in [-1, 1], the FSR-side tension being t e^(phi mu Theta):
    phi <- clamp(phi + k dx / (mu Theta t_fsr), -1, 1),  t = t_fsr e^(-phi mu Theta)   (`tip_tension`)
phi = 0 at the first sample, the same start. The seed's own compensation (eq 7) is the law without stick:
t = t_fsr e^-mu Theta while pulling, e^+mu Theta while paying out (`hold_tension`).
The catalogue fits the forward law to a recorded drive (`capstan_rate_step`): there the direction is the sign
of the recording's rate (its convention, central or backward, the diagnosis's to pick), the travel still x's,
and a stick stiffness at the fit's upper bound is the instant switch, which no finite k reaches on samples.

Constants: a (N_CONST,) float64 array, `Sheath.constants()`, indices MU, THETA0, STICK_K, PRETENSION; a
kernel holding more constants keeps the sheath's at the head of its array.
State: a (N_STATE, n) float64 array, one column per cable, `new_state(n)`; rows
    X    motor position at the cable's last sample [m] (NaN: none yet)
    F    FSR-side force of the forward law [N]
    PHI  friction state of the inverse law, in [-1, 1]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from teleop.core.errors import InputError
from teleop.core.kernels.friction import clamp
from teleop.core.kernels.jit import njit

MU, THETA0, STICK_K, PRETENSION, N_CONST = range(5)
X, F, PHI, N_STATE = range(4)

#: Stick stiffness [N/m] of a sheath nothing is known of: the catalogue's capstan_friction default (where its
#: fits start). A stiff stick: the transitions take a quarter of the seed robot's travel (`Sheath.stick_k`),
#: blips the direction rule alone handles; still softer than the 30 mm of steel between FSR and effector.
STIFF_STICK_K = 2e4


@dataclass(frozen=True)
class Sheath:
    """The sheaths of the robot (every cable alike), SI. Defaults: the seed robot's.

    Attributes:
        mu: friction coefficient of the capstan law [-] (fitted to seed 000 Fig 9).
        theta0: scaffold bend of every cable, added to its pose-dependent wrap (eq 6) [rad] (seed 000 §3).
        stick_k: stick stiffness of the transitions at reversals [N/m]: the FSR tension crosses the friction
            band [t e^-mu Theta, t e^mu Theta] over band / k of cable travel. Seed 000 Fig 13 shows these
            transitions after single compensation as segments (EF, GH) long enough to be fitted by
            polynomials at its 0.5 mm/s, and §6 reports large shifts when the speed changes: a soft stick,
            the compliance of the FSR press block's silicone film (seed 000 §2) between FSR and effector.
        pretension: reference cable tension of the tension distribution [N]; seed 000 Fig 9 pre-tensions the
            cable with 1.96-2.94 N; 2.85 N is the middle of the [0.2, 5.5] N tension range.
    """

    mu: float = 0.056
    theta0: float = float(np.deg2rad(140.0))
    stick_k: float = 5e3
    pretension: float = 2.85

    def __post_init__(self):
        vals = (self.mu, self.theta0, self.stick_k, self.pretension)
        if not all(math.isfinite(v) and v >= 0 for v in vals):
            raise InputError(f"sheath: mu, theta0, stick_k and pretension must be finite and >= 0, got {vals}")

    def constants(self) -> np.ndarray:
        """(N_CONST,) float64: these parameters as the kernels read them."""
        c = np.empty(N_CONST)
        c[MU], c[THETA0], c[STICK_K], c[PRETENSION] = self.mu, self.theta0, self.stick_k, self.pretension
        return c


def new_state(n: int) -> np.ndarray:
    """(N_STATE, n) float64: n cables before their first sample."""
    st = np.zeros((N_STATE, n))
    st[X] = math.nan
    st[F] = math.nan
    return st


# ------------------------------------------------------------------ the law on floats (mu_theta = mu Theta)
@njit
def capstan_band(f, mu_theta):
    """(lo, hi): f e^-mu Theta and f e^+mu Theta [N], ordered (f may be negative)."""
    e = math.exp(mu_theta)
    a, b = f / e, f * e
    return (a, b) if a <= b else (b, a)


@njit
def capstan_band_loop(f, mu_theta, lo, hi):
    """capstan_band element-wise: lo, hi (n,) [N] for forces f (n,) [N] and mu Theta (n,) (1-D arrays of one
    length)."""
    for k in range(f.shape[0]):
        lo[k], hi[k] = capstan_band(f[k], mu_theta[k])


@njit
def capstan_play_step(f, dx, F_tip, mu_theta, k):
    """Motor force [N] after a motor travel dx [m] from f [N]: clamp(f + k dx) into the band of the tip force
    F_tip [N], k [N/m]."""
    lo, hi = capstan_band(F_tip, mu_theta)
    return clamp(f + k * dx, lo, hi)


@njit
def start_on_tip(F_tip, mu_theta, k):
    """Motor force [N] at a cable's first sample: it starts on the tip force F_tip, clamped into its band."""
    return capstan_play_step(F_tip, 0.0, F_tip, mu_theta, k)


@njit
def capstan_hold(t, pulling, mu_theta):
    """Tip tension [N] from the sensor tension t [N]: t e^-mu Theta while pulling, t e^+mu Theta releasing."""
    return t * math.exp(-mu_theta) if pulling else t * math.exp(mu_theta)


@njit
def capstan_state_step(phi, dx, t_sensor, mu_theta, k):
    """Friction state phi in [-1, 1] after a motor travel dx [m] at sensor tension t_sensor [N]: d phi =
    k dx / (mu Theta t_sensor), clipped at +-1 where the cable slips (a slack cable, t <= 1e-6 N, at once)."""
    den = mu_theta * (t_sensor if t_sensor > 1e-6 else 1e-6)
    return clamp(phi + k * dx / (den if den > 1e-12 else 1e-12), -1.0, 1.0)


@njit
def capstan_tip_step(F_tip, F_motor, mu_theta):
    """Tip force [N] estimated from the motor force with flat transitions: the tip force holds while it
    stays inside the band of the motor force, clamp(F_tip, F_m e^-mu Theta, F_m e^+mu Theta)."""
    lo, hi = capstan_band(F_motor, mu_theta)
    return clamp(F_tip, lo, hi)


@njit
def forward_step(x_prev, f, x, t_tip, mu_theta, k):
    """The forward law's sample: the FSR-side force [N] at motor position x [m] and tip tension t_tip [N]
    from the force f [N] at x_prev [m] (NaN: the cable's first sample, which starts on the tip tension)."""
    if x_prev != x_prev:
        return start_on_tip(t_tip, mu_theta, k)
    return capstan_play_step(f, x - x_prev, t_tip, mu_theta, k)


# ------------------------------------------------------------------ the law on a recorded drive (the catalogue's)
#: the catalogue's capstan_friction kernel: its constants are the sheath's, then PRELOAD [N], INSTANT [N/m]
#: (the stick stiffness from which on a reversal is a plain switch), STICK_N and STICK_SPREAD (the transitions'
#: exponent and spread, `stick_transition`); its state the sheath's rows, then T_PREV
PRELOAD, INSTANT, STICK_N, STICK_SPREAD, N_RATE_CONST = N_CONST, N_CONST + 1, N_CONST + 2, N_CONST + 3, N_CONST + 4
T_PREV, N_RATE_STATE = N_STATE, N_STATE + 1


@njit
def _band_part(z, a, up):
    """Part u in [0, 1] of the band [lo, hi] crossed at the friction coordinate z in [0, 1] (`stick_transition`)
    for the curve's ratio a >= 1 (a = sqrt(hi / lo) for Kaneko's): from lo (up) u = ((1 + (a - 1) z)^2 - 1) /
    (a^2 - 1), from hi u = (1 - (1 - (1 - 1/a) z)^2) / (1 - 1/a^2); u = z at a = 1."""
    if abs(a - 1.0) < 1e-9:
        return z
    if up:
        return ((1.0 + (a - 1.0) * z) ** 2 - 1.0) / (a * a - 1.0)
    b = 1.0 - 1.0 / a
    return (1.0 - (1.0 - b * z) ** 2) / (1.0 - 1.0 / (a * a))


@njit
def _band_coordinate(u, a, up):
    """The inverse of `_band_part`: z in [0, 1] for u in [0, 1]."""
    if abs(a - 1.0) < 1e-9:
        return u
    if up:
        return (math.sqrt(max(1.0 + u * (a * a - 1.0), 0.0)) - 1.0) / (a - 1.0)
    b = 1.0 - 1.0 / a
    return (1.0 - math.sqrt(max(1.0 - u * (1.0 - 1.0 / (a * a)), 0.0))) / b


@njit
def stick_transition(f, travel, s, lo, hi, k, n, spread=0.0):
    """Motor force [N] after a travel [m] (>= 0) in the direction s (+1, -1) from f [N] across the band
    [lo, hi] [N]: the part u of the band crossed from the line the cable left grows with the travel delta
    since it left it, rho = delta / delta_c, delta_c = (hi - lo) / k the travel across the whole band (k [N/m]
    the transition's mean stiffness), as u = B_a(rho^n), a = sqrt(hi / lo)^(2 (1 - n) spread).

    spread = 0 (a = 1, B the identity): the power law u = rho^n; n = 1 the linear stick (a lumped
    compliance), clamp(f + s k travel, lo, hi); n = 1/2 the square-root transition of a narrow band.
    spread = 1, n = 1/2: Coulomb friction spread uniformly along the sheath (Kaneko et al. 1991): after a
    reversal the tension changes over a zone growing from the proximal end, where the new and the old
    exponential profiles meet at the wrap phi_c with e^(2 phi_c) = the proximal tension's ratio to its start,
    and the motor travel is the cable's stretch change over that zone: from lo, delta ~ lo (sqrt(1 + r) - 1)^2
    (r the tension's rise over lo), from hi delta ~ hi (1 - sqrt(1 - r))^2; the whole band is crossed when the
    zone reaches the tip (phi_c = mu Theta), so with a = e^(mu Theta) = sqrt(hi / lo): sqrt(rho) = z,
    u = B_a(z) with B_a(z) = ((1 + (a - 1) z)^2 - 1) / (a^2 - 1) from lo and (1 - (1 - (1 - 1/a) z)^2) /
    (1 - 1/a^2) from hi (`_band_part`): steeper leaving the high line than the low one for a wide band.
    Between and beyond (spread > 1: more curved than a uniform friction's), continuous in n and spread (n = 1:
    the linear stick whatever the spread). Exact for any travel: rho advances by travel / delta_c."""
    if n == 1.0 or hi <= lo:
        return clamp(f + s * k * travel, lo, hi)
    band = hi - lo
    a = (hi / lo) ** ((1.0 - n) * spread) if lo > 0.0 and spread > 0.0 else 1.0
    up = s > 0.0
    u = clamp((f - lo) / band if up else (hi - f) / band, 0.0, 1.0)
    z = clamp(_band_coordinate(u, a, up), 0.0, 1.0)
    z = min(z ** (1.0 / n) + k * travel / band, 1.0) ** n
    u = clamp(_band_part(z, a, up), 0.0, 1.0)
    return lo + band * u if up else hi - band * u


@njit
def rate_play_step(f, dx, s, lead, F_tip, mu_theta, k, instant, n, spread):
    """Motor force [N] after a sample of a recorded drive: the forward law's clamp(f + k dx) into the band of
    the tip force F_tip [N], its direction taken from the drive's rate sign s (+1, -1; 0: at rest, f held
    in the band) rather than from the travel dx [m] since the last sample. They differ for a sample after a
    reversal the rate places inside the last interval (a central difference sees the turn half a sample
    before a backward one): then the travel since the turn is `lead` [m] (a fraction of |v| dt) in the new
    direction. k >= instant [N/m] is the limit of an instant switch: the band's side of s. The transition
    across the band: `stick_transition` of exponent n (1: linear) and spread."""
    lo, hi = capstan_band(F_tip, mu_theta)
    if s == 0.0:
        return clamp(f, lo, hi)
    if k >= instant:
        return hi if s > 0.0 else lo
    if dx * s <= 0.0:
        dx = s * lead
    return stick_transition(f, dx * s, s, lo, hi, k, n, spread)


@njit
def capstan_rate_step(st, u, c):
    """The catalogue's capstan_friction step: u = (t [s], x [m], v [m/s], load [N], theta [rad]) one sample of
    a recorded drive and its tip load; c (N_RATE_CONST,) the sheath's constants, PRELOAD, INSTANT, STICK_N,
    STICK_SPREAD; st (N_RATE_STATE,) one cable's state. Motor force [N] of the sheath's law (`rate_play_step`) on
    the tension load + preload, read from the preload. The first sample starts on the tip tension (at once on
    the side of the motion for an instant switch)."""
    t, x, v, load, theta = u[0], u[1], u[2], u[3], u[4]
    P = c[PRELOAD]
    mt = c[MU] * theta
    s = 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)
    if st[X] != st[X]:
        f = start_on_tip(load + P, mt, c[STICK_K])
        if c[STICK_K] >= c[INSTANT] and s != 0.0:
            f = rate_play_step(f, 0.0, s, 0.0, load + P, mt, c[STICK_K], c[INSTANT], c[STICK_N], c[STICK_SPREAD])
    else:
        lead = 0.125 * abs(v) * (t - st[T_PREV])   # a quadratic turn's travel since: |v| dt / 8 on average
        f = rate_play_step(st[F], x - st[X], s, lead, load + P, mt, c[STICK_K], c[INSTANT], c[STICK_N],
                           c[STICK_SPREAD])
    st[F], st[X], st[T_PREV] = f, x, t
    return f - P


@njit
def capstan_rate_run(st, U, c, out):
    """out (n,): capstan_rate_step along U (n, 5) from the state st."""
    for i in range(U.shape[0]):
        out[i] = capstan_rate_step(st, U[i], c)
    return out


# ------------------------------------------------------------------ per cable, on the state and constants
@njit
def motor_force(st, i, x, t_tip, theta, c):
    """The forward law: cable i's FSR-side force [N] at motor position x [m] and tip tension t_tip [N] over
    the wrap theta [rad]; st (N_STATE, n) its state (X, F updated), c the sheath's constants."""
    f = forward_step(st[X, i], st[F, i], x, t_tip, c[MU] * theta, c[STICK_K])
    st[F, i], st[X, i] = f, x
    return f


@njit
def motor_forces(st, x, t_tip, theta, c, out):
    """out (n,): motor_force of every cable at one sample, x, t_tip, theta (n,)."""
    for i in range(x.shape[0]):
        out[i] = motor_force(st, i, x[i], t_tip[i], theta[i], c)
    return out


@njit
def motor_force_run(x, t_tip, theta, c, st, i, out):
    """out (m,): motor_force of cable i along m samples x, t_tip, theta (m,), continuing from st[:, i]."""
    for j in range(x.shape[0]):
        out[j] = motor_force(st, i, x[j], t_tip[j], theta[j], c)
    return out


@njit
def tip_tension(st, i, dx, t, theta, c):
    """The inverse law: cable i's tip tension [N] from its FSR-side tension t [N] after a motor travel dx [m]
    (0 at its first sample) over the wrap theta [rad]; st[PHI, i] updated (X is the caller's to keep)."""
    mt = c[MU] * theta
    phi = capstan_state_step(st[PHI, i], dx, t, mt, c[STICK_K])
    st[PHI, i] = phi
    return t * math.exp(-phi * mt)


@njit
def tip_tensions(st, dx, t, theta, c, out):
    """out (n,): tip_tension of every cable at one sample, dx, t, theta (n,)."""
    for i in range(t.shape[0]):
        out[i] = tip_tension(st, i, dx[i], t[i], theta[i], c)
    return out


@njit
def hold_tension(t, pulling, theta, c):
    """The seed's compensation (eq 7): tip tension [N] from the FSR-side tension t [N] over the wrap theta
    [rad], the cable pulling or paying out (no stick)."""
    return capstan_hold(t, pulling, c[MU] * theta)


# ------------------------------------------------------------------ array form of the flat-transition inverse
@njit
def capstan_tip_run(F_motor, mu_theta, F0, out):
    """out (n,): tip force [N] from motor forces F_motor (n,) [N] with flat transitions, from F0."""
    f = F0
    for j in range(F_motor.shape[0]):
        f = capstan_tip_step(f, F_motor[j], mu_theta[j])
        out[j] = f
    return out
