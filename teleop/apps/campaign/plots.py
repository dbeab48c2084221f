"""Campaign figures: correct-ranking curves against the JND with their confidence intervals, and the
findings heat map of a fleet of recordings."""

from __future__ import annotations

import math

import numpy as np

from teleop.io.figures import legend_outside

CURVES_PER_AXES = 6


def _pyplot():
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    return plt


def jnd_curves_figure(curves: list, title: str):
    """curves: [(label, points)] with points as blind.curve_points. Correct-ranking share against the JND
    [%] with 95 % Wilson intervals, up to CURVES_PER_AXES curves per panel (nudged sideways so the
    intervals do not hide each other); one curve also shows its mean Kendall tau."""
    plt = _pyplot()
    panels = math.ceil(len(curves) / CURVES_PER_AXES)
    cols = min(panels, 2)
    rows = math.ceil(panels / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(9.5 * cols, 4.5 * rows), squeeze=False)
    for i, ax in enumerate(axes.flat):
        group = curves[i * CURVES_PER_AXES:(i + 1) * CURVES_PER_AXES]
        if not group:
            ax.set_visible(False)
            continue
        xs_all = sorted({pt["jnd"] * 100 for _, pts in group for pt in pts})
        # the curves' markers spread over at most a sixth of the closest JND spacing (1.5 % of the axis)
        spread = min(min(np.diff(xs_all)) / 6, 0.015 * (xs_all[-1] - xs_all[0])) if len(xs_all) > 1 else 0.0
        for k, (label, pts) in enumerate(group):
            nudge = (k - (len(group) - 1) / 2) / max(len(group) - 1, 1) * spread
            x = [pt["jnd"] * 100 + nudge for pt in pts]
            y = [pt["correct_ranking_rate"] for pt in pts]
            err = [[pt["correct_ranking_rate"] - pt["ci95"][0] for pt in pts],
                   [pt["ci95"][1] - pt["correct_ranking_rate"] for pt in pts]]
            ax.errorbar(x, y, yerr=err, fmt="o-", capsize=3, ms=4,
                        label=f"{label} (n={pts[0]['participants']})" if len(curves) > 1 else
                        "all four in the right order (95 % CI)")
            if len(curves) == 1:
                ax.plot(x, [pt["kendall_tau_mean"] for pt in pts], "s--", label="mean Kendall tau")
        ax.axvline(23, color="grey", ls="--", lw=0.8, label="Jones & Hunter 1990: 23 %")
        ax.set_xlabel("participants' stiffness JND [%]")
        ax.set_ylabel("share ranking all four correctly [-]" if len(curves) > 1 else "share / tau [-]")
        ax.set_ylim(-0.02, 1.02)
        legend_outside(ax, "right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def findings_heatmap(recordings: list, columns: list, matrix: np.ndarray, title: str):
    """Held-out improvement (RMSE before / after the effect is modelled) per recording (rows) and
    effect on a channel (columns); blank where the effect was not found. Colour on a log scale."""
    plt = _pyplot()
    from matplotlib.colors import LogNorm  # heavy: loaded only to draw

    n_r, n_c = matrix.shape
    fig, ax = plt.subplots(figsize=(max(5.0, 1.3 * n_c + 3.5), max(4.0, 0.35 * n_r + 2.5)))
    shown = np.ma.masked_invalid(matrix)
    finite = matrix[np.isfinite(matrix)]
    vmax = max(float(finite.max()) if finite.size else 2.0, 1.01)
    im = ax.imshow(shown, aspect="auto", cmap="viridis", norm=LogNorm(vmin=1.0, vmax=vmax))
    for i in range(n_r):
        for j in range(n_c):
            v = matrix[i, j]
            if np.isfinite(v):
                ax.text(j, i, f"x{v:.2f}", ha="center", va="center", fontsize=7,
                        color="white" if v < math.sqrt(vmax) else "black")
    ax.set_xticks(range(n_c), columns, rotation=30, ha="right", fontsize=8)
    ax.set_yticks(range(n_r), recordings, fontsize=8)
    ax.set_xlabel("effect on channel" + (" (blank: not found on that recording)" if np.isnan(matrix).any() else ""))
    ax.set_ylabel("recording")
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator  # heavy: loaded only to draw

    cb = fig.colorbar(im, ax=ax, label="RMSE before / after [-]")
    ticks = [t for t in (1, 1.5, 2, 3, 5, 10, 20, 50, 100, 1000) if t <= vmax]
    cb.ax.yaxis.set_major_locator(FixedLocator(ticks))
    cb.ax.yaxis.set_minor_locator(NullLocator())
    cb.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"x{v:g}"))
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return fig
