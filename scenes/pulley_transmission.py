"""Seed 002's cable-pulley chain as every cable's transmission of the simulated robot (`sim://robot?plant=pulley`,
`SimRobotParams.pulley`), in place of the lumped sheath between the tension sensor and the end effector.

Each cable runs from the end effector over a guide pulley (the turn where the cable leaves the scaffold: its
wrap is the cable's pose-dependent capstan wrap Theta = theta (eq 6) + theta0, the wrap the lumped sheath
takes) and then over the instrument's pulleys, placed by a planar layout (`PulleyTransmissionParams.layout`,
teleop.core.physics.pulley.chain_from_layout: each wrap and span from where the pulleys sit), to its motor.
The chain's physics is teleop.core.physics.pulley's (one home): per pulley the capstan ratio K_i =
exp(mu_i theta_i) and the bending loss EI / R_i^2 (`chain_tensions`), the motor force dragged across its band
[releasing line, pulling line] by the motor travel at the stick stiffness k with lost motion (kernel
effects.driven_play), the segment tensions from the force's place in its band (`band_segments`) and the
cable's stretch sum_j T_j d_j / EA (`segment_stretch`).

Per reading (`step`) and along a run (`run`), as scenes.sim_robot.DistributedCables: the motor position is the
haul-in x = L_home - L of the cable length L; the tip carries the tension of the tension distribution t_tip
(A t + f = 0); returned are the tensions at the FSR (by default right after the guide, where the lumped
sheath's FSR reads: the instrument's pulleys lie between it and the motor), at the FBG (the tip segment, before
the guide: the tip tension) and at the motor [N].
`x_tip` holds the tip's travel [m] after the last call: x minus the cable's stretch, measured from the
uniform stretch of the first sample's tip tension (T L / EA; a frictionless cable's tip then travels with its
motor). The robot's pose still follows the commanded (or played) lengths; the stretch is not fed back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from teleop.core.config import check_keys, get_integer, get_number, load_toml_table
from teleop.core.errors import InputError
from teleop.core.kernels.effects import driven_play, driven_play_run
from teleop.core.physics.pulley import PulleyChain, band_segments, chain_from_layout, chain_tensions, \
    segment_stretch

#: the project's instrument (teleop bench pulley): pulley places from the tip anchor to the motor exit,
#: x [m] along the shaft, y [m], signed radius [m] (teleop.core.physics.pulley.tangent): a wrist (two 1.5 mm
#: idlers), a 400 mm shaft and a 4 mm idler turning the cable to the motor capstan. Project layout: seed 002
#: places its pulleys in a figure the project's copy does not hold.
INSTRUMENT_LAYOUT = ((0.0, 0.0, 0.0),
                     (-0.006, 0.0030, 0.0015),
                     (-0.010, 0.0010, -0.0015),
                     (-0.400, 0.0065, -0.0040),
                     (-0.4065, 0.040, 0.0))


@dataclass(frozen=True)
class PulleyTransmissionParams:
    """One cable's pulley chain (SI). Defaults: the project's instrument (teleop bench pulley prints them
    with their sources).

    Attributes:
        layout: pulley places (x, y, rho) [m] from the guide's exit (the tip anchor, rho 0) to the motor exit
            (rho 0), rho the signed radius; () for no instrument pulleys (the guide alone, the motor at its exit).
        mu: equivalent friction coefficient of every instrument pulley [-] (cable and shaft), or one per pulley
            (project assumption 0.10: steel cable on steel pulleys).
        EI: the cable's dissipative bending rigidity [N m^2] (project estimate 1e-6: 7x19 steel cable 0.45 mm,
            wires bending independently).
        EA: the cable's axial stiffness [N] (project estimate 9.5e3: the same cable).
        guide_R: the guide pulley's radius [m] (its bending loss EI / guide_R^2).
        guide_mu: the guide's friction coefficient [-]; None: the robot's sheath mu (its capstan law's).
        tip_span: free cable from the end effector to the guide [m] (the robot's cable lengths, ~25 mm).
        stick_k: stick stiffness of the reversals [N/m]; None: the cable's EA / L over the chain's length.
        sensor_after: pulleys between the tip and the FSR, the guide counted; None: all (the motor end).
            Default 1: the FSR right after the guide, where the lumped sheath's and the distributed cable's FSR
            sit (at B: the scaffold's turn between it and the tip, the route between it and the motor).
    """

    layout: tuple = INSTRUMENT_LAYOUT
    mu: float | tuple = 0.10
    EI: float = 1.0e-6
    EA: float = 9.5e3
    guide_R: float = 0.002
    guide_mu: float | None = None
    tip_span: float = 0.025
    stick_k: float | None = None
    sensor_after: int | None = 1

    def __post_init__(self):
        nums = {"EI": self.EI, "EA": self.EA, "guide_R": self.guide_R, "tip_span": self.tip_span}
        bad = [k for k, v in nums.items() if not (math.isfinite(v) and v >= 0)]
        if bad or self.EA <= 0 or self.guide_R <= 0:
            raise InputError(f"pulley transmission: EI, tip_span >= 0 and EA, guide_R > 0 (finite) expected, got "
                             f"{nums}")
        if self.guide_mu is not None and not (math.isfinite(self.guide_mu) and self.guide_mu >= 0):
            raise InputError(f"pulley transmission: guide_mu must be >= 0, got {self.guide_mu}")
        if self.stick_k is not None and not (math.isfinite(self.stick_k) and self.stick_k > 0):
            raise InputError(f"pulley transmission: stick_k must be > 0, got {self.stick_k}")
        mus = np.atleast_1d(np.asarray(self.mu, dtype=float))
        if not (np.isfinite(mus).all() and (mus >= 0).all()):
            raise InputError(f"pulley transmission: mu must be >= 0, got {self.mu}")
        p = self.chain().pulleys
        if self.sensor_after is not None and not 0 <= self.sensor_after <= len(p) + 1:
            raise InputError(f"pulley transmission: sensor_after must be in [0, {len(p) + 1}] (pulleys between tip "
                             f"and FSR, the guide counted), got {self.sensor_after}")

    def chain(self) -> PulleyChain:
        """The instrument's pulleys (no guide) as a PulleyChain; InputError for a layout with no free cable."""
        if len(self.layout) == 0:
            return PulleyChain((), EI=self.EI, EA=self.EA, d_tip=0.0)
        pts = np.asarray(self.layout, dtype=float)
        mus = np.atleast_1d(np.asarray(self.mu, dtype=float))
        if mus.size not in (1, max(pts.shape[0] - 2, 1)) or pts.ndim != 2:
            raise InputError(f"pulley transmission: mu must be one value or one per pulley of the layout, got "
                             f"{self.mu}")
        try:
            return chain_from_layout(pts, mus if mus.size > 1 else float(mus[0]), EI=self.EI, EA=self.EA)
        except ValueError as exc:
            raise InputError(f"pulley transmission: {exc}") from None

    @classmethod
    def from_dict(cls, d: dict, where: str = "pulley transmission") -> "PulleyTransmissionParams":
        """From a table with units in the keys (TOML_KEYS); unknown keys or wrong types raise InputError."""
        check_keys(d, TOML_KEYS, where)
        kw = {}
        for key, value in d.items():
            name = TOML_KEYS[key]
            if name == "layout":
                ok = isinstance(value, list) and all(isinstance(r, list) and len(r) == 3 and all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) for v in r) for r in value)
                if not ok:
                    raise InputError(f"{where}: {key} must be a list of [x, y, rho] rows in m, got {value!r}")
                kw[name] = tuple(tuple(float(v) for v in r) for r in value)
            elif name == "mu" and isinstance(value, list):
                if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
                    raise InputError(f"{where}: {key} must be a number or a list of numbers, got {value!r}")
                kw[name] = tuple(float(v) for v in value)
            elif name == "sensor_after":
                kw[name] = get_integer(d, key, where)
            else:
                kw[name] = get_number(d, key, where)
        try:
            return cls(**kw)
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None

    @classmethod
    def from_toml(cls, path, table: str = "pulley_transmission") -> "PulleyTransmissionParams":
        """From the table `table` of a TOML file (keys as `from_dict`; docs/formats.md)."""
        values, where = load_toml_table(path, table)
        return cls.from_dict(values, where=where)


#: TOML key -> field (units in the key)
TOML_KEYS = {"layout_m": "layout", "mu": "mu", "EI_N_m2": "EI", "EA_N": "EA", "guide_radius_m": "guide_R",
             "guide_mu": "guide_mu", "tip_span_m": "tip_span", "stick_k_N_per_m": "stick_k",
             "sensor_after": "sensor_after"}


@dataclass(frozen=True)
class PulleyTrace:
    """`PulleyTransmission.travel` over m readings, (m, n) each: tensions at the FSR, the FBG (tip segment) and
    the motor [N], the tip's travel [m] (module docstring)."""

    t_fsr: np.ndarray
    t_fbg: np.ndarray
    t_motor: np.ndarray
    x_tip: np.ndarray


class PulleyTransmission:
    """n cables, each over the guide and the instrument's pulleys (module docstring); the same `step` / `run`
    interface as scenes.sim_robot.DistributedCables.

    Args:
        params: the chain (PulleyTransmissionParams).
        n: number of cables.
        L_home: cable lengths [m] (scalar or (n,)) at which the motor position x = L_home - L is 0.
        sheath_mu: the guide's friction coefficient when params.guide_mu is None (the robot's sheath mu).
    """

    def __init__(self, params: PulleyTransmissionParams, n: int, L_home=0.0, sheath_mu: float = 0.0):
        self.params = params
        chain = params.chain()
        self.mu_guide = float(sheath_mu if params.guide_mu is None else params.guide_mu)
        # pulleys tip side first: the guide (its K per sample from the wrap), then the instrument's
        self.K_rest = list(chain.K)
        self.B = [params.EI / params.guide_R ** 2] + list(chain.B)
        self.spans = np.concatenate([[params.tip_span], chain.spans])
        self.L = float(self.spans.sum())
        self.k = float(params.EA / self.L if params.stick_k is None else params.stick_k)
        self.j_fsr = len(self.B) if params.sensor_after is None else int(params.sensor_after)
        self.L_home = np.broadcast_to(np.asarray(L_home, dtype=float), (n,)).copy()
        self.n = n
        self.state = np.full((n, 2), math.nan)   # per cable (x_prev, F - k x_prev): kernel driven_play's
        self.e_ref = np.full(n, math.nan)        # the first sample's uniform stretch [m]
        self.x_tip = np.zeros(n)

    def _profiles(self, T, wrap) -> tuple[np.ndarray, np.ndarray]:
        """(releasing, pulling) segment tensions (p + 2, N) [N] for tip tensions T (N,) and guide wraps (N,)."""
        K = [np.exp(self.mu_guide * np.asarray(wrap, dtype=float))] + self.K_rest
        return chain_tensions(T, K, self.B, False), chain_tensions(T, K, self.B, True)

    def _tip(self, x, T, seg) -> np.ndarray:
        """Tip travel [m] from motor positions x, tip tensions T and segment tensions seg (rows: segments)."""
        first = np.isnan(self.e_ref)
        if first.any():
            T0 = np.asarray(T, dtype=float).reshape(-1, self.n)[0]
            self.e_ref[first] = T0[first] * self.L / self.params.EA
        stretch = segment_stretch(seg, self.spans, self.params.EA)
        return x - (stretch - self.e_ref)

    def step(self, L, t_tip, wrap) -> tuple:
        """One reading: cable lengths L (n,) [m], tip tensions t_tip (n,) [N], capstan wraps (n,) [rad] ->
        (tension at the FSR, at the FBG, at the motor) (n,) each [N]; x_tip updated."""
        x = self.L_home - np.asarray(L, dtype=float)
        T = np.asarray(t_tip, dtype=float)
        rel, pull = self._profiles(T, wrap)
        F = np.empty(self.n)
        for i in range(self.n):
            F[i] = driven_play(self.state[i], x[i], T[i], rel[-1, i], pull[-1, i], self.k)
        seg = band_segments(F, rel, pull)
        self.x_tip = self._tip(x, T, seg)
        return seg[self.j_fsr], seg[0], F

    def travel(self, X, T_tip, TH) -> PulleyTrace:
        """`step` over m readings: (m, n) lengths [m], tip tensions [N] and wraps [rad] -> PulleyTrace."""
        X, T, TH = (np.asarray(a, dtype=float) for a in (X, T_tip, TH))
        m = X.shape[0]
        x = self.L_home[None, :] - X
        rel, pull = self._profiles(T.reshape(-1), TH.reshape(-1))   # (p + 2, m n), sample-major
        lo, hi = rel[-1].reshape(m, self.n), pull[-1].reshape(m, self.n)
        F = np.empty((self.n, m))
        p = np.array([self.k])
        for i in range(self.n):
            U = np.ascontiguousarray(np.column_stack([x[:, i], T[:, i], lo[:, i], hi[:, i]]))
            driven_play_run(self.state[i], U, p, F[i])
        F = np.ascontiguousarray(F.T)
        seg = band_segments(F.reshape(-1), rel, pull).reshape(-1, m, self.n)
        x_tip = self._tip(x, T, seg)
        self.x_tip = x_tip[-1].copy()
        return PulleyTrace(t_fsr=seg[self.j_fsr], t_fbg=seg[0], t_motor=F, x_tip=x_tip)

    def run(self, X, T_tip, TH) -> tuple:
        """`step` over m readings, (m, n) lengths, tip tensions and wraps -> (m, n) tensions at the FSR, the FBG
        and the motor [N]."""
        r = self.travel(X, T_tip, TH)
        return r.t_fsr, r.t_fbg, r.t_motor
