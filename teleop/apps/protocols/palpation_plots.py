"""Figures of the palpation tests: per-poke bars (seed 000 Fig 15/16 style) and the letter images (Fig 17).
Each title names the test, the plant and the sensor; estimators whose forces are identical on every poke
(with --sensor fbg|one every estimator name runs the same tensions) are drawn once, their names joined."""

from __future__ import annotations

import numpy as np

from scenes.materials import ATTRIBUTION
from scenes.pads import SCAN_COLS, SCAN_ROWS, scan_grid
from teleop.io.figures import legend_outside

COLOURS = {"ground_truth": "black", "non_compensated": "tab:red", "single": "tab:orange", "double": "tab:blue",
           "dynamic": "tab:green"}
TEST_NAMES = {"stiffness": "stiffness test (seed 000 Table 1)", "z": "z test (seed 000 Fig 16a)",
              "xy": "x/y test in the hole (seed 000 Fig 16b,c)", "scan": "letter scan (seed 000 Fig 17)"}
SENSOR_NAMES = {"fsr": "FSR array", "fbg": "FBG on every cable (seed 001)",
                "one": "FSR array + one cable's FBG (seed 001 sensor model)"}


def figure_title(res) -> str:
    """What the figure shows: the test, the plant, the sensor, the speed profile and the seed."""
    sensor = res.params.get("sensor", "fsr")
    plant = res.extra.get("plant", {}).get("name", "matched")
    return (f"teleop palpate: {TEST_NAMES.get(res.test, res.test)}, simulated robot\n"
            f"plant {plant}, sensor {sensor} ({SENSOR_NAMES.get(sensor, sensor)}), "
            f"{res.profile} speed, seed {res.seed}")


def distinct_estimators(res, keys) -> list:
    """[(label, [keys])]: `keys` grouped where every poke's force is the same, in their order."""
    groups = []
    for k in keys:
        v = [p[f"{k}_N"] for p in res.pokes]
        for g in groups:
            if g[1] == v:
                g[2].append(k)
                break
        else:
            groups.append((k, v, [k]))
    return [(group_label(res, ks), ks) for _, _, ks in groups]


def group_label(res, ks) -> str:
    """A legend name for estimators `ks` whose forces are identical."""
    sensor = res.params.get("sensor", "fsr")
    if len(ks) > 1 and len(ks) == len(res.summary) and sensor != "fsr":
        return f"every estimator (same tip tensions from sensor {sensor})"
    return " = ".join(ks)


def plot_result(res):
    """A matplotlib Figure for a PalpationResult (Agg backend)."""
    import matplotlib  # heavy: loaded only to draw

    matplotlib.use("Agg")

    if res.test == "scan":
        fig = _scan_figure(res)
    else:
        fig = _bars_figure(res)
    fig.text(0.01, 0.0, ATTRIBUTION, fontsize=6, color="0.4", va="top")  # under the axes (saved tight)
    return fig


def _bars_figure(res):
    """Per poke label (Fig 16a: the 25 points) the mean over repeats, with the spread as error bars."""
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    groups = [("ground_truth", ["ground_truth"])] + distinct_estimators(res, list(res.summary))
    labels = list(dict.fromkeys(p["label"] for p in res.pokes))
    n = len(labels)
    fig, ax = plt.subplots(figsize=(min(14.0, max(6.0, 0.5 * n + 2)) + 3.0, 4.2))  # + the legend
    x = np.arange(n)
    w = 0.8 / len(groups)
    top, bottom = 0.0, 0.0
    for i, (name, ks) in enumerate(groups):
        k = ks[0]
        vals = [[p[f"{k}_N"] for p in res.pokes if p["label"] == lab] for lab in labels]
        mean = np.array([np.mean(v) for v in vals])
        spread = np.array([np.std(v) for v in vals])
        top, bottom = max(top, (mean + spread).max()), min(bottom, (mean - spread).min())
        label = "ground truth (pad)" if k == "ground_truth" else \
            f"{name} (MAE {res.summary[k]['mean_abs_error_N']:.3f} N)"
        ax.bar(x + (i - (len(groups) - 1) / 2) * w, mean, w, yerr=spread if len(res.pokes) > n else None,
               color=COLOURS.get(ks[-1]), label=label, error_kw={"elinewidth": 0.6})
    ax.set_ylim(bottom, top * 1.05)
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=90 if n > 12 else 0, fontsize=7)
    ax.set_xlabel({"z": "poke point", "stiffness": "pad region"}.get(res.test, "poke"))
    ax.set_ylabel("force along the poke\nat its deepest point [N]")
    reps = len(res.pokes) // max(n, 1)
    ax.set_title(figure_title(res) + (f", mean of {reps} pokes each" if reps > 1 else ""), fontsize=9)
    legend_outside(ax, "right", title="force", title_fontsize=7)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    return fig


def _scan_figure(res):
    """Per letter (rows) and estimator (columns) the force of each poke on the pad's x/y grid [mm], all panels on
    one colour scale so that an offset (the uncompensated estimate's) shows as a colour shift."""
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    grids = res.extra["grids"]
    first = next(iter(grids.values()))
    present = [k for k in res.summary if f"{k}_N" in first]
    # the grids' values decide which estimators are the same: every poke of every letter
    groups = [("ground truth (pad)", ["ground_truth"])]
    for k in present:
        v = [g[f"{k}_N"] for g in grids.values()]
        for g in groups[1:]:
            if [gg[f"{g[1][0]}_N"] for gg in grids.values()] == v:
                g[1].append(k)
                break
        else:
            groups.append((k, [k]))
    groups = [(lab if len(ks) == 1 else group_label(res, ks), ks) for lab, ks in groups]

    def values(g, k):
        return np.array([[np.nan if v is None else v for v in row] for row in g[f"{k}_N"]], dtype=float)

    every = np.concatenate([values(g, ks[0]).ravel() for g in grids.values() for _, ks in groups])
    every = every[np.isfinite(every)]
    vmin, vmax = (float(every.min()), float(every.max())) if every.size else (0.0, 1.0)
    pts = scan_grid() * 1e3                                   # [row, col, xy] poke points [mm]
    cw, ch = (pts[0, 1, 0] - pts[0, 0, 0]), (pts[1, 0, 1] - pts[0, 0, 1])
    extent = (pts[0, 0, 0] - cw / 2, pts[0, -1, 0] + cw / 2, pts[0, 0, 1] - ch / 2, pts[-1, 0, 1] + ch / 2)
    fig, axes = plt.subplots(len(grids), len(groups), figsize=(2.9 * len(groups) + 1.2, 3.3 * len(grids) + 1.0),
                             squeeze=False, layout="constrained")
    for r, (letter, g) in enumerate(grids.items()):
        mask = np.array(g["mask"])
        ys, xs = np.nonzero(mask)
        for c, (label, ks) in enumerate(groups):
            ax = axes[r, c]
            # row 0 is -y: drawn with origin at the bottom like the pad seen from the robot
            im = ax.imshow(values(g, ks[0]), origin="lower", cmap="viridis", interpolation="nearest",
                           vmin=vmin, vmax=vmax, extent=extent)
            ax.scatter(pts[ys, xs, 0], pts[ys, xs, 1], s=6, c="white", marker="s", alpha=0.5)
            mae = "" if ks[0] == "ground_truth" else f"\nMAE {res.summary[ks[0]]['mean_abs_error_N']:.3f} N"
            ax.set_title(f"'{letter}': {label}{mae}", fontsize=8)
            ax.set_xlabel("x [mm]", fontsize=8)
            ax.set_ylabel("y [mm]", fontsize=8)
            ax.tick_params(labelsize=7)
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8,
                 label="force along the poke at its deepest point [N] (one scale for every panel)")
    fig.suptitle(figure_title(res) + f"\nper letter {SCAN_COLS} x {SCAN_ROWS} cells; white squares: rigid letter "
                 f"cells; blank: not poked; MAE over all the pokes", fontsize=9)
    return fig
