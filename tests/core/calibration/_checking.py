"""Calibration data for checking the fits' standard errors: made here, not by the project's generator.

teleop.core.calibration.generate makes one shape per kind (the seed's protocols: white noise of one level,
the FSR's branch lag on the default quintic, 0-20 N FBG steps of 2 N with a half-sine loop, a sine-driven
spring through the capstan law with 1 % stick transitions). The fits were written looking at those files.
The data below vary what the generator holds fixed, each run drawn from its own seeded generator:

- fsr_runs: per branch a polynomial of degree 1 to 4 in tension (the loading and unloading curves
  independent, not one curve and a lag), with or without a conductance at zero tension; 6 to 16 weight
  levels (8 at least in one pass) up to 3-9 N, 1 to 4 passes; noise 0.05-1 uS RMS, white or growing with the conductance
  (heteroscedastic), or with an AR(1) drift along the protocol.
- fbg_runs: S 8-60 pm/N, kT1 4-20 pm/degC, r 1.3-3.2; 2-4 temperatures; 5-15 force levels to 5-40 N;
  holds of 5-25 samples; a loop gap shaped 4u(1-u)(1 + c (2u - 1)) (lopsided arch) of 0-6 % of full scale;
  noise 1-15 pm, white or AR(1) (rho 0.3-0.9, a slow wander inside each hold and across holds);
  reference-force noise 0-0.02 N; zero offsets on both gratings.
- one_sensor_runs: eq 7's play between the lines Kp Fp + bp and Kr Fp + br (Kp 0.4-0.9, Kr 1.1-2.4, the
  intercepts zero in half the runs, else +-0.6 N) driven by a sine, a triangle or two sines between the
  releasing line's and the pulling line's ends of a 3-10 N distal swing from 1-4 N; 2-6 cycles of
  400-3000 samples; distal noise 0.005-0.15 N white or AR(1) (rho 0.5-0.97), proximal noise 0-0.02 N.

Each *_runs function returns (inputs, truth) per run; the truth is what a 95 % interval (1.96 standard
errors) of the fit's reported value should hold. `coverage(kind, n_runs)` fits them and gives the fraction
of intervals that hold, per quantity; `python -m tests.core.calibration._checking [N] [SEED]` prints it for
the three kinds.
"""

from __future__ import annotations

import numpy as np

import sys

from numpy.polynomial import polynomial as P

from teleop.core.calibration.fbg import FbgData, fit_fbg, loading_state
from teleop.core.calibration.fsr import fit_fsr
from teleop.core.calibration.one_sensor import fit_one_sensor, transition_width
from teleop.core.sensors import LOADING, UNLOADING, FsrCalibrationData, ProximalDistalModel


def _ar1(rng, n: int, rho: float, sigma: float) -> np.ndarray:
    """(n,) AR(1) noise of stationary RMS sigma and lag-one correlation rho."""
    e = rng.normal(0.0, sigma * np.sqrt(1.0 - rho * rho), n)
    x = np.empty(n)
    x[0] = rng.normal(0.0, sigma)
    for k in range(1, n):
        x[k] = rho * x[k - 1] + e[k]
    return x


def fsr_runs(n_runs: int, seed: int = 0):
    """[(FsrCalibrationData, truth)]: truth(t, branch) the noise-free conductance [S] (module docstring)."""
    out = []
    for i in range(n_runs):
        rng = np.random.default_rng([seed, 1, i])
        top = rng.uniform(3.0, 9.0)
        passes = int(rng.integers(1, 5))
        levels = np.linspace(0.0, top, int(rng.integers(8 if passes == 1 else 6, 17)))
        coefs = {}
        for b in (LOADING, UNLOADING):
            deg = int(rng.integers(1, 5))
            # a monotone-ish curve: positive slope at 0 and bends up to +-40 % of the linear rise at the top
            c = np.zeros(6)
            c[0] = 0.0 if rng.random() < 0.5 else rng.uniform(0.5, 5.0)
            c[1] = rng.uniform(2.0, 10.0)
            for k in range(2, deg + 1):
                c[k] = rng.uniform(-0.4, 0.4) * c[1] / top ** (k - 1)
            coefs[b] = c * 1e-6
        t, b = [], []
        for _ in range(passes):
            t += list(levels) + list(levels[-2::-1])
            b += [LOADING] * levels.size + [UNLOADING] * (levels.size - 1)
        t, b = np.array(t), np.array(b)
        g = np.where(b == LOADING, np.polynomial.polynomial.polyval(t, coefs[LOADING]),
                     np.polynomial.polynomial.polyval(t, coefs[UNLOADING]))
        sigma = rng.uniform(0.05, 1.0) * 1e-6
        colour = rng.integers(3)
        if colour == 0:
            noise = rng.normal(0.0, sigma, t.size)
        elif colour == 1:      # heteroscedastic: grows with the reading
            noise = rng.normal(0.0, 1.0, t.size) * sigma * (0.3 + 1.4 * g / g.max())
        else:                  # drift along the protocol plus white noise
            noise = _ar1(rng, t.size, rng.uniform(0.3, 0.8), sigma)
        data = FsrCalibrationData(t, g + noise, b, source=f"checking fsr {i}")
        out.append((data, lambda tt, bb, c=coefs: np.where(
            np.asarray(bb) == LOADING, np.polynomial.polynomial.polyval(tt, c[LOADING]),
            np.polynomial.polynomial.polyval(tt, c[UNLOADING]))))
    return out


def fbg_runs(n_runs: int, seed: int = 0):
    """[(FbgData, truth)]: truth {"S_pm_N", "kT1_pm_C", "kT2_pm_C", "r", "hysteresis_N"} (module docstring;
    hysteresis_N the largest loading - unloading gap as a force)."""
    out = []
    for i in range(n_runs):
        rng = np.random.default_rng([seed, 2, i])
        S, kT1, r = rng.uniform(8.0, 60.0), rng.uniform(4.0, 20.0), rng.uniform(1.3, 3.2)
        top = rng.uniform(5.0, 40.0)
        nlev = int(rng.integers(5, 16))
        levels = np.linspace(0.0, top, nlev)
        cycle = np.r_[levels, levels[-2::-1]]
        direction = np.r_[np.ones(nlev), -np.ones(nlev - 1)]
        temps = np.sort(rng.uniform(15.0, 70.0, int(rng.integers(2, 5))))
        temps[-1] = max(temps[-1], temps[0] + 8.0)
        hold = int(rng.integers(5, 26))
        F = np.repeat(np.tile(cycle, temps.size), hold)
        d = np.repeat(np.tile(direction, temps.size), hold)
        T = np.repeat(temps, cycle.size * hold) + rng.normal(0.0, 0.05, F.size)
        gap_pct, tilt = rng.uniform(0.0, 6.0), rng.uniform(-0.5, 0.5)
        u = F / top
        shape = 4 * u * (1 - u) * (1 + tilt * (2 * u - 1))
        grid = np.linspace(0, 1, 2001)
        peak = float(np.max(4 * grid * (1 - grid) * (1 + tilt * (2 * grid - 1))))
        gap_N = gap_pct / 100 * top                      # largest gap as a force
        half = 0.5 * gap_N * shape / peak
        sigma = rng.uniform(1.0, 15.0)
        rho = 0.0 if rng.random() < 0.5 else rng.uniform(0.3, 0.9)
        n1 = _ar1(rng, F.size, rho, sigma / np.sqrt(2) / r)
        n2 = _ar1(rng, F.size, rho, sigma / np.sqrt(2))
        c1, c2 = rng.uniform(-50, 50, 2)
        dl1 = kT1 * (T - temps[0]) + c1 + n1
        dl2 = S * (F + d * half) + r * kT1 * (T - temps[0]) + c2 + n2
        F_ref = F + rng.normal(0.0, rng.uniform(0.0, 0.02), F.size)
        data = FbgData(F_ref, T, dl1, dl2, loading_state(F_ref), source=f"checking fbg {i}")
        out.append((data, {"S_pm_N": S, "kT1_pm_C": kT1, "kT2_pm_C": r * kT1, "r": r, "hysteresis_N": gap_N}))
    return out


def _play(Fp: np.ndarray, Kp: float, Kr: float, bp: float, br: float) -> np.ndarray:
    """Distal force of seed 001 eq 7 written out here: flat between the two lines, on the lower one first."""
    lo, hi = Kp * Fp + bp, Kr * Fp + br
    Fd = np.empty_like(Fp)
    Fd[0] = lo[0]
    for k in range(1, Fp.size):
        Fd[k] = min(max(Fd[k - 1], lo[k]), hi[k])
    return Fd


def one_sensor_runs(n_runs: int, seed: int = 0):
    """[((Fp, Fd), truth)]: truth {"Kp", "Kr", "bp", "br"} (module docstring)."""
    out = []
    for i in range(n_runs):
        rng = np.random.default_rng([seed, 3, i])
        Kp, Kr = rng.uniform(0.4, 0.9), rng.uniform(1.1, 2.4)
        bp, br = (0.0, 0.0) if rng.random() < 0.5 else tuple(rng.uniform(-0.6, 0.6, 2))
        n = int(rng.integers(400, 3001))
        cycles = int(rng.integers(2, 7))
        ph = 2 * np.pi * cycles * np.arange(n) / n
        # the swing reaches both lines: the distal force between lo and hi, the proximal between the
        # releasing line's lo and the pulling line's hi
        lo = rng.uniform(1.0, 4.0)
        hi = lo + rng.uniform(3.0, 10.0)
        Fp_lo, Fp_hi = (lo - br) / Kr, (hi - bp) / Kp
        mean, amp = 0.5 * (Fp_lo + Fp_hi), 0.5 * (Fp_hi - Fp_lo)
        kind = rng.integers(3)
        wave = (np.sin(ph) if kind == 0 else 2 / np.pi * np.arcsin(np.sin(ph)) if kind == 1
                else (np.sin(ph) + 0.35 * np.sin(3.1 * ph + 1.0)) / 1.35)
        Fp = mean + amp * wave
        Fd = _play(Fp, Kp, Kr, bp, br)
        sigma = rng.uniform(0.005, 0.15)
        rho = 0.0 if rng.random() < 0.5 else rng.uniform(0.5, 0.97)
        Fd_meas = Fd + _ar1(rng, n, rho, sigma)
        Fp_meas = Fp + rng.normal(0.0, rng.uniform(0.0, 0.02), n)
        out.append(((Fp_meas, Fd_meas), {"Kp": Kp, "Kr": Kr, "bp": bp, "br": br}))
    return out


Z95 = 1.959964  # the normal distribution's 97.5 % point


def coverage(kind: str, n_runs: int = 100, seed: int = 0) -> dict:
    """Fraction of 95 % intervals (value +- 1.96 reported standard errors) that hold the truth, per quantity,
    over n_runs checking calibrations of `kind` (fsr: the curve at 1/4, 1/2, 3/4 of the top tension on
    both branches, through the coefficients' covariance, pooled as "curve"; one-sensor also the transition
    widths at the top and bottom turns, pooled as "transition_width")."""
    hold = {}
    if kind == "one-sensor":
        for (Fp, Fd), truth in one_sensor_runs(n_runs, seed):
            fit = fit_one_sensor(Fp, Fd)
            for k, v in truth.items():
                hold.setdefault(k, []).append(abs(getattr(fit.model, k) - v) <= Z95 * fit.stderr[k] + 1e-12)
            true_model = ProximalDistalModel(truth["Kp"], truth["Kr"], truth["bp"], truth["br"])
            for w in fit.widths.values():
                hold.setdefault("transition_width", []).append(
                    abs(w["width"] - float(transition_width(true_model, w["distal"]))) <= Z95 * w["stderr"])
    elif kind == "fbg":
        for data, truth in fbg_runs(n_runs, seed):
            fit = fit_fbg(data)
            for k, v in truth.items():
                hold.setdefault(k, []).append(abs(fit.values[k] - v) <= Z95 * fit.stderr[k])
    elif kind == "fsr":
        for data, truth in fsr_runs(n_runs, seed):
            fit = fit_fsr(data)
            t = np.array([0.25, 0.5, 0.75]) * float(np.max(data.tension))
            V = P.polyvander(t, 5)
            for b, name in ((LOADING, "loading"), (UNLOADING, "unloading")):
                c = np.asarray(fit.cal.loading if b == LOADING else fit.cal.unloading)
                se = np.sqrt(np.einsum("ij,jk,ik->i", V, fit.cov[name], V))
                hold.setdefault("curve", []).extend(np.abs(V @ c - truth(t, b)) <= Z95 * se)
    else:
        raise ValueError(f"kind must be fsr, fbg or one-sensor, got {kind!r}")
    return {k: float(np.mean(v)) for k, v in hold.items()}


if __name__ == "__main__":
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    first = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    for name in ("fsr", "fbg", "one-sensor"):
        print(name, {k: round(v, 3) for k, v in coverage(name, runs, first).items()})
