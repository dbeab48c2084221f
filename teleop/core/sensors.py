"""Tension sensors: FSR calibration (seed 000 §2.2, eq 2, Fig 7), FBG force with temperature compensation
(seed 001 eq 3) and the one-sensor-for-all proximal/distal model (seed 001 eqs 4-7).

FSR chain (what the robot's ADC sees, SI inside):
    tension t [N] --branch polynomial P(t) (eq 2)--> conductance G [S] --voltage divider--> counts [0, adc_max]
The calibration fits one quintic per branch (loading, unloading); the inverse map reading -> tension is a
monotone interpolation table per branch built once. `FsrConverter` keeps per-cable state and picks the branch
from the direction of change of the reading (with a dead band so noise does not flip branches).
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import Polynomial
from scipy.optimize import least_squares
from scipy.signal import butter, sosfilt, sosfilt_zi

from teleop.core.direction import DirectionTracker
from teleop.core.errors import InputError
from teleop.core.kernels.jit import broadcast_call
from teleop.core.kernels.sensor import (adc_round_loop, branch_lag_loop, conductance2counts_loop, conductance_loop,
                                   counts2conductance, counts2conductance_loop, eq7_run, eq7_start, eq7_step,
                                   fbg_force_loop, fsr_counts, polynomial_loop)

G = 9.80665  # standard gravity [m/s^2], converts the seed's calibration weights to newtons
LOADING, UNLOADING = 1, -1


# --------------------------------------------------------------------------------------------------------
# FSR: calibration data, quintic fits, inversion
# --------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FsrCalibrationData:
    """Calibration samples of one FSR (seed 000 Fig 6/7 procedure).

    Attributes:
        tension: (n,) applied tension [N] (weight times g).
        reading: (n,) sensor conductance [S].
        branch: (n,) +1 loading (weight added), -1 unloading (weight removed).
        source: where the data came from (file name or a description).
    """

    tension: np.ndarray
    reading: np.ndarray
    branch: np.ndarray
    source: str = ""


def default_fsr_calibration_data(seed: int = 0, repeats: int = 3, noise_S: float = 0.4e-6) -> FsrCalibrationData:
    """Synthetic calibration made to look like seed 000 Fig 7 (not measured data).

    0-600 g in 50 g steps up (loading) and 600-0 g down (unloading), each the mean of `repeats` runs like the
    seed's three. Conductance rises concavely to about 62 uS (loading) at 5.89 N; the unloading branch lies
    above the loading one at the same weight (friction in the sheath holds the pressed block), by up to
    ~12 % mid-range and ~4 % at 600 g (the seed's 600 g unloading reading follows 650 g). Both start at 0.
    """
    rng = np.random.default_rng(seed)
    w_g = np.arange(0.0, 601.0, 50.0)
    t = w_g * 1e-3 * G
    t_max = t[-1]
    x = t / t_max
    g_load = 62e-6 * (1.35 * x - 0.35 * x ** 2) * (1.0 - np.exp(-x / 0.04))
    g_unload = g_load + 7.5e-6 * np.sin(np.pi * x ** 0.8) + 2.5e-6 * x * (1.0 - np.exp(-x / 0.04))
    tension, reading, branch = [], [], []
    for b, curve in ((LOADING, g_load), (UNLOADING, g_unload[::-1])):
        tt = t if b == LOADING else t[::-1]
        mean = np.mean([np.maximum(curve + rng.normal(0.0, noise_S, curve.shape), 0.0) for _ in range(repeats)],
                       axis=0)
        tension.append(tt)
        reading.append(mean)
        branch.append(np.full(tt.shape, b))
    return FsrCalibrationData(np.concatenate(tension), np.concatenate(reading), np.concatenate(branch),
                              source="synthetic, shaped after seed 000 Fig 7")


@dataclass(frozen=True)
class FsrCalibration:
    """Quintic reading = P(tension) per branch (seed 000 eq 2, fitted as an ordinary polynomial).

    Attributes:
        loading, unloading: (6,) power-series coefficients of conductance [S] in tension [N], lowest first.
        t_max: upper end of the calibrated tension range [N].
        r_divider: divider resistor of the ADC circuit [ohm] (counts = adc_max G R / (1 + G R)).
        adc_max: ADC full scale [counts].
        table_size: points of the inverse tables.
    """

    loading: tuple
    unloading: tuple
    t_max: float
    r_divider: float = 10e3
    adc_max: int = 1023
    table_size: int = 2048
    _tables: dict = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self):
        grid = np.linspace(0.0, self.t_max, self.table_size)
        tables = {}
        for b, coefs in ((LOADING, self.loading), (UNLOADING, self.unloading)):
            g = polynomial_loop(grid, np.asarray(coefs, dtype=float), np.empty(grid.shape[0]))
            # monotone inversion: a quintic can wiggle at the ends; keep the running maximum so the
            # table reading -> tension is non-decreasing, then drop repeated readings.
            g = np.maximum.accumulate(g)
            keep = np.r_[True, np.diff(g) > 0]
            gk, tk = g[keep], grid[keep]
            slope = (tk[-1] - tk[-8]) / (gk[-1] - gk[-8])  # dt/dG at the top, for linear extrapolation
            tables[b] = (gk, tk, float(slope), gk.tolist(), tk.tolist())
        object.__setattr__(self, "_tables", tables)

    def reading(self, t, branch) -> np.ndarray:
        """Conductance [S] for tension t [N] on `branch` (+1 loading, -1 unloading), array-broadcast."""
        t = np.asarray(t, dtype=float)
        b = np.broadcast_to(np.asarray(branch), t.shape)
        flat = np.ascontiguousarray(t.reshape(-1))
        gl, gu = (conductance_loop(flat, np.asarray(c, dtype=float), np.empty(flat.shape[0])).reshape(t.shape)
                  for c in (self.loading, self.unloading))
        return np.where(b == UNLOADING, gu, gl)

    def tension(self, reading, branch) -> np.ndarray:
        """Tension [N] for conductance `reading` [S] on `branch` (inverse of `reading`; 0 below, linear above)."""
        g = np.asarray(reading, dtype=float)
        b = np.broadcast_to(np.asarray(branch), g.shape)
        out = np.empty(g.shape)
        for br in (LOADING, UNLOADING):
            gk, tk, slope = self._tables[br][:3]
            m = b == br
            gm = g[m]
            tm = np.interp(gm, gk, tk)
            above = gm > gk[-1]
            tm[above] = tk[-1] + slope * (gm[above] - gk[-1])
            out[m] = tm
        return out

    def tension1(self, reading: float, branch: int) -> float:
        """`tension` for one float reading [S] (bisection in the same table; the per-tick form)."""
        _, _, slope, gk, tk = self._tables[UNLOADING if branch == UNLOADING else LOADING]
        if reading != reading:
            return reading
        if reading > gk[-1]:
            return tk[-1] + slope * (reading - gk[-1])
        if reading <= gk[0]:
            return tk[0]
        j = bisect_right(gk, reading)  # gk[j-1] <= reading < gk[j]
        g0, g1 = gk[j - 1], gk[j]
        return tk[j - 1] + (tk[j] - tk[j - 1]) * (reading - g0) / (g1 - g0)

    def counts2conductance(self, counts) -> np.ndarray:
        """Conductance [S] from ADC counts through the divider: G = c / ((adc_max - c) R), counts clipped to
        [0, adc_max - 0.5] (kernel sensor.counts2conductance, array-broadcast)."""
        return broadcast_call(counts2conductance_loop, counts, self.r_divider, self.adc_max)

    def counts_tension1(self, counts: float, branch: int) -> float:
        """Tension [N] of one float reading in ADC counts on `branch`: `tension1` of its conductance (kernel
        sensor.counts2conductance; the per-tick form)."""
        return self.tension1(counts2conductance(counts, float(self.r_divider), float(self.adc_max)), branch)

    def conductance2counts(self, g) -> np.ndarray:
        """ADC counts (float, unrounded) for conductance g [S]: adc_max G R / (1 + G R) (kernel
        sensor.conductance2counts, array-broadcast)."""
        return broadcast_call(conductance2counts_loop, g, self.r_divider, self.adc_max)


class FsrBranchLag:
    """The FSR's hysteresis as a lag between its two calibration branches: what an FSR reads for a tension
    history t [N] (per cable), as the loading-branch reading of an equivalent tension u [N].

    Seed 000 §2.2 puts the hysteresis down to friction: the unloading branch reads as if the tension were
    higher by the branch gap G(t) [N] (g_L(t + G(t)) = g_U(t); 0.13-0.87 N over 0.2-5.9 N for the default
    calibration). Friction holds the reading when the tension turns, so u follows t with play:

        u = clip(u_prev, t, t + G(t))

    rising t: u = t (loading branch); falling: u = t + G(t) (unloading branch); right after a reversal the
    reading holds until t has crossed the gap. More tension never lowers the reading (a blend of the branches
    over a fixed force width narrower than the gap would: at the pretension it would read backwards over
    the crossover). It agrees with the seed's calibration protocol (Fig 7): at 600 g the gap is 0.44 N, so
    its one 50 g (0.49 N) step back from 650 g reads on the unloading branch.

    The gap is tabulated once on [0, cal.t_max] (constant beyond); t + G(t) is made non-decreasing there
    so u stays monotone in t for any calibration. Starts on the loading branch (u = t): the state u (n,) [N]
    is NaN for a cable that has read nothing yet (after `reset`), and is written in place.
    """

    def __init__(self, cal: FsrCalibration, n: int = 6, points: int = 1024):
        t = np.linspace(0.0, cal.t_max, points)
        gap = np.maximum(cal.tension(cal.reading(t, UNLOADING), LOADING) - t, 0.0)
        self.cal = cal
        self._t = t
        self._gap = np.maximum.accumulate(t + gap) - t
        self.n = n
        self.u = np.full(n, np.nan)
        self._c = np.asarray(cal.loading, dtype=float)
        self._r, self._adc = float(cal.r_divider), float(cal.adc_max)

    def gap(self, t) -> np.ndarray:
        """Branch gap G(t) [N] (array-broadcast)."""
        return np.interp(t, self._t, self._gap)

    def reset(self) -> None:
        self.u[:] = np.nan

    def kernel_args(self) -> tuple:
        """(u, grid, gap, c, r_divider, adc_max): this lag's state and constants as kernel sensor.fsr_counts takes
        them after the tensions (u written in place by the kernel; a caller may fuse that kernel into its own)."""
        return self.u, self._t, self._gap, self._c, self._r, self._adc

    def _check(self, n: int) -> None:
        if n != self.n:
            raise InputError(f"FSR branch lag: {n} tensions for a lag of {self.n} cables")

    def step(self, t) -> np.ndarray:
        """(n,) equivalent tensions u [N] after tensions t (n,) [N]."""
        return self.run(np.reshape(t, (1, -1)))[0]

    def run(self, T) -> np.ndarray:
        """(m, n) equivalent tensions for (m, n) tensions, continuing from the state (same numbers as `step`
        row by row; kernel sensor.branch_lag)."""
        T = np.ascontiguousarray(T, dtype=float)
        self._check(T.shape[1])
        return branch_lag_loop(self.u, T, self._t, self._gap, np.empty_like(T))

    def counts(self, t, noise) -> np.ndarray:
        """(n,) int64 ADC counts after tensions t (n,) [N] with noise (n,) [counts] added before rounding:
        `step`, the loading branch's conductance, the divider and the ADC (one kernel call, sensor.fsr_counts;
        the numbers of conductance2counts(conductance(step(t))) + noise, rounded and clipped)."""
        t = np.ascontiguousarray(t, dtype=float)
        self._check(t.shape[0])
        counts = np.empty(t.shape[0], dtype=np.int64)
        fsr_counts(t, self.u, self._t, self._gap, self._c, self._r, self._adc, np.ascontiguousarray(noise, dtype=float),
                   counts)
        return counts

    def conductance(self, u) -> np.ndarray:
        """Conductance [S] the FSR reads at equivalent tension u [N]: the loading branch."""
        return self.cal.reading(u, LOADING)


def fit_fsr_calibration(data: FsrCalibrationData, degree: int = 5, **kwargs) -> FsrCalibration:
    """Least-squares quintic per branch of reading vs tension (numpy.polynomial), seed 000 eq 2."""
    coefs = {}
    for b in (LOADING, UNLOADING):
        m = data.branch == b
        if np.count_nonzero(m) < degree + 1:
            raise InputError(f"{data.source or 'calibration'}: need at least {degree + 1} points per branch")
        coefs[b] = tuple(Polynomial.fit(data.tension[m], data.reading[m], degree).convert().coef.tolist())
    return FsrCalibration(loading=coefs[LOADING], unloading=coefs[UNLOADING],
                          t_max=float(np.max(data.tension)), **kwargs)


def tension_noise(cal: FsrCalibration, noise_counts: float = 1.0, t: float = 2.85, branch: int = LOADING) -> float:
    """RMS tension noise [N] that `noise_counts` RMS ADC noise makes at tension t [N]: noise / (dcounts/dt)."""
    h = 1e-3
    c = cal.conductance2counts(cal.reading(np.array([t - h, t + h]), branch))
    return float(noise_counts / ((c[1] - c[0]) / (2 * h)))


def default_fsr_calibration() -> FsrCalibration:
    """The quintic fits of the synthetic Fig-7-like calibration (`default_fsr_calibration_data`)."""
    return fit_fsr_calibration(default_fsr_calibration_data())


def plot_fsr_calibration(data: FsrCalibrationData, cal: FsrCalibration):
    """Figure like seed 000 Fig 7: calibration points and the two quintic branches (conductance vs tension)."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    fig, ax = plt.subplots(figsize=(6, 4))
    t = np.linspace(0.0, cal.t_max, 200)
    for b, name, color in ((LOADING, "loading", "tab:red"), (UNLOADING, "unloading", "tab:purple")):
        m = data.branch == b
        ax.plot(data.tension[m], data.reading[m] * 1e6, "o", color=color, label=f"{name} points")
        ax.plot(t, cal.reading(t, b) * 1e6, "-", color=color, label=f"{name} quintic fit")
    ax.set_xlabel("tension [N]")
    ax.set_ylabel("conductance [uS]")
    ax.set_title(f"FSR calibration ({data.source})", fontsize=9)
    ax.legend(fontsize=8)
    return fig


def eq2_roots(coefs) -> tuple[float, np.ndarray]:
    """(a, x_i): the fitted quintic written as eq 2, P(x) = a prod(x - x_i) (roots may be complex)."""
    p = Polynomial(coefs)
    return float(p.coef[-1]), p.roots()


def synthesize_fsr_counts(t, branch, cal: FsrCalibration, rng: np.random.Generator | None = None,
                          noise_counts: float = 0.0) -> np.ndarray:
    """Raw FSR ADC counts (int) from tensions t [N] on `branch`: t -> conductance -> counts, + noise, rounded.

    This is how a simulated robot makes its raw readings; `noise_counts` is the RMS ADC noise [counts].
    """
    c = cal.conductance2counts(cal.reading(t, branch))
    if noise_counts > 0:
        if rng is None:
            raise ValueError("synthesize_fsr_counts: noise needs a seeded rng")
        c = c + rng.normal(0.0, noise_counts, np.shape(c))
    return adc_counts(c, cal.adc_max)


def adc_counts(c, adc_max) -> np.ndarray:
    """Rounded, clipped ADC counts (int64) for counts c (float, unrounded): kernel sensor.adc_round."""
    return np.asarray(broadcast_call(adc_round_loop, c, adc_max)).astype(np.int64)


class FsrConverter:
    """Per-cable raw counts -> tension [N], picking the branch from the direction of change of the reading.

    Rising reading -> loading branch, falling -> unloading. A branch flips only after the reading has moved
    more than `deadband_counts` back from its extreme since the last flip (a Schmitt trigger on reversals,
    `DirectionTracker`), so ADC noise does not chatter between branches. Before any motion: loading.
    The default 8 counts (~0.4 N mid-range) is ~5.5 sigma of the difference of two readings with 1 count RMS
    ADC noise; 3 counts chattered on slow pokes in the palpation runs.
    """

    def __init__(self, cal: FsrCalibration, n: int = 6, deadband_counts: float = 8.0):
        self.cal = cal
        self.tracker = DirectionTracker(n, deadband_counts)

    @property
    def branch(self) -> np.ndarray:
        """(n,) current branch per cable: +1 loading, -1 unloading."""
        return np.where(self.tracker.direction < 0, UNLOADING, LOADING)

    def reset(self) -> None:
        self.tracker.reset()

    def update(self, counts) -> np.ndarray:
        """(n,) tensions [N] for (n,) raw counts; updates the branch state. Same numbers as
        cal.tension(cal.counts2conductance(counts), branch), computed per float (faster for six cables)."""
        c = np.asarray(counts, dtype=float).tolist()
        d = self.tracker.update(c).tolist()
        cal = self.cal
        return np.array([cal.counts_tension1(ci, UNLOADING if di < 0 else LOADING) for ci, di in zip(c, d)])


# --------------------------------------------------------------------------------------------------------
# FBG: dual-grating temperature compensation (seed 001 eq 3)
# --------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FbgParams:
    """Dual-FBG force sensor (seed 001 §2.1, §3.1).

    Attributes:
        S_pm_N: force sensitivity of FBG2 [pm/N] (34.12).
        r: temperature sensitivity ratio FBG2/FBG1 [-] (2.28).
        kT1_pm_C, kT2_pm_C: temperature sensitivities of FBG1 (strain-free) and FBG2 [pm/degC].
        noise_pm: RMS error of the wavelength-shift fit [pm] (12.59 pm -> 0.37 N).
    """

    S_pm_N: float = 34.12
    r: float = 2.28
    kT1_pm_C: float = 11.23
    kT2_pm_C: float = 25.62
    noise_pm: float = 12.59

    @property
    def force_error_N(self) -> float:
        """Sensor measurement error noise_pm / S [N] (seed: 0.37 N)."""
        return self.noise_pm / self.S_pm_N


def fbg2force(dl1_pm, dl2_pm, p: FbgParams = FbgParams()) -> np.ndarray:
    """Force [N] F = (dl2 - r dl1) / S from Bragg shifts of FBG1 (temperature) and FBG2 (force + temperature) [pm]
    (kernel sensor.fbg_force, array-broadcast)."""
    return np.asarray(broadcast_call(fbg_force_loop, dl1_pm, dl2_pm, p.r, p.S_pm_N))


def fbg2force_uncompensated(dl2_pm, p: FbgParams = FbgParams()) -> np.ndarray:
    """Force [N] from FBG2 alone, dl2 / S (temperature not removed)."""
    return np.asarray(dl2_pm, dtype=float) / p.S_pm_N


def synthesize_fbg(force_N, dT_C, p: FbgParams = FbgParams(), rng: np.random.Generator | None = None):
    """(dl1, dl2) [pm]: dl1 = kT1 dT + n1, dl2 = S F + kT2 dT + n2.

    The seed's 12.59 pm RMSE is the error of the compensated shift dl2 - r dl1; it is split between the two
    gratings in proportion (n2 and r n1 carry equal variance), so the compensated force noise is noise/S.
    """
    F = np.asarray(force_N, dtype=float)
    dT = np.asarray(dT_C, dtype=float)
    dl1 = p.kT1_pm_C * dT
    dl2 = p.S_pm_N * F + p.kT2_pm_C * dT
    if rng is not None:
        s2 = p.noise_pm / np.sqrt(2.0)
        dl1 = dl1 + rng.normal(0.0, s2 / p.r, np.shape(dl1))
        dl2 = dl2 + rng.normal(0.0, s2, np.shape(dl2))
    return dl1, dl2


def plot_fbg_compensation(t_s, force_true, dl1_pm, dl2_pm, dT_C, p: FbgParams = FbgParams(), fc_hz: float = 0.1):
    """Figure like seed 001 Fig 4c: uncompensated, compensated and low-passed force, and the temperature."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    t = np.asarray(t_s, dtype=float)
    comp = fbg2force(dl1_pm, dl2_pm, p)
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(t, fbg2force_uncompensated(dl2_pm, p), color="tab:gray", lw=0.8, label="FBG2 only (uncompensated)")
    ax.plot(t, comp, color="tab:blue", lw=0.5, alpha=0.6, label=f"compensated, r = {p.r}")
    ax.plot(t, lowpass2(comp, 1.0 / np.median(np.diff(t)), fc_hz), color="tab:blue", lw=1.5,
            label=f"compensated, 2nd-order low-pass {fc_hz:g} Hz")
    ax.plot(t, np.broadcast_to(force_true, t.shape), "k--", lw=1, label="applied force")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("force [N]")
    ax2 = ax.twinx()
    ax2.plot(t, dT_C, color="tab:red", lw=1)
    ax2.set_ylabel("temperature change [degC]", color="tab:red")
    ax.legend(fontsize=8, loc="upper left")
    return fig


def lowpass2(x, fs_hz: float, fc_hz: float) -> np.ndarray:
    """Causal second-order Butterworth low-pass (the seed's filter), started at the first sample's value."""
    x = np.asarray(x, dtype=float)
    sos = butter(2, fc_hz, fs=fs_hz, output="sos")
    y, _ = sosfilt(sos, x, zi=sosfilt_zi(sos) * x[0])
    return y


# --------------------------------------------------------------------------------------------------------
# One sensor for all cables (seed 001 §2.2): pulling slope Kp, releasing slope Kr, flat transitions
# --------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ProximalDistalModel:
    """Proximal -> distal tension profile of a tendon-sheath (seed 001 eq 7, Fig 2b).

    Pulling line Fd = Kp Fp + bp, releasing line Fd = Kr Fp + br (Kp < Kr). Between the lines the distal
    tension stays flat (the transition phases): Fd_k = clip(Fd_{k-1}, lower line, upper line), a play operator
    (kernels sensor.eq7_step, eq7_start, eq7_run: `step`, `start` and `distal` are their faces).

    Attributes:
        Kp, Kr: pulling and releasing slopes dFd/dFp [-].
        bp, br: intercepts [N].
    """

    Kp: float
    Kr: float
    bp: float = 0.0
    br: float = 0.0

    def start(self, Fp: float) -> float:
        """Distal tension [N] of a first reading at proximal tension Fp [N]: on the lower line."""
        return eq7_start(float(Fp), self.Kp, self.Kr, self.bp, self.br)

    def step(self, Fd: float, Fp: float) -> float:
        """Distal tension [N] after proximal tension Fp [N] from the previous distal tension Fd [N]."""
        return eq7_step(float(Fd), float(Fp), self.Kp, self.Kr, self.bp, self.br)

    def distal(self, Fp, Fd0: float | None = None) -> np.ndarray:
        """(n,) distal tension estimate [N] from a proximal tension series Fp (n,) [N]: `step` along Fp.

        Fd0: the initial distal tension (default: `start` at Fp[0], on the lower line).
        """
        Fp = np.ascontiguousarray(Fp, dtype=float)
        return eq7_run(Fp, np.nan if Fd0 is None else float(Fd0), float(self.Kp), float(self.Kr), float(self.bp),
                       float(self.br), np.empty(Fp.shape[0]))


def fit_proximal_distal(Fp, Fd, min_step: float | None = None) -> ProximalDistalModel:
    """Identify Kp, Kr (and intercepts) from one instrumented cable's proximal/distal tensions [N].

    Stage 1: samples where Fp and Fd both rise (pulling) or both fall (releasing) by more than `min_step`
    (default: 3x the median |dFd|) give line fits; flat samples belong to the transitions. Stage 2 refines the
    four parameters by least squares of the play-operator prediction against Fd.
    """
    Fp = np.asarray(Fp, dtype=float)
    Fd = np.asarray(Fd, dtype=float)
    if Fp.shape != Fd.shape or Fp.ndim != 1 or Fp.size < 20:
        raise InputError("fit_proximal_distal: Fp and Fd must be 1-D series of the same length (>= 20)")
    dp, dd = np.diff(Fp), np.diff(Fd)
    step = 3.0 * np.median(np.abs(dd)) if min_step is None else min_step
    pull = (dp > 0) & (dd > step)
    rel = (dp < 0) & (dd < -step)
    if pull.sum() < 3 or rel.sum() < 3:
        raise InputError("fit_proximal_distal: the record needs both pulling and releasing phases")
    Kp, bp = np.polyfit(Fp[1:][pull], Fd[1:][pull], 1)
    Kr, br = np.polyfit(Fp[1:][rel], Fd[1:][rel], 1)

    def resid(z):
        return ProximalDistalModel(*z).distal(Fp, Fd[0]) - Fd

    sol = least_squares(resid, [Kp, Kr, bp, br], x_scale=[0.1, 0.1, 0.1, 0.1])
    return ProximalDistalModel(*map(float, sol.x))


def fit_proximal_distal_origin(Fp, Fd, direction=None) -> ProximalDistalModel:
    """Kp, Kr of seed 001 eq 7 with lines through the origin (eqs 4-6: Fd = Fp e^(-+a), bp = br = 0) from one
    instrumented cable's proximal and distal tensions Fp, Fd (n,) [N].

    Unlike `fit_proximal_distal` it needs no distal force swing: a record at a constant distal load whose
    cable is hauled in and paid out (the palpation's no-load runs) identifies both slopes, because the
    proximal force swings between Fd / Kp and Fd / Kr. Start: medians of Fd / Fp over the samples of each
    direction (`direction` (n,): +1 hauling in, -1 paying out; default from the sign of the change of Fp);
    then least squares of the play-operator prediction (ProximalDistalModel.distal) against Fd.
    """
    Fp = np.asarray(Fp, dtype=float)
    Fd = np.asarray(Fd, dtype=float)
    if Fp.shape != Fd.shape or Fp.ndim != 1 or Fp.size < 20 or not (np.all(np.isfinite(Fp)) and np.all(np.isfinite(Fd))):
        raise InputError("fit_proximal_distal_origin: Fp and Fd must be finite 1-D series of the same length (>= 20)")
    if np.min(Fp) <= 0:
        raise InputError("fit_proximal_distal_origin: the proximal tension must stay > 0 (a slack cable)")
    d = np.sign(np.r_[0.0, np.diff(Fp)]) if direction is None else np.sign(np.asarray(direction, dtype=float))
    ratio = Fd / Fp
    if np.count_nonzero(d > 0) < 5 or np.count_nonzero(d < 0) < 5:
        raise InputError("fit_proximal_distal_origin: the record needs both pulling and releasing phases")
    k0 = sorted((float(np.median(ratio[d > 0])), float(np.median(ratio[d < 0]))))

    def resid(z):
        return ProximalDistalModel(z[0], z[1]).distal(Fp, Fd[0]) - Fd

    sol = least_squares(resid, k0, x_scale=[0.1, 0.1])
    Kp, Kr = sorted(map(float, sol.x))
    return ProximalDistalModel(Kp, Kr)


# --------------------------------------------------------------------------------------------------------
# Sensor kinds of the robot's reading path (docs/formats.md "Robot readings: sensor kinds")
# --------------------------------------------------------------------------------------------------------

#: fsr: the FSR array at the proximal ends of the sheaths (seed 000); fbg: a dual-grating FBG on the distal
#: sheath of every cable (seed 001 sec. 2.1, temperature compensated by eq 3); one: the FSR array plus one
#: cable's distal FBG, the other cables' distal tensions from the eq 7 model identified on it (seed 001 sec. 2.2)
SENSOR_KINDS = ("fsr", "fbg", "one")


def check_sensor_kind(kind: str, where: str = "sensor") -> str:
    """`kind` if it is one of SENSOR_KINDS, else a one-line InputError naming `where`."""
    if kind not in SENSOR_KINDS:
        raise InputError(f"{where}: unknown sensor kind '{kind}' (expected one of: {', '.join(SENSOR_KINDS)})")
    return kind


def fbg_tensions(fbg_pm, p: FbgParams = FbgParams()) -> np.ndarray:
    """(..., n) tensions [N] from Bragg shifts fbg_pm (..., 2, n) [pm] (row 0 FBG1, row 1 FBG2): eq 3,
    `fbg2force`; NaN where a cable has no FBG."""
    a = np.asarray(fbg_pm, dtype=float)
    return fbg2force(a[..., 0, :], a[..., 1, :], p)
