"""Cable-pulley transmission (seed 002, Xue et al. 2017): tension lost over a chain of pulleys and the
cable's elastic elongation, with stick transitions at reversals.

Seed 002 in the project holds only its abstract, introduction and nomenclature (wrap angle theta, cable
and pulley radii, friction between cable, pulley and shaft, bending rigidity, elongation dL = T d / (E A));
the model below is built from those quantities and says where it simplifies:

- friction at pulley i (wrap angle theta_i, equivalent friction coefficient mu_i): the moving cable's
  tension grows towards the side that drives it by K_i = exp(mu_i theta_i). Shaft (bearing) friction is
  proportional to the axle load 2 T sin(theta_i / 2), hence to T, and is folded into mu_i.
- bending rigidity: bending the cable onto radius R_i and straightening it again takes the moment
  M = EI / R_i; a stranded cable's internal friction keeps most of that work, so each unit length drawn
  over the pulley loses about EI / R_i^2 of tension: B_i = EI / R_i^2 [N], load-independent. (EI is the
  dissipative bending rigidity [N m^2]; an upper bound for a cable that bends elastically.)
- one pulley, pulling (the motor side drives, x increasing): T_out = K_i T_in + B_i; releasing (the load
  drives): T_out = max((T_in - B_i) / K_i, 0), T_in the tip-side tension, T_out the motor side.
  The chain applies this pulley by pulley from the tip to the motor; the motor force lies between the
  releasing line lo(T_tip) and the pulling line hi(T_tip).
- reversals: the cable sticks on the pulleys and the motor force travels between the lines with the cable
  stretch, F_m <- clamp(F_m + k dx, lo, hi), k the stick stiffness [N/m] (the capstan law's transition,
  teleop.core.physics.capstan; kernel effects.driven_play).
- elongation: segment j (length d_j [m], tension T_j) stretches by T_j d_j / EA; the tip position is
  x - sum_j T_j d_j / EA. During a transition the segment tensions are interpolated between their
  releasing and pulling profiles by where the motor force sits in its band.

Array functions take a `PulleyChain`; the catalogue effects (`pulley_friction`: force link, x and load ->
motor force; `pulley_elongation`: position link, x and load -> tip position) are its lumped one-pulley
form, whose parameters a recording can identify: mu and wrap only as the product mu wrap (fix one),
bend = sum_i B_i, and c = L / EA the cable's compliance (the lumped pulley sits mid-cable, so the mean
segment tension (T_tip + F_m) / 2 stretches the whole length). Their physics is one step kernel each
(teleop.core.kernels.effects), the array forms the catalogue's driver loop over it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from teleop.core.kernels.effects import driven_play_run, driven_play_step, pulley_elongation_run, \
    pulley_elongation_step, pulley_friction_run, pulley_friction_step
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, kernel_call, register

DRIVEN_PLAY = Kernel(driven_play_step, driven_play_run, state=(math.nan, 0.0))


@dataclass(frozen=True)
class Pulley:
    """One pulley: wrap angle theta [rad], radius R [m], equivalent friction coefficient mu [-] (cable and
    shaft), span d [m] of free cable from this pulley towards the motor (its segment's length)."""

    theta: float
    R: float
    mu: float
    d: float = 0.0

    def __post_init__(self):
        if not (self.theta >= 0 and self.R > 0 and self.mu >= 0 and self.d >= 0):
            raise ValueError(f"pulley: theta, mu, d must be >= 0 and R > 0, got {self}")


@dataclass(frozen=True)
class PulleyChain:
    """Pulleys from the tip to the motor, the cable's dissipative bending rigidity EI [N m^2], axial
    stiffness EA [N], and the tip segment's length d_tip [m] (from the load to the first pulley)."""

    pulleys: tuple
    EI: float = 0.0
    EA: float = math.inf
    d_tip: float = 0.0

    @property
    def K(self) -> np.ndarray:
        """(p,) tension ratio exp(mu_i theta_i) per pulley."""
        return np.array([math.exp(p.mu * p.theta) for p in self.pulleys])

    @property
    def B(self) -> np.ndarray:
        """(p,) bending loss EI / R_i^2 per pulley [N]."""
        return np.array([self.EI / p.R ** 2 for p in self.pulleys])

    @property
    def spans(self) -> np.ndarray:
        """(p + 1,) segment lengths [m], tip segment first."""
        return np.array([self.d_tip] + [p.d for p in self.pulleys])


def pulley_out(T_in, K, B, pulling):
    """Motor-side tension [N] after one pulley from the tip-side tension T_in [N] (broadcasts):
    K T_in + B pulling, max((T_in - B) / K, 0) releasing."""
    T_in = np.asarray(T_in, dtype=float)
    return np.where(pulling, K * T_in + B, np.maximum((T_in - B) / K, 0.0))


def chain_tensions(T_tip, K, B, pulling) -> np.ndarray:
    """(p + 1, n) segment tensions [N], tip segment first, over pulleys of tension ratios K and bending losses
    B [N] (p rows each, tip side first; a row a scalar or (n,): a pulley whose wrap changes sample by sample),
    for tip tension T_tip (n,) and the direction `pulling` (bool, scalar or (n,)): the last row is the motor
    force."""
    T = np.atleast_1d(np.asarray(T_tip, dtype=float))
    rows = [T]
    for k, b in zip(K, B):
        rows.append(pulley_out(rows[-1], k, b, pulling))
    return np.vstack(rows)


def segment_tensions(T_tip, chain: PulleyChain, pulling) -> np.ndarray:
    """(p + 1, n) tensions [N] of the segments, tip segment first, for tip tension T_tip (n,) and the
    direction `pulling` (bool, scalar or (n,)): the last row is the motor force (`chain_tensions`)."""
    return chain_tensions(T_tip, chain.K, chain.B, pulling)


def pulley_band(T_tip, chain: PulleyChain) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi): the releasing and pulling lines of the motor force [N] for tip tension T_tip [N]."""
    return segment_tensions(T_tip, chain, False)[-1], segment_tensions(T_tip, chain, True)[-1]


def pulley_motor_force(x, T_tip, chain: PulleyChain, k: float, F0: float | None = None) -> np.ndarray:
    """(n,) motor force [N] for motor position x (n,) [m] and tip tension T_tip (n,) [N] with stick
    transitions of stiffness k [N/m]: F_k = clamp(F_k-1 + k (x_k - x_k-1), lo_k, hi_k), F0 default T_tip[0]
    clamped into its band (kernel effects.driven_play)."""
    x = np.asarray(x, dtype=float)
    T = np.broadcast_to(np.asarray(T_tip, dtype=float), x.shape)
    lo, hi = pulley_band(T, chain)
    start = T if F0 is None else np.full(x.shape, float(F0))
    return kernel_call(DRIVEN_PLAY, (k,), x, start, lo, hi)


def pulley_elongation(F_motor, T_tip, chain: PulleyChain) -> np.ndarray:
    """(n,) cable stretch [m] between motor and tip: sum_j T_j d_j / EA, the segment tensions T_j
    interpolated between their releasing and pulling profiles by the motor force's place in its band."""
    T = np.atleast_1d(np.asarray(T_tip, dtype=float))
    if not math.isfinite(chain.EA):
        return np.zeros(T.shape)
    return band_stretch(F_motor, segment_tensions(T, chain, False), segment_tensions(T, chain, True),
                        chain.spans, chain.EA)


def band_segments(F_motor, rel: np.ndarray, pull: np.ndarray) -> np.ndarray:
    """(p + 1, n) segment tensions [N] while the motor force F_motor (n,) [N] sits in its band: the releasing
    and pulling profiles rel, pull ((p + 1, n), `chain_tensions`) interpolated by where F_motor sits between
    their last rows (the middle for an empty band)."""
    width = pull[-1] - rel[-1]
    s = np.where(width > 0, (np.asarray(F_motor, dtype=float) - rel[-1]) / np.where(width > 0, width, 1.0), 0.5)
    return rel + np.clip(s, 0.0, 1.0) * (pull - rel)


def segment_stretch(seg: np.ndarray, spans, EA: float) -> np.ndarray:
    """Cable stretch [m] sum_j T_j d_j / EA of segment tensions seg ((p + 1, ...) [N], tip segment first), spans
    d_j (p + 1,) [m], EA [N]; the shape of seg without its first axis."""
    return np.tensordot(np.asarray(spans, dtype=float), seg, axes=1) / EA


def band_stretch(F_motor, rel: np.ndarray, pull: np.ndarray, spans, EA: float) -> np.ndarray:
    """(n,) cable stretch [m] (`segment_stretch`) of the segments of `band_segments`."""
    return segment_stretch(band_segments(F_motor, rel, pull), spans, EA)


def tangent(c1, rho1: float, c2, rho2: float) -> tuple[np.ndarray, np.ndarray]:
    """(p1, p2): where the free cable leaves circle 1 (centre c1 [m], signed radius rho1 [m]) and meets
    circle 2, travelling from 1 to 2. A positive radius puts the centre left of the travel (the cable turns
    counter-clockwise round it), a negative one right, zero is a point. Raises ValueError when no such
    tangent exists (circles too close)."""
    c1, c2 = np.asarray(c1, dtype=float), np.asarray(c2, dtype=float)
    D = c2 - c1
    d = float(np.hypot(*D))
    a = (rho1 - rho2) / d if d > 0 else math.inf
    if not abs(a) < 1.0:
        raise ValueError(f"pulley layout: no free cable between centres {c1} and {c2} (radii {rho1}, {rho2})")
    Dh = D / d
    Dp = np.array([-Dh[1], Dh[0]])
    n = a * Dh - math.sqrt(1.0 - a * a) * Dp        # right-hand normal of the travel
    return c1 + rho1 * n, c2 + rho2 * n


def chain_from_layout(points, mu, EI: float = 0.0, EA: float = math.inf) -> PulleyChain:
    """The chain from the pulleys' places (seed 002: the spatial location of the pulleys sets each wrap
    angle and span). points: (p + 2) rows (x [m], y [m], rho [m]) from the tip anchor to the motor exit,
    rho the signed radius (`tangent`; 0 for the two end points); mu: (p,) friction coefficients [-] or one.
    Each pulley's wrap theta_i is the turn of the cable's direction round it; its span d_i the free cable
    to the next place. The arcs on the pulleys are not counted in the spans. Planar layout only: the
    out-of-plane deviation angle between pulleys (seed 002 alpha_i) is not modelled."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 3 or pts[0, 2] != 0 or pts[-1, 2] != 0:
        raise ValueError("pulley layout: expected (p + 2) rows of (x, y, rho), rho 0 at both ends, p >= 1")
    mus = np.broadcast_to(np.asarray(mu, dtype=float), (pts.shape[0] - 2,))
    legs = [tangent(pts[j, :2], pts[j, 2], pts[j + 1, :2], pts[j + 1, 2]) for j in range(pts.shape[0] - 1)]
    spans = [float(np.hypot(*(b - a))) for a, b in legs]
    pulleys = []
    for i in range(1, pts.shape[0] - 1):
        u_in = legs[i - 1][1] - legs[i - 1][0]
        u_out = legs[i][1] - legs[i][0]
        turn = math.atan2(u_in[0] * u_out[1] - u_in[1] * u_out[0], float(np.dot(u_in, u_out)))
        theta = (math.copysign(1.0, pts[i, 2]) * turn) % (2 * math.pi)
        pulleys.append(Pulley(theta=theta, R=abs(float(pts[i, 2])), mu=float(mus[i - 1]), d=spans[i]))
    return PulleyChain(tuple(pulleys), EI=EI, EA=EA, d_tip=spans[0])


def lumped_chain(p: Mapping[str, float]) -> PulleyChain:
    """The catalogue effects' one-pulley chain: wrap, mu, bend (= EI / R^2 with R = 1 m)."""
    return PulleyChain((Pulley(theta=p["wrap"], R=1.0, mu=p["mu"]),), EI=p["bend"])


# ---- catalogue effects ------------------------------------------------------------------------------------

def _friction_guess(s: Signals, y: np.ndarray) -> dict:
    wrap = PARAMS_F[1].default
    pull = s.v > 0.2 * np.percentile(np.abs(s.v), 90)
    if pull.sum() > 5 and np.ptp(s.load[pull]) > 0:
        K, B = np.polyfit(s.load[pull], y[pull], 1)      # pulling line F_m = K T + B
    else:
        K, B = math.exp(PARAMS_F[0].default * wrap), 0.0
    mu = math.log(max(K, 1.0 + 1e-6)) / wrap
    dx, dF = np.diff(s.x), np.diff(y)
    moving = np.abs(dx) > 1e-12
    k = float(np.percentile(np.abs(dF[moving] / dx[moving]), 95)) if moving.sum() > 10 else PARAMS_F[3].default
    return {"mu": mu, "wrap": wrap, "bend": max(float(B), 0.0), "k": k}


PARAMS_F = (
    ParamSpec("mu", "1", 0.0, 1.5, 0.1, "equivalent cable-pulley friction coefficient (shaft friction folded in)"),
    ParamSpec("wrap", "rad", 0.0, 8 * np.pi, np.pi,
              "total wrap angle of the cable over the pulleys (mu and wrap are identifiable only as a "
              "product: fix one when fitting)"),
    ParamSpec("bend", "N", 0.0, 50.0, 0.05, "bending-rigidity loss summed over the pulleys, sum EI / R_i^2"),
    ParamSpec("k", "N/m", 1.0, 1e8, 2e4, "stick stiffness during reversals (motor force per motor travel)",
              log=True),
)


def _hold_wrap(rec, known, direction) -> dict:
    """mu and the wrap: only their product shows."""
    return {"wrap": PARAMS_F[1].default}


PULLEY_FRICTION = register(Effect(
    name="pulley_friction",
    link="force",
    doc="motor force from tip load over pulleys (seed 002): exp(mu wrap) T + bend pulling, "
        "(T - bend) exp(-mu wrap) releasing, stick transitions of stiffness k",
    params=PARAMS_F,
    inputs=("x", "load"),
    output="load",
    guess=_friction_guess,
    kernel=Kernel(pulley_friction_step, pulley_friction_run, state=(math.nan, 0.0)),
    # on force data alone the capstan law plus a constant bending loss: beside a capstan baseline it would
    # rename a Coulomb friction, not find the pulleys
    rules=Rules(channel="motor_force", primary=("mu",), not_beside=("capstan_friction",), hold=_hold_wrap),
))


def _elong_guess(s: Signals, y: np.ndarray) -> dict:
    g = _friction_guess(s, s.load)   # no motor force here: the friction starts at its defaults
    g.update(mu=PARAMS_E[1].default, bend=PARAMS_E[3].default)
    e = s.x - y
    c = float(np.dot(s.load, e) / max(np.dot(s.load, s.load), 1e-300))
    return {**g, "c": c if c > 0 else PARAMS_E[0].default}


PARAMS_E = (ParamSpec("c", "m/N", 1e-9, 1e-1, 2e-5, "cable compliance L / (E A) between motor and tip",
                      log=True, positive=True),) + PARAMS_F


PULLEY_ELONGATION = register(Effect(
    name="pulley_elongation",
    link="position",
    doc="tip position after the cable's elastic elongation over pulleys (seed 002): "
        "x - c (T_tip + F_motor) / 2, F_motor from pulley_friction",
    params=PARAMS_E,
    inputs=("x", "load"),
    output="x",
    guess=_elong_guess,
    kernel=Kernel(pulley_elongation_step, pulley_elongation_run, state=(math.nan, 0.0)),
    rules=Rules(channel="tip_pos", primary=("c",), hold=_hold_wrap),
))
