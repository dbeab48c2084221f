"""Figures of the palpation tests: per-poke bars (seed 000 Fig 15/16 style) and the letter images (Fig 17)."""

from __future__ import annotations

import numpy as np

from scenes.materials import ATTRIBUTION

COLOURS = {"ground_truth": "black", "non_compensated": "tab:red", "single": "tab:orange", "double": "tab:blue",
           "dynamic": "tab:green"}


def plot_result(res):
    """A matplotlib Figure for a PalpationResult (Agg backend)."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")

    if res.test == "scan":
        fig = _scan_figure(res)
    else:
        fig = _bars_figure(res)
    fig.text(0.01, 0.005, ATTRIBUTION, fontsize=6, color="0.4")
    return fig


def _bars_figure(res):
    """Per poke label (Fig 16a: the 25 points) the mean over repeats, with the spread as error bars."""
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    keys = ["ground_truth"] + list(res.summary)
    labels = list(dict.fromkeys(p["label"] for p in res.pokes))
    n = len(labels)
    fig, ax = plt.subplots(figsize=(min(14.0, max(6.0, 0.5 * n + 2)), 4.2))
    x = np.arange(n)
    w = 0.8 / len(keys)
    top, bottom = 0.0, 0.0
    for i, k in enumerate(keys):
        vals = [[p[f"{k}_N"] for p in res.pokes if p["label"] == lab] for lab in labels]
        mean = np.array([np.mean(v) for v in vals])
        spread = np.array([np.std(v) for v in vals])
        top, bottom = max(top, (mean + spread).max()), min(bottom, (mean - spread).min())
        label = k if k == "ground_truth" else f"{k} (MAE {res.summary[k]['mean_abs_error_N']:.3f} N)"
        ax.bar(x + (i - (len(keys) - 1) / 2) * w, mean, w, yerr=spread if len(res.pokes) > n else None,
               color=COLOURS.get(k), label=label, error_kw={"elinewidth": 0.6})
    ax.set_ylim(bottom, top * 1.4)
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=90 if n > 12 else 0, fontsize=7)
    ax.set_xlabel("poke point" if res.test == "z" else "poke")
    ax.set_ylabel("force along the poke at its deepest point [N]")
    reps = len(res.pokes) // max(n, 1)
    ax.set_title(f"palpation {res.test} test, {res.profile} speed, seed {res.seed} (simulated"
                 f"{f', mean of {reps} repeats' if reps > 1 else ''})")
    ax.legend(fontsize=7, ncol=3 if n > 6 else 2, loc="upper left")
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    return fig


def _scan_figure(res):
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    grids = res.extra["grids"]
    keys = ["ground_truth", "non_compensated", "double", "dynamic"]
    fig, axes = plt.subplots(len(grids), len(keys), figsize=(3.0 * len(keys), 3.2 * len(grids)), squeeze=False)
    for r, (letter, g) in enumerate(grids.items()):
        mask = np.array(g["mask"])
        for c, k in enumerate(keys):
            a = np.array([[np.nan if v is None else v for v in row] for row in g[f"{k}_N"]], dtype=float)
            ax = axes[r, c]
            # row 0 is -y: draw with origin at the bottom like the pad seen from the robot
            im = ax.imshow(a, origin="lower", cmap="viridis", interpolation="nearest")
            ys, xs = np.nonzero(mask)
            ax.scatter(xs, ys, s=6, c="white", marker="s", alpha=0.5)
            ax.set_title(f"'{letter}' {k}", fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
            fig.colorbar(im, ax=ax, fraction=0.046, label="N")
    fig.suptitle(f"letter scan (6 x 7 pokes), {res.profile} speed, seed {res.seed} (simulated); "
                 f"white squares: rigid letter cells", fontsize=9)
    fig.tight_layout(rect=(0, 0.03, 1, 0.95))
    return fig
