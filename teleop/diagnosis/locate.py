"""Locate a residual: which condition explains it, and the time windows where it concentrates.

Each condition is a small set of regressors built from the link's signals; its evidence is the fraction
of the residual's variance a least-squares fit on them explains (R^2, with a constant). The conditions:

after motion reversals  sign of the motion since the last reversal, and its decay with travel
at high speed           velocity
at low speed            sign(v) exp(-|v| / v_low)
proportional to load    load and load x direction (load centred: a constant load x direction is
                        'after motion reversals')
during holds            indicator of |v| below 2 % of the peak speed
loading vs unloading    sign of the output's rate of change (held through pauses)
with position           position and its square about the mean (force links: a static, conservative force
                        beside the transmission, a spring)
drifting with temperature, drifting with time, periodic in position (sin/cos of the strongest of 64
harmonics over the travel), with indentation rate, with indentation depth (d^2: stiffening).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from teleop.core.physics.links import LinkData
from teleop.diagnosis.links import smooth

SWITCHING = ("after motion reversals", "loading vs unloading", "at low speed", "during holds")


def held_sign(v: np.ndarray, eps: float) -> np.ndarray:
    """(n,) sign of v held through |v| <= eps (the direction of the last motion; 0 before any)."""
    s = np.where(v > eps, 1.0, np.where(v < -eps, -1.0, 0.0))
    idx = np.where(s != 0, np.arange(s.size), 0)
    np.maximum.accumulate(idx, out=idx)
    out = s[idx]
    return out


def reversal_times(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times [s] where the held direction of x changes sign."""
    v = np.gradient(x, t)
    s = held_sign(v, 0.02 * float(np.max(np.abs(v))) + 1e-300)
    k = np.flatnonzero((s[1:] != s[:-1]) & (s[:-1] != 0)) + 1
    return t[k]


def _travel_since_reversal(x: np.ndarray, s: np.ndarray) -> np.ndarray:
    """|x - x at the last change of s| (n,)."""
    change = np.concatenate(([True], s[1:] != s[:-1]))
    idx = np.where(change, np.arange(x.size), 0)
    np.maximum.accumulate(idx, out=idx)
    return np.abs(x - x[idx])


def travel_phase(x: np.ndarray) -> np.ndarray:
    """(n,) the position as a phase over the travel [rad]: 0 at its lowest, 2 pi at its highest."""
    return 2 * np.pi * (x - x.min()) / (float(np.ptp(x)) + 1e-300)


def condition_features(d: LinkData, output: np.ndarray) -> dict:
    """condition -> (n, k) regressors available for this link."""
    f = {}
    n = d.n
    if d.x is not None:
        v = np.gradient(d.x, d.t)
        vmax = float(np.max(np.abs(v))) + 1e-300
        s = held_sign(v, 0.02 * vmax)
        span = float(np.ptp(d.x)) + 1e-300
        travel = _travel_since_reversal(d.x, s)
        f["after motion reversals"] = np.column_stack([s, s * np.exp(-travel / (0.05 * span))])
        f["at high speed"] = v[:, None]
        moving = np.abs(v) > 0.02 * vmax
        v_low = float(np.percentile(np.abs(v[moving]), 10)) if moving.sum() > 10 else 0.1 * vmax
        f["at low speed"] = (np.sign(v) * np.exp(-np.abs(v) / max(v_low, 1e-300)))[:, None]
        f["during holds"] = (~moving).astype(float)[:, None]
        f["periodic in position"] = travel_phase(d.x)   # harmonic picked later
        if d.link.kind == "force":   # a force beside the transmission (a spring); on a position link a
            dx = (d.x - float(np.mean(d.x))) / span   # static function of position is the gain's or the load's
            f["with position"] = np.column_stack([dx, dx * dx])
        if d.load is not None or d.link.kind == "force":
            load = d.u if d.link.kind == "force" else d.load
            dl = load - np.mean(load)
            f["proportional to load"] = np.column_stack([dl, dl * s])
    if d.link.kind != "position":  # loading/unloading: the state of a force channel
        rate = np.gradient(smooth(output, max(1, n // 200) | 1), d.t)
        f["loading vs unloading"] = held_sign(rate, 0.02 * float(np.max(np.abs(rate))) + 1e-300)[:, None]
    if d.temperature is not None:
        f["drifting with temperature"] = d.temperature[:, None]
    f["drifting with time"] = d.t[:, None]
    if d.link.kind == "contact":
        rate = np.gradient(smooth(d.u, max(1, n // 500) | 1), d.t)
        f["with indentation rate"] = rate[:, None]
        f["with indentation depth"] = (np.maximum(d.u, 0.0) ** 2)[:, None]
        holding = (d.u > 0) & (np.abs(rate) < 0.02 * float(np.max(np.abs(rate)) + 1e-300))
        # relaxation: the time held so far, inside each hold
        start = np.where(holding & ~np.concatenate(([False], holding[:-1])), np.arange(n), 0)
        np.maximum.accumulate(start, out=start)
        held = np.where(holding, d.t - d.t[start], 0.0)
        f["during holds"] = np.column_stack([holding.astype(float), held])
    return f


def periodic_features(phase: np.ndarray, r: np.ndarray, sl, harmonics: int = 64) -> np.ndarray:
    """(n, 2) sin/cos of the harmonic m (1..harmonics) of `phase` [rad over the travel] that projects
    most of r on samples sl (cogging, pulley eccentricity, a damaged tooth: periodic in position)."""
    ph, rr = phase[sl], r[sl] - np.mean(r[sl])
    m = np.arange(1, harmonics + 1)[:, None]
    power = np.abs(np.exp(1j * m * ph[None, ::max(1, ph.size // 4000)]) @ rr[::max(1, ph.size // 4000)])
    best = int(np.argmax(power)) + 1
    return np.column_stack([np.sin(best * phase), np.cos(best * phase)])


def explain(r: np.ndarray, X: np.ndarray) -> tuple[float, np.ndarray]:
    """(R^2, coefficients) of least squares of r on [1, X]: the fraction of var(r) explained."""
    A = np.column_stack([np.ones(r.size), X])
    coef, *_ = np.linalg.lstsq(A, r, rcond=None)
    tss = float(np.sum((r - r.mean()) ** 2))
    return (0.0 if tss <= 0 else max(0.0, 1.0 - float(np.sum((r - A @ coef) ** 2)) / tss)), coef


def r2(r: np.ndarray, X: np.ndarray) -> float:
    """Fraction of var(r) explained by least squares on [1, X]."""
    return explain(r, X)[0]


@dataclass(frozen=True)
class Location:
    """condition: best-explaining condition; evidence: {condition: R^2}; windows: [[t0, t1], ...] [s]."""

    condition: str
    evidence: dict
    windows: list

    def as_dict(self) -> dict:
        return {"condition": self.condition, "windows": self.windows,
                "evidence": {k: round(v, 4) for k, v in self.evidence.items()}}


def noise_level(r: np.ndarray) -> float:
    """White-noise standard deviation of r [r's unit] from its third differences (white noise of sigma gives
    them a variance of 20 sigma^2), robustly (MAD): a residual's smooth structure (a slow misfit, an input's
    smoothed noise carried through the model) leaves almost nothing in them, and its short events (a
    misfit at each reversal) fall outside the median; first differences kept both and read a misfit as
    noise. Their standard deviation where the MAD is 0 (a residual on a lattice)."""
    d3 = np.diff(r, 3)
    if not d3.size:
        return 0.0
    mad = float(np.median(np.abs(d3 - np.median(d3))))
    return (1.4826 * mad if mad > 0 else float(np.std(d3))) / math.sqrt(20.0)


def windows_from(t: np.ndarray, score: np.ndarray, frac: float = 0.5, max_windows: int = 40) -> list:
    """Merged intervals [[t0, t1], ...] where score > frac * its 99.5th percentile, strongest first."""
    top = float(np.percentile(score, 99.5))
    if top <= 0:
        return []
    on = score > frac * top
    if not on.any():
        return []
    T = float(t[-1] - t[0])
    edges = np.diff(np.concatenate(([0], on.astype(np.int8), [0])))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    merged = []
    for a, b in zip(starts, stops):
        if merged and t[a] - t[merged[-1][1]] < 0.01 * T:
            merged[-1][1] = b
        else:
            merged.append([a, b])
    ranked = sorted(merged, key=lambda ab: -float(np.sum(score[ab[0]:ab[1] + 1])))[:max_windows]
    return [[round(float(t[a]), 4), round(float(t[b]), 4)] for a, b in sorted(ranked)]


def locate(d: LinkData, r: np.ndarray, output: np.ndarray, index=None, change: np.ndarray | None = None
           ) -> Location:
    """Locate residual r (n,) of link d: the condition best explaining r (or, when given, `change`: an
    effect's contribution (n,)) on samples `index` (all when None); windows where the target switches
    (switching conditions) or is large (the others)."""
    sl = slice(None) if index is None else index
    target = r if change is None else change
    if d.link.kind == "contact":
        # a pad's static stiffness change (linear in depth) is the baseline gain's: project it out
        A = np.column_stack([np.ones(d.n), np.maximum(d.u, 0.0)])
        coef, *_ = np.linalg.lstsq(A[sl], target[sl], rcond=None)
        target = target - A @ coef
    feats = condition_features(d, output)
    if "periodic in position" in feats:
        feats["periodic in position"] = periodic_features(feats["periodic in position"], target, sl)
    ev = {name: r2(target[sl], X[sl]) for name, X in feats.items()}
    best = max(ev, key=ev.get)
    width = max(1, d.n // 400) | 1
    if best in SWITCHING:
        # where the part of the target that the condition explains switches (noise-free by construction)
        _, coef = explain(target[sl], feats[best][sl])
        explained = np.column_stack([np.ones(d.n), feats[best]]) @ coef
        score = smooth(np.abs(np.gradient(explained)), width)
    else:
        score = smooth(np.abs(target - np.median(target)), width)
    ev = dict(sorted(ev.items(), key=lambda kv: -kv[1]))
    return Location(best, ev, windows_from(d.t, score))
