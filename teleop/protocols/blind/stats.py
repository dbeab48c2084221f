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
    """Stiffness dF/dx [N/m] of the loading phase of one poke.

    x: (n,) displacement into the pad [m]; f: (n,) force pushing back [N]. The loading phase runs from
    the start to the deepest sample; samples where the force exceeds `f_min` and stays below 90 % of its
    loading peak are fitted by least squares (F = k x + c). Returns 0 when no force was felt.
    """
    x = np.asarray(x, dtype=float)
    f = np.asarray(f, dtype=float)
    if x.size < 3:
        return 0.0
    end = int(np.argmax(x)) + 1
    xl, fl = x[:end], f[:end]
    peak = float(fl.max()) if fl.size else 0.0
    if peak <= f_min:
        return 0.0
    sel = (fl > f_min) & (fl <= max(0.9 * peak, f_min + 1e-12))
    if sel.sum() < 3 or np.ptp(xl[sel]) <= 0:
        sel = fl > f_min
        if sel.sum() < 2 or np.ptp(xl[sel]) <= 0:
            return 0.0
    k, _ = np.polyfit(xl[sel], fl[sel], 1)
    return float(max(k, 0.0))
