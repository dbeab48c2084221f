"""The distributed tendon-sheath cable: a plant whose physics no estimator shares (a yardstick; it imports
nothing of teleop.core.physics or the estimators).

The cable runs from the motor (node 0, its travel prescribed) through the sheath to the tip (node N) as N
elastic elements of stiffness k = EA / l, l = L / N, each with its bend angle b_j from the sheath's bend
profile: the route bend theta1, the scaffold bend theta0 and the kinematic bend theta (the robot's, it
changes with the pose), each a total angle spread uniformly over its own span [s_a, s_b] of the sheath.
Each node i carries the normal force of the half elements beside it and friction on it (travel u hauling in
positive, tension T_j in element j between nodes j and j+1):

    T_j = max(0, t0 + k (u_j - u_{j+1}))                           elastic, slack at zero tension
    n_i = (T_{i-1} b_{i-1} + T_i b_i) / 2                         normal force [N]
    m_i dv_i/dt = T_{i-1} - T_i - n_i phi_i  (- F_load at i = N)   node momentum
    phi_i = sigma0 z_i + sigma1 dz_i/dt + sigma2 v_i                LuGre friction coefficient [-]
    dz_i/dt = v_i - sigma0 |v_i| z_i / g(v_i),  g(v) = mu_c + (mu_s - mu_c) exp(-(v / v_s)^2)

In steady sliding every node's phi is +-g and the tension falls along the sheath by the capstan law, the
discrete product ((1 + a) / (1 - a))^N = exp(mu Theta) (1 + O(a^2)), a = mu Theta / (2 N), for a uniform
bend (Kaneko et al., "Basic considerations on transmission characteristics for tendon drive robots", ICAR
1991; Agrawal, Peine and Yao, "Modeling of transmission characteristics across a cable-conduit system",
IEEE Trans Robot 2010).
After a reversal the motor travels through a dead zone while the tension profile turns over; its width and
the transmission's apparent stiffness follow in closed form for a uniform bend (`dead_zone_uniform`,
`apparent_stiffness`). The load on the tip is a spring with an external force, or the tip's travel is
prescribed (the reaction is the load force). The motor force is the tension at the sheath's entrance (the
proximal gauge): T_0 with the friction of the motor node's half element.

Friction: LuGre per node, with every term proportional to the normal force (sigma0, sigma1, sigma2 per newton
of normal load). LuGre rather than Dahl because it carries the Stribeck curve g(v) and the pre-sliding
(bristle) stiffness in one state; Dahl has no Stribeck peak. Scaling by n_i keeps the friction within
g(v) n_i whatever the tension does, and the pre-sliding travel g / sigma0 independent of the load. Do,
Tjahjowidodo, Lau and Phee ("Nonlinear friction modelling and compensation control of hysteresis phenomena
for a pair of tendon-sheath actuated surgical robots", Mech Syst Signal Process 2015) use a Dahl-type state
for the same purpose.

Integration: backward Euler, all of it implicit (tensions, normal forces, bristle states; the Stribeck curve
at the last step's velocity), solved by Newton's method on the tridiagonal Jacobian, O(N) a step
(scenes.tendon_sheath_kernels). Why implicit: with the cable's real mass the highest axial mode of an element,
2 sqrt(k / m_i), is of order 1e5 rad/s at N = 20, so an explicit step would need ~1e-5 s (about 100 sub-steps a
1 kHz tick, more with stiff bristles), where backward Euler is stable at any step. Its price: modes the tick
does not resolve are damped, not reproduced, i.e. the cable's first axial mode, (pi / 2) sqrt(EA / rho_l) / L,
about the loop's rate, and the cable's mass on a soft load spring, sqrt(k_load / (rho_l L)); below them the
cable is quasi-static, as the real one is. Mass per length: the real one (`mass_per_length`), not a
relaxation: it costs nothing in an implicit step and keeps nodes between slack elements determined.
Sub-steps: a tick runs in ceil(tick / max_step) steps, the motor and tip inputs interpolated linearly. The
default max_step is the loop's 1 ms tick, so the loop runs one implicit step a tick: stability needs no
sub-steps (backward Euler), and accuracy none either (the 4 kHz and the 1 kHz runs of the robot's kind of drive
agree within 1 %, tests/scenes/test_tendon_sheath.py); a coarser tick (a slower robot link) gets sub-steps.

`TendonSheath` holds the state of c cables; its `step` (the loop's tick) and `run` (a whole trajectory)
call the same compiled per-tick step (scenes.tendon_sheath_kernels.step): one call for all cables and
sub-steps, on state arrays allocated once (no allocation a tick).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scenes import tendon_sheath_kernels as K
from teleop.core.config import check_keys, get_integer, get_number, load_toml_table
from teleop.core.errors import InputError

LOAD_KINDS = ("spring", "force", "position")


@dataclass(frozen=True)
class TendonSheathParams:
    """One cable in its sheath (SI). Defaults and their sources (docs/plant-distributed.md: which figure each
    one is checked against; none is taken from the figure it is checked against):

    Attributes:
        length: cable length from the motor to the tip L [m]; assumed: seed 000 gives no length, ~1 m from the
            motor box to the scaffold (scenes.sim_robot tip_stiffness).
        EA: axial stiffness [N]; cable material data: seed 000 names a Bowden cable (steel inner cable) in a
            PTFE-lined Bowden tube, no diameter; taken as 0.3 mm 7x7 302 stainless (the project's assumption) with
            the maker's elastic stretch factor G = 1.20e-5 (Loos & Co. / Strand Core wire-rope stretch chart:
            stretch [% of length] = W [lbf] G / D [in]^2), EA = 100 D^2 / G lbf = 5.17 kN.
        mass_per_length: rho_l [kg/m]: steel 7900 kg/m^3 over the 0.3 mm section with a 0.75 fill factor.
        n_elements: N elements (>= 20).
        mu_c: Coulomb friction coefficient of cable on liner [-]; from one figure: seed 000 Fig 9b's distal swing
            (3.32 / 2.39 N at theta = 30 deg, pretension 2.94 N) = exp(2 mu (theta0 + theta)): 0.0554, one mu for
            the whole sheath.
        mu_s: static (breakaway) coefficient [-]: 1.2 mu_c, the low end of steel on a polymer liner (1.2-2);
            assumed, not checked by a seed figure.
        v_s: Stribeck velocity [m/s]: 0.1 mm/s, below the palpation's cable speed; assumed.
        sigma0: bristle stiffness per newton of normal force [1/m]: mu_c / sigma0 is the pre-sliding travel,
            10 um; assumed (below the FSR's and the encoder's resolution at the seed's speeds).
        sigma1: bristle damping per newton of normal force [s/m]; 0: LuGre with sigma1 > 0 can generate
            energy at some speeds (Barabanov and Ortega 2000), and backward Euler damps the bristle modes.
        sigma2: viscous friction per newton of normal force [s/m]; 0, assumed (the seed's speeds are slow).
        theta0, scaffold_span: scaffold bend [rad] (seed 000 Fig 8, B-C: 140 deg) over [s_a, s_b] [m].
        theta1, route_span: route bend of the sheath [rad] (seed 000 Fig 8, A-B: 360 deg) over [s_a, s_b] [m].
        kinematic_span: where the kinematic bend theta (an input, each tick) sits [m] (C-D, at the tip).
        max_step: longest implicit step [s]; a tick runs in ceil(tick / max_step) steps.
        newton_tol: Newton tolerance on the node travel per step [m].
        newton_iter: Newton iteration limit per step.
    """

    length: float = 1.0
    EA: float = 5.17e3
    mass_per_length: float = 4.2e-4
    n_elements: int = 20
    mu_c: float = 0.0554
    mu_s: float = 0.0665
    v_s: float = 1.0e-4
    sigma0: float = 5.54e3
    sigma1: float = 0.0
    sigma2: float = 0.0
    theta0: float = math.radians(140.0)
    theta1: float = math.radians(360.0)
    route_span: tuple = (0.0, 0.80)
    scaffold_span: tuple = (0.80, 0.95)
    kinematic_span: tuple = (0.95, 1.0)
    max_step: float = 1.0e-3
    newton_tol: float = 1.0e-12
    newton_iter: int = 60

    def __post_init__(self):
        positive = ("length", "EA", "mass_per_length", "sigma0", "max_step", "newton_tol")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InputError(f"tendon sheath: {name} must be a number > 0, got {value!r}")
        for name in ("mu_c", "mu_s", "v_s", "sigma1", "sigma2", "theta0", "theta1"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise InputError(f"tendon sheath: {name} must be a number >= 0, got {value!r}")
        if self.mu_s < self.mu_c:
            raise InputError(f"tendon sheath: mu_s ({self.mu_s}) must be >= mu_c ({self.mu_c})")
        if not isinstance(self.n_elements, int) or self.n_elements < 20:
            raise InputError(f"tendon sheath: n_elements must be an integer >= 20, got {self.n_elements!r}")
        if not isinstance(self.newton_iter, int) or self.newton_iter < 1:
            raise InputError(f"tendon sheath: newton_iter must be an integer >= 1, got {self.newton_iter!r}")
        for name in ("route_span", "scaffold_span", "kinematic_span"):
            span = getattr(self, name)
            if not (len(span) == 2 and 0 <= span[0] <= span[1] <= self.length):
                raise InputError(f"tendon sheath: {name} must be [s_a, s_b] with 0 <= s_a <= s_b <= length "
                                 f"({self.length} m), got {span!r}")

    @property
    def element_length(self) -> float:
        """l = L / N [m]."""
        return self.length / self.n_elements

    @property
    def element_stiffness(self) -> float:
        """k = EA / l [N/m]."""
        return self.EA / self.element_length

    @property
    def node_mass(self) -> float:
        """m_i = rho_l l of an interior node [kg] (the tip node half of it)."""
        return self.mass_per_length * self.element_length

    @property
    def bend_weights(self) -> np.ndarray:
        """(3, N): the share of theta0, theta1 and theta in each element [-] (rows sum to 1)."""
        return np.array([span_weights(s, self.length, self.n_elements)
                         for s in (self.scaffold_span, self.route_span, self.kinematic_span)])

    def kernel_params(self, load: "SheathLoad", rest: float) -> np.ndarray:
        """The parameter vector of scenes.tendon_sheath_kernels (P_COUNT,): the cable's and the load's (the tick's
        entries, P_MODE, P_TICK and P_NSUB, are TendonSheath's)."""
        p = np.zeros(K.P_COUNT)
        p[K.P_K], p[K.P_M] = self.element_stiffness, self.node_mass
        p[K.P_MU_C], p[K.P_MU_S], p[K.P_V_S] = self.mu_c, self.mu_s, self.v_s
        p[K.P_SIGMA0], p[K.P_SIGMA1], p[K.P_SIGMA2] = self.sigma0, self.sigma1, self.sigma2
        p[K.P_K_LOAD], p[K.P_REST] = load.stiffness, rest
        p[K.P_TOL], p[K.P_ITER] = self.newton_tol, self.newton_iter
        return p

    @classmethod
    def from_dict(cls, d: dict, where: str = "tendon sheath") -> "TendonSheathParams":
        """From a table with edge units in the keys (TOML_KEYS); unknown keys raise InputError."""
        check_keys(d, TOML_KEYS, where)
        kw = {}
        for key, value in d.items():
            name, scale = TOML_KEYS[key]
            if name.endswith("_span"):
                if not (isinstance(value, (list, tuple)) and len(value) == 2
                        and all(isinstance(x, (int, float)) for x in value)):
                    raise InputError(f"{where}: {key} must be [start, end] in m, got {value!r}")
                kw[name] = (float(value[0]), float(value[1]))
            elif name in ("n_elements", "newton_iter"):
                kw[name] = get_integer(d, key, where)
            else:
                kw[name] = get_number(d, key, where) * scale
        return cls(**kw)

    @classmethod
    def from_toml(cls, path, table: str = "tendon_sheath") -> "TendonSheathParams":
        """From the table `table` of a TOML file (keys as `from_dict`)."""
        values, where = load_toml_table(path, table)
        return cls.from_dict(values, where=where)


#: TOML key -> (field, factor to SI)
TOML_KEYS = {
    "length_m": ("length", 1.0), "EA_N": ("EA", 1.0), "mass_per_length_kg_per_m": ("mass_per_length", 1.0),
    "n_elements": ("n_elements", 1), "mu_c": ("mu_c", 1.0), "mu_s": ("mu_s", 1.0),
    "v_s_m_per_s": ("v_s", 1.0), "sigma0_per_m": ("sigma0", 1.0), "sigma1_s_per_m": ("sigma1", 1.0),
    "sigma2_s_per_m": ("sigma2", 1.0), "theta0_deg": ("theta0", math.pi / 180), "theta1_deg": ("theta1", math.pi / 180),
    "route_span_m": ("route_span", 1.0), "scaffold_span_m": ("scaffold_span", 1.0),
    "kinematic_span_m": ("kinematic_span", 1.0), "max_step_s": ("max_step", 1.0),
    "newton_tol_m": ("newton_tol", 1.0), "newton_iter": ("newton_iter", 1),
}


@dataclass(frozen=True)
class SheathLoad:
    """The load on the cable's tip.

    Attributes:
        kind: "spring" (F = stiffness (x_tip - rest) + f_ext, f_ext the tip input [N]), "force" (F = f_ext),
            "position" (the tip input is the tip's travel x_tip [m]; F is the reaction).
        stiffness: spring stiffness [N/m] ("spring" only).
        rest: the spring's rest position in tip travel [m]; None: the one that holds the pretension at
            x_tip = 0 with f_ext = 0 (rest = -pretension / stiffness).
    """

    kind: str = "spring"
    stiffness: float = 0.0
    rest: float | None = None

    def __post_init__(self):
        if self.kind not in LOAD_KINDS:
            raise InputError(f"tendon sheath load: kind must be one of {', '.join(LOAD_KINDS)}, got {self.kind!r}")
        if self.kind == "spring" and not (math.isfinite(self.stiffness) and self.stiffness > 0):
            raise InputError(f"tendon sheath load: a spring needs stiffness > 0, got {self.stiffness!r}")
        if self.kind != "spring" and (self.stiffness != 0 or self.rest is not None):
            raise InputError(f"tendon sheath load: stiffness and rest belong to the spring, not {self.kind!r}")

    @property
    def mode(self) -> int:
        return K.MODE_POSITION if self.kind == "position" else K.MODE_SPRING


def span_weights(span, length: float, n: int) -> np.ndarray:
    """(n,) share of a bend spread uniformly over span [s_a, s_b] [m] in each of n equal elements over
    [0, length] (sums to 1); a point span puts it all in the element holding that point."""
    a, b = float(span[0]), float(span[1])
    edges = np.linspace(0.0, length, n + 1)
    if b <= a:
        w = np.zeros(n)
        w[min(int(a / length * n), n - 1)] = 1.0
        return w
    return np.clip(np.minimum(edges[1:], b) - np.maximum(edges[:-1], a), 0.0, None) / (b - a)


@dataclass(frozen=True)
class SheathRun:
    """A trajectory of c cables over m ticks (SI).

    Attributes:
        t (m,) time [s]; x_motor, f_motor, f_tip, x_tip (m, c): motor travel [m], motor force (tension at the
        sheath's entrance) [N], tip load force [N], tip travel [m]; iterations (m, c) Newton iterations a
        tick; tensions (m, c, N) element tensions [N] or None; tapped (m, taps, c) the tensions [N] at the
        sheath's tapped elements, then its tapped nodes (TendonSheath taps, node_taps).
    """

    t: np.ndarray
    x_motor: np.ndarray
    f_motor: np.ndarray
    f_tip: np.ndarray
    x_tip: np.ndarray
    iterations: np.ndarray
    tensions: np.ndarray | None = None
    tapped: np.ndarray | None = None

    def motor_work(self) -> np.ndarray:
        """(c,) work the motor put in over the run [J]: sum of F dx (trapezoid)."""
        f = 0.5 * (self.f_motor[1:] + self.f_motor[:-1])
        return np.sum(f * np.diff(self.x_motor, axis=0), axis=0)

    def tip_work(self) -> np.ndarray:
        """(c,) work done on the load over the run [J]: sum of F dx_tip (trapezoid)."""
        f = 0.5 * (self.f_tip[1:] + self.f_tip[:-1])
        return np.sum(f * np.diff(self.x_tip, axis=0), axis=0)

    def plot(self, cable: int = 0):
        """Motor and tip force against motor travel of one cable; returns the matplotlib figure."""
        import matplotlib.pyplot as plt  # optional heavy dependency

        fig, ax = plt.subplots()
        ax.plot(self.x_motor[:, cable] * 1e3, self.f_motor[:, cable], label="motor (sheath entrance)")
        ax.plot(self.x_motor[:, cable] * 1e3, self.f_tip[:, cable], label="tip load")
        ax.set_xlabel("motor travel [mm]")
        ax.set_ylabel("force [N]")
        ax.legend()
        return fig


class TendonSheath:
    """c distributed tendon-sheath cables with their state; `step` is one tick, `run` a trajectory (the same
    compiled step).

    Args:
        params: the cable and sheath (TendonSheathParams), the same for every cable.
        load: the tip load (SheathLoad).
        pretension: the initial configuration's uniform tension [N] (no friction stored), scalar or (c,).
        n_cables: c.
        tick: the loop's period [s].
        theta0, theta1: scaffold and route bends per cable [rad], scalar or (c,); None: params' values.
        taps: indices of elements whose tension every tick reports (sensors there; `step_into`, SheathRun.tapped).
        node_taps: indices of nodes whose tension every tick reports after the elements' (a sensor at a node,
            between two elements: tendon_sheath_kernels.node_tension, as `tension_at_b`).
        motor_ref, motor_sign, theta_offset: the inputs' map, per cable (scalar or (c,)): a tick's motor input x
            is the motor travel motor_ref + motor_sign x [m] (the robot gives its cable lengths: L_home - L), its
            theta input the kinematic bend |theta - theta_offset| [rad]. Defaults: the travel and the bend.
    """

    def __init__(self, params: TendonSheathParams = TendonSheathParams(), load: SheathLoad = SheathLoad("force"),
                 pretension=2.0, n_cables: int = 1, tick: float = 1e-3, theta0=None, theta1=None, taps=(),
                 motor_ref=0.0, motor_sign=1.0, theta_offset=0.0, node_taps=()):
        if not (math.isfinite(tick) and tick > 0) or n_cables < 1:
            raise InputError(f"tendon sheath: need tick > 0 and n_cables >= 1, got {tick}, {n_cables}")
        pre = np.broadcast_to(np.asarray(pretension, dtype=float), (n_cables,)).copy()
        if not np.all(np.isfinite(pre)) or np.any(pre < 0):
            raise InputError(f"tendon sheath: pretension must be >= 0 N, got {pretension!r}")
        N = params.n_elements
        taps = np.array(taps, dtype=np.int64).reshape(-1)
        if np.any((taps < 0) | (taps >= N)):
            raise InputError(f"tendon sheath: taps must be element indices in [0, {N}), got {taps.tolist()}")
        node_taps = np.array(node_taps, dtype=np.int64).reshape(-1)
        if np.any((node_taps < 0) | (node_taps >= N)):
            raise InputError(f"tendon sheath: node_taps must be node indices in [0, {N}), got {node_taps.tolist()}")
        self.params, self.load, self.tick, self.n_cables = params, load, float(tick), n_cables
        self.pretension = pre
        self.taps, self.node_taps = taps, node_taps
        self.n_sub = max(1, math.ceil(self.tick / params.max_step - 1e-9))
        rest = load.rest
        if load.kind == "spring" and rest is None:
            if np.ptp(pre) > 0:
                raise InputError("tendon sheath: a spring load's default rest needs one pretension for all cables")
            rest = -float(pre[0]) / load.stiffness
        p = params.kernel_params(load, 0.0 if rest is None else rest)
        p[K.P_MODE], p[K.P_TICK], p[K.P_NSUB], p[K.P_ETAPS] = load.mode, self.tick, self.n_sub, len(taps)
        self._p = np.concatenate([p, taps.astype(float), node_taps.astype(float)])  # the parameters, then the taps
        # the kernel's arrays (scenes.tendon_sheath_kernels): node arrays S (u, v, z, the bend weights and the
        # step's scratch), per-cable scalars cab (pretension, last tip input, fixed bends, the inputs' map and
        # the step's scratch)
        self._S = np.zeros((K.S_ROWS, n_cables, N + 1))
        self._S[K.S_W0:K.S_W2 + 1, :, :N] = params.bend_weights[:, None, :]
        self.u, self.v, self.z = self._S[K.S_U], self._S[K.S_V], self._S[K.S_Z]
        self._cab = np.zeros((n_cables, K.CAB_COLS))
        self._cab[:, K.C_T0] = pre
        for col, a in ((K.C_THETA0, params.theta0 if theta0 is None else theta0),
                       (K.C_THETA1, params.theta1 if theta1 is None else theta1),
                       (K.C_X0, motor_ref), (K.C_XS, motor_sign), (K.C_TH_OFF, theta_offset)):
            self._cab[:, col] = np.broadcast_to(np.asarray(a, float), (n_cables,))
        if not np.all(np.isfinite(self._cab[:, :K.C_TH_OFF + 1])):
            raise InputError("tendon sheath: bends, motor_ref, motor_sign and theta_offset must be finite")
        self.tensions = np.empty((n_cables, N))
        self.reset()

    @property
    def out_rows(self) -> int:
        """Rows of a tick's output (`step_into`): motor force, tip load force, tip travel, Newton iterations, then
        the tapped elements' tensions, then the tapped nodes'."""
        return K.O_ROWS + len(self.taps) + len(self.node_taps)

    def reset(self) -> None:
        """Back to the initial configuration: motor and tip at 0, uniform pretension, no friction stored."""
        self._S[:K.S_W0] = 0.0
        self._cab[:, K.C_TIP] = 0.0 if self.load.kind != "force" else self.pretension
        self.tensions[:] = self.pretension[:, None]
        self.t = 0.0

    @property
    def tip_prev(self) -> np.ndarray:
        """(c,) the last tick's tip input (a view of the kernel's state)."""
        return self._cab[:, K.C_TIP]

    def held_tip_input(self) -> np.ndarray:
        """(c,) the last tick's tip input, the default of the next (at the start the one that holds the initial
        configuration: f_ext 0 on a spring, the pretension as a force, tip travel 0)."""
        return self.tip_prev.copy()

    def _inputs(self, x_motor, tip_input, theta, m):
        """Inputs of m ticks as contiguous (m, c) (a 1-D input is per tick, the same for every cable)."""
        shape = (m, self.n_cables)

        def arr(a):
            a = np.asarray(a, dtype=float)
            if a.ndim == 1:
                a = a[:, None]
            try:
                return np.ascontiguousarray(np.broadcast_to(a, shape))
            except ValueError:
                raise InputError(f"tendon sheath: an input of shape {a.shape} does not fit {shape}") from None

        X, TH = arr(x_motor), arr(theta)
        if tip_input is None:  # held from the last tick
            tip_input = self.held_tip_input()[None]
        TIP = arr(tip_input)
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(TIP)) and np.all(np.isfinite(TH))):
            raise InputError("tendon sheath: motor, tip and theta inputs must be finite")
        return X, TIP, TH

    def _tick_input(self, a, tip=False) -> np.ndarray:
        """One tick's input as a (c,) float array (the loop's path: no copies when it already is one)."""
        if a is None and tip:
            return self.held_tip_input()
        if type(a) is np.ndarray and a.shape == (self.n_cables,) and a.dtype == np.float64 and a.flags.c_contiguous:
            return a
        a = np.asarray(a, dtype=float)
        if a.ndim == 0:
            return np.full(self.n_cables, float(a))
        if a.shape != (self.n_cables,):
            raise InputError(f"tendon sheath: an input of shape {a.shape} does not fit ({self.n_cables},)")
        return np.ascontiguousarray(a)

    def step(self, x_motor, tip_input=None, theta=0.0) -> np.ndarray:
        """One tick to motor travel x_motor [m] (scalar or (c,); through the inputs' map): tip_input f_ext [N]
        ("spring", "force") or tip travel [m] ("position"), default `held_tip_input`; theta the kinematic bend
        [rad]. Returns (c, 3): motor force [N], tip load force [N], tip travel [m]."""
        X, TIP, TH = self._tick_input(x_motor), self._tick_input(tip_input, True), self._tick_input(theta)
        if not math.isfinite(float(X.sum() + TIP.sum() + TH.sum())):
            raise InputError("tendon sheath: motor, tip and theta inputs must be finite")
        out = np.empty((self.out_rows, self.n_cables))
        self.step_into(X, TIP, TH, out)
        return out[:3].T

    def step_into(self, x_motor, tip_input, theta, out) -> None:
        """`step` without its input checks, for a caller whose inputs are its own arrays: x_motor, tip_input,
        theta (c,) float64, C-contiguous and finite; writes out (out_rows, c): motor force [N], tip load force
        [N], tip travel [m], Newton iterations of the tick, then the tension [N] at each tapped element and
        node. One compiled call for all cables and sub-steps."""
        K.step(self._S, self._cab, self._p, x_motor, tip_input, theta, self.tensions, out)
        self.t += self.tick

    def run(self, x_motor, tip_input=None, theta=0.0, keep_tensions: bool = False) -> SheathRun:
        """Ticks for motor travel x_motor (m,) or (m, c) [m]; tip_input and theta as in `step`, each (m,) or
        (m, c) or a constant. The state carries on from the last tick."""
        m = np.shape(x_motor)[0]
        X, TIP, TH = self._inputs(x_motor, tip_input, theta, m)
        OUT = np.empty((m, self.out_rows, self.n_cables))
        TT = np.empty((m if keep_tensions else 1, self.n_cables, self.params.n_elements))
        K.run(self._S, self._cab, self._p, X, TIP, TH, OUT, TT)
        self.tensions[:] = TT[-1]
        t = self.t + self.tick * np.arange(1, m + 1)
        self.t += m * self.tick
        x_motor = self._cab[:, K.C_X0] + self._cab[:, K.C_XS] * X  # the motor's travel (the inputs' map)
        return SheathRun(t=t, x_motor=x_motor, f_motor=OUT[:, K.O_MOTOR], f_tip=OUT[:, K.O_TIP],
                         x_tip=OUT[:, K.O_X_TIP],
                         iterations=OUT[:, K.O_ITER], tensions=TT if keep_tensions else None,
                         tapped=OUT[:, K.O_ROWS:])

    def tension_at(self, s: float) -> np.ndarray:
        """(c,) the tension [N] of the element holding arc length s [m] from the motor (a sensor there)."""
        if not 0 <= s <= self.params.length:
            raise InputError(f"tendon sheath: s must be in [0, {self.params.length}] m, got {s}")
        j = min(int(s / self.params.element_length), self.params.n_elements - 1)
        return self.tensions[:, j].copy()


def b_node(params: TendonSheathParams) -> int:
    """The node at B, the scaffold bend's start s_B (s_B = j l, rounded down; at most N - 1)."""
    return min(int(params.scaffold_span[0] / params.element_length), params.n_elements - 1)


def tension_at_b(T: np.ndarray, params: TendonSheathParams, theta1=None) -> np.ndarray:
    """(m,) tension [N] at B (`b_node`, a sensor there: the FSR) from element tensions T (m, N) [N] with the
    sheath's fixed bends (theta0, and theta1 or params'): tendon_sheath_kernels.node_tension of the node's
    two elements, as TendonSheath's node taps read it each tick."""
    T = np.ascontiguousarray(T, dtype=float)
    j = b_node(params)
    w_scaffold, w_route, _ = params.bend_weights
    th1 = params.theta1 if theta1 is None else float(theta1)
    b = params.theta0 * w_scaffold + th1 * w_route  # (N,) bend of each element [rad] (the kernel's order)
    out = np.empty(T.shape[0])
    K.node_tension_rows(T, j, float(b[j - 1]) if j > 0 else 0.0, float(b[j]), out)
    return out


# ---- closed forms for a uniform bend (Kaneko), Coulomb friction mu over a total bend Theta ---------------

def capstan_ratio(mu_theta: float) -> float:
    """T_proximal / T_distal in steady sliding while pulling, exp(mu Theta) (releasing: its inverse)."""
    return math.exp(mu_theta)


def apparent_stiffness(EA: float, length: float, mu_theta: float, pulling: bool = True) -> float:
    """Motor travel per tip force change with the tip held [N/m] in steady sliding over a uniform bend:
    EA mu Theta / (L (e^{mu Theta} - 1)) pulling, EA mu Theta / (L (1 - e^{-mu Theta})) releasing (EA / L
    without friction)."""
    if mu_theta == 0:
        return EA / length
    d = math.expm1(mu_theta) if pulling else -math.expm1(-mu_theta)
    return EA * mu_theta / (length * d)


def dead_zone_uniform(t_tip: float, EA: float, length: float, mu_theta: float) -> float:
    """Motor travel [m] after a reversal before the tip moves, the tip force t_tip [N] at the reversal: the
    tension profile turns from t_tip e^{mu kappa (L - s)} to t_tip e^{-mu kappa (L - s)},
    2 t_tip L (cosh(mu Theta) - 1) / (EA mu Theta)."""
    if mu_theta == 0:
        return 0.0
    return 2.0 * t_tip * length * (math.cosh(mu_theta) - 1.0) / (EA * mu_theta)
