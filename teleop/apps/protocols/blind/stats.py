"""Statistics of a ranking study: Kendall's tau against the true order, Kendall's W across participants,
Table 3 summary (mean, std per area), and the stiffness rendered on the stylus from force-displacement traces.
"""

from __future__ import annotations

import numpy as np

# Seed 000 Table 3, hardest first (true order rigid > Dragon Skin 30 > Ecoflex 00-50 > Ecoflex 00-20): the
# ratings of its ten participants and the mean and sample std (ddof=1) per area as printed. The printed std
# of the white row (0.80) does not follow from its printed ratings (0.88 with ddof=1); the others do.
SEED_TABLE3 = (
    {"colour": "black", "material": "rigid PLA", "ratings": (10, 9, 9, 10, 10, 8, 10, 9, 9, 10),
     "mean": 9.4, "std": 0.70},
    {"colour": "red", "material": "Dragon Skin 30", "ratings": (6, 7, 7, 7, 6, 5, 7, 7, 7, 8),
     "mean": 6.7, "std": 0.82},
    {"colour": "yellow", "material": "Ecoflex 00-50", "ratings": (4, 6, 6, 4, 4, 3, 4, 5, 4, 5),
     "mean": 4.5, "std": 0.97},
    {"colour": "white", "material": "Ecoflex 00-20", "ratings": (1, 3, 3, 2, 1, 1, 1, 2, 2, 3),
     "mean": 1.9, "std": 0.80},
)


def kendall_tau(ranking, truth) -> float:
    """Kendall's tau-a between two rankings of the same items (each a sequence, hardest first); in [-1, 1]."""
    pos = {item: i for i, item in enumerate(ranking)}
    r = np.array([pos[item] for item in truth], dtype=float)
    n = r.size
    if n < 2:
        return 1.0
    i, j = np.triu_indices(n, 1)
    s = np.sign(r[j] - r[i])   # truth has i before j; concordant when ranking also has i before j
    return float(s.sum() / (n * (n - 1) / 2))


def average_ranks(row) -> np.ndarray:
    """(n,) ranks 1..n of a row, ties sharing their average rank (as scipy.stats.rankdata)."""
    v = np.asarray(row, dtype=float)
    order = np.argsort(v, kind="mergesort")
    ranks = np.empty(v.size)
    ranks[order] = np.arange(1, v.size + 1)
    for value in np.unique(v):
        tie = v == value
        ranks[tie] = ranks[tie].mean()
    return ranks


def kendall_w(ratings: np.ndarray) -> float:
    """Kendall's coefficient of concordance W (with the tie correction) of an (m raters, n items) array.

    W = 12 S / (m^2 (n^3 - n) - m T), S = sum over items of (R_j - mean R)^2, T = sum over raters of
    sum (t^3 - t) over tie groups. 1 = every rater ranks alike, 0 = no agreement.
    """
    ratings = np.asarray(ratings, dtype=float)
    m, n = ratings.shape
    if m < 1 or n < 2:
        return float("nan")
    ranks = np.vstack([average_ranks(row) for row in ratings])
    R = ranks.sum(axis=0)
    S = float(((R - R.mean()) ** 2).sum())
    T = 0.0
    for row in ratings:
        _, counts = np.unique(row, return_counts=True)
        T += float((counts ** 3 - counts).sum())
    denom = m * m * (n ** 3 - n) - m * T
    return float(12.0 * S / denom) if denom > 0 else 1.0


def mean_std(values) -> tuple:
    """Mean and sample standard deviation (ddof=1, as Table 3) of a sequence; std 0 for one value."""
    v = np.asarray(values, dtype=float)
    return float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0


def loading_slope(x: np.ndarray, f: np.ndarray, f_min: float = 0.02) -> float:
    """Stiffness dF/dx [N/m] of the loading phase of one poke: the Theil-Sen slope (median of the pairwise
    slopes; Theil 1950, Sen 1968) of the force against the displacement.

    x: (n,) displacement into the pad [m]; f: (n,) force pushing back [N]. The loading phase runs from the
    start to the deepest sample; its samples where the stylus is at its deepest so far (a hand pushed back
    by the rendered force and pushing on again is loading only once it passes its earlier depth) and the
    force exceeds `f_min` (felt) and stays below 98 % of the loading peak (a force clamped at the device
    limit stays flat at its peak while the stylus goes on) are used. The median of pairwise slopes ignores
    up to ~29 % of stray samples, which a least-squares line does not: a force felt before the contact
    (friction-compensation residue, up to ~0.06 N on the stylus after a previous poke; least squares read
    66 N/m on a 200 N/m area there).
    Only the last contact before the peak counts: a force felt and lost again on the way in (a blip in free
    travel: the FSR's loading state crossing over at the press's reversal, ~0.1 N on the stylus for a few
    tens of ms; it read rigid PLA as 113-118 N/m instead of ~500 in 2 of 10 rigid presses with seed 3)
    is not the pad; the loading phase starts after the last sample before the peak where the force was
    gone (at or below f_min / 4: the rendered force back to ~nothing, not a noisy dip near the threshold).
    Returns 0 when no force was felt.
    """
    x = np.asarray(x, dtype=float)
    f = np.asarray(f, dtype=float)
    if x.size < 3:
        return 0.0
    end = int(np.argmax(x)) + 1
    xl, fl = x[:end], f[:end]
    lost = np.nonzero(fl[:int(np.argmax(fl))] <= 0.25 * f_min)[0]  # the last contact starts after the last of these
    if lost.size:
        xl, fl = xl[lost[-1] + 1:], fl[lost[-1] + 1:]
    if xl.size < 2:
        return 0.0
    front = xl >= np.maximum.accumulate(xl)  # the stylus at its deepest so far (a bounce back is skipped)
    below_peak = fl < _PLATEAU * fl.max()    # a force held flat at its peak (a device clamp) has no slope
    sel = np.nonzero(front & below_peak & (fl > f_min))[0]
    if sel.size < 2:
        return 0.0
    if sel.size > _THEIL_MAX:  # evenly thinned: the median of pairwise slopes over <= _THEIL_MAX samples
        sel = sel[np.linspace(0, sel.size - 1, _THEIL_MAX).round().astype(int)]
    xs, fs = xl[sel], fl[sel]
    i, j = np.triu_indices(xs.size, 1)
    dx = xs[j] - xs[i]
    ok = np.abs(dx) > _DX_MIN
    if not ok.any():
        return 0.0
    k = float(np.median((fs[j] - fs[i])[ok] / dx[ok]))
    return max(k, 0.0)


_PLATEAU = 0.98   # fraction of the loading peak above which the force counts as held flat
_THEIL_MAX = 400   # samples in a Theil-Sen fit (80k pairs)
_DX_MIN = 1e-6     # [m] pairs closer than this in displacement carry no slope (stylus resolution ~ 0.055 mm)
