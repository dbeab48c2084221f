"""The commands' figures, checked on their matplotlib objects (no pixels): a title that says what the figure is
(the test, the plant, the sensor), every data axis labelled with a unit in brackets, legends outside every
data area, and one colour scale where panels are compared. Each figure is built from small inputs made here
(or the examples/ calibration files), not from a simulation run."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.ticker import LogFormatter, ScalarFormatter

from scenes.pads import SCAN_COLS, SCAN_ROWS, letter_mask
from teleop.apps.bench import cable, feedforward
from teleop.apps.campaign.blind import point_label_units
from teleop.apps.campaign.plots import findings_heatmap, jnd_curves_figure
from teleop.apps.protocols.palpation import PalpationResult
from teleop.apps.protocols.palpation_plots import plot_result
from teleop.core.calibration.fsr import fit_fsr, plot_fsr_fit
from teleop.core.calibration.one_sensor import fit_one_sensor, plot_one_sensor_fit
from teleop.diagnosis.plot import shown_unit
from teleop.io.calibration_csv import read_fsr_steps, read_one_sensor
from teleop.io.figures import legend_outside

matplotlib.use("Agg")  # no display: the figures are only inspected
EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "calibration"
UNIT = re.compile(r"\[[^\]]+\]")


def texts(fig) -> str:
    """Every title of the figure: its suptitle and each axes' titles."""
    parts = [fig._suptitle.get_text() if fig._suptitle is not None else ""]
    for ax in fig.axes:
        parts += [ax.get_title(loc) for loc in ("left", "center", "right")]
    return "\n".join(parts)


def data_axes(fig) -> list:
    """Visible axes that draw data (colour bars left out: their one label is checked apart)."""
    return [ax for ax in fig.axes if ax.get_visible() and ax.axison and not hasattr(ax, "_colorbar")]


def check_figure(fig, *must_say: str) -> None:
    """The house rules: titles naming `must_say`, units in brackets on every labelled data axis (an x axis
    of named categories excepted), every legend clear of every data area."""
    fig.canvas.draw()
    title = texts(fig)
    for word in must_say:
        assert word in title, f"{word!r} not in the titles {title!r}"
    axes = data_axes(fig)
    for ax in axes:
        assert UNIT.search(ax.get_ylabel()), f"y label without a unit: {ax.get_ylabel()!r}"
        if isinstance(ax.xaxis.get_major_formatter(), (ScalarFormatter, LogFormatter)):  # not named ticks
            # a shared x axis is labelled once, on the panel at the bottom
            shared = [a.get_xlabel() for a in ax.get_shared_x_axes().get_siblings(ax)]
            assert any(UNIT.search(label) for label in [ax.get_xlabel()] + shared), \
                f"x label without a unit: {ax.get_xlabel()!r}"
    renderer = fig.canvas.get_renderer()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends)
    for leg in legends:
        box = leg.get_window_extent(renderer)
        for ax in axes:
            assert not box.overlaps(ax.get_window_extent(renderer)), \
                f"legend {[t.get_text() for t in leg.get_texts()]} over the axes titled {ax.get_title()!r}"
    plt.close(fig)


def test_check_figure_fails_on_a_legend_inside_and_a_label_without_unit():
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], label="a trace")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("force [N]")
    ax.set_title("what it is")
    ax.legend(loc="upper left")
    with pytest.raises(AssertionError, match="legend"):
        check_figure(fig)
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], label="a trace")
    ax.set_xlabel("time")
    ax.set_ylabel("force [N]")
    legend_outside(ax, "below")
    with pytest.raises(AssertionError, match="x label"):
        check_figure(fig)
    for side in ("right", "below"):
        fig, ax = plt.subplots()
        ax.plot([0, 1], [0, 1], label="a trace")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("force [N]")
        legend_outside(ax, side)
        check_figure(fig)


def _pokes(estimates: dict, n: int = 3) -> list:
    return [{"session": "z60", "label": str(i + 1), "repeat": 0, "direction": "+z", "xy_mm": [0.0, 0.0],
             "depth_mm": 5.0, "ground_truth_N": 1.9 + 0.1 * i,
             **{f"{k}_N": v + 0.1 * i for k, v in estimates.items()}} for i in range(n)]


def _summary(estimates: dict) -> dict:
    return {k: {"mean_abs_error_N": abs(v - 1.9), "rmse_N": abs(v - 1.9)} for k, v in estimates.items()}


def _palpation(test: str, sensor: str, plant: str, estimates: dict, extra: dict | None = None):
    return PalpationResult(test=test, profile="uniform", seed=3, params={"sensor": sensor}, pokes=_pokes(estimates),
                           summary=_summary(estimates), extra={"plant": {"name": plant}, **(extra or {})},
                           simulated_s=1.0, wall_s=1.0)


def test_palpation_bars_name_test_plant_sensor_and_merge_identical_estimators():
    distinct = {"non_compensated": 3.4, "single": 1.95, "double": 1.93, "dynamic": 1.91}
    fig = plot_result(_palpation("z", "fsr", "rich", distinct))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert len(labels) == 5  # the truth and four different estimators
    check_figure(fig, "z test", "plant rich", "sensor fsr", "seed 3")
    same = {k: 2.0 for k in distinct}  # --sensor one: every estimator name runs the same tensions
    fig = plot_result(_palpation("z", "one", "matched", same))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert len(labels) == 2 and "every estimator" in labels[1], labels
    check_figure(fig, "z test", "plant matched", "sensor one")


def test_palpation_scan_in_mm_on_one_colour_scale():
    est = {"non_compensated": 3.0, "single": 1.0, "double": 1.0, "dynamic": 1.0}
    grids = {}
    for letter in "EP":
        g = {"mask": letter_mask(letter).tolist()}
        base = np.where(letter_mask(letter), 4.0, 0.5)
        g["ground_truth_N"] = base.tolist()
        for k, off in est.items():
            g[f"{k}_N"] = (base + off).tolist()
        grids[letter] = g
    fig = plot_result(_palpation("scan", "fbg", "distributed", est, {"grids": grids}))
    images = [im for ax in fig.axes for im in ax.get_images()]
    assert len({im.get_clim() for im in images}) == 1, "panels on different colour scales"
    lo, hi = images[0].get_clim()
    assert lo <= 0.5 and hi >= 7.0  # the uncompensated offset inside the shared scale
    titles = texts(fig)
    assert "single" in titles  # every estimator is on the figure
    x0, x1, y0, y1 = images[0].get_extent()
    assert x1 - x0 == pytest.approx(30.0) and y1 - y0 == pytest.approx(30.0)  # the 30 mm pad
    assert images[0].get_array().shape == (SCAN_ROWS, SCAN_COLS)
    check_figure(fig, "letter scan", "plant distributed", "sensor fbg")


def _fig13_res() -> dict:
    t = np.linspace(0, 10, 200)
    x = 0.01 * np.sin(t)
    series = {"t": t, "x": x}
    for W in ("1.96", "4.9"):
        series[W] = {k: 0.1 * np.sign(np.cos(t)) * (i + 1) for i, k in
                     enumerate(("non_compensated", "single", "double", "flat_transitions"))}
    return {"pretensions": {"1.96": {}, "4.9": {}}, "series": series}


def test_cable_fig13_title_units_legends():
    res = _fig13_res()
    fig = cable.figure("fig13", res, noise_seed=0)
    for ax in fig.axes[:-1]:
        assert "external" not in ax.get_ylabel()  # one cable: a tension estimate, not an external force
    check_figure(fig, "Fig 13", "plant matched", "sensor FSR")
    fig = cable.figure("fig10b", {"theta_CD_deg": 60.0, "plant": "distributed", "cases": {
        str(w): {"weight_N": w, "fsr_change_N": w / 3, "compensated_change_N": 0.01, "tension_B_change_N": w / 3}
        for w in (0.5, 1.0, 2.0)}})
    check_figure(fig, "Fig 10b", "plant distributed")


def test_feedforward_legend_outside_and_plant_named():
    t = np.linspace(0, 4, 50)
    runs = {name: {"t": t, "err": 1e-4 * (i + 1) * np.ones_like(t)} for i, name in enumerate(feedforward.SESSIONS)}
    out = {"backlash_mm": 0.5, "compensation": {"width_mm": 0.5}, "settle_s": 1.0, "seed": 0, "ratio_rms": 2.0,
           "stylus": {"axis": "x", "amp_mm": 12.0, "period_s": 2.0}, "plant": "distributed",
           "sessions": {name: {"tip_error_mm": {"rms": 0.1}} for name in feedforward.SESSIONS}}
    check_figure(feedforward.figure(out, runs), "feedforward", "plant distributed")


def test_campaign_curves_legend_outside():
    pts = [{"jnd": j, "participants": 4, "correct_ranking_rate": r, "ci95": [max(r - 0.2, 0), min(r + 0.2, 1)],
            "kendall_tau_mean": r} for j, r in ((0.1, 0.9), (0.3, 0.5), (0.6, 0.1))]
    check_figure(jnd_curves_figure([("", pts)], "teleop bench blind-jnd: plant matched, sensor fsr"), "sensor fsr")
    curves = [(f"force_scale={g}", pts) for g in (0.05, 0.1, 0.2, 0.4)]
    check_figure(jnd_curves_figure(curves, "teleop campaign"), "teleop campaign")
    m = np.array([[2.0, np.nan], [1.5, 3.0]])
    fig = findings_heatmap(["a", "b"], ["backlash on tip_pos", "lag on tip_force"], m, "teleop campaign (diagnose)")
    fig.canvas.draw()
    assert "teleop campaign" in texts(fig)
    plt.close(fig)


def test_calibration_plots():
    fig = plot_fsr_fit(fit_fsr(read_fsr_steps(EXAMPLES / "fsr_steps.csv")))
    check_figure(fig, "teleop calibrate fsr")
    Fp, Fd, unit, source = read_one_sensor(EXAMPLES / "one_cable.csv")
    fit = fit_one_sensor(Fp, Fd, unit, source)
    fig = plot_one_sensor_fit(fit)
    w = fit.widths["top"]["width"]
    # the title's top width is the drawn one: the segment between the two eq 7 lines at the top turn
    segs = [ln for ln in fig.axes[0].get_lines() if ln.get_color() == "m"]
    drawn = sorted(abs(np.ptp(ln.get_xdata())) for ln in segs)
    assert any(d == pytest.approx(w, rel=1e-9) for d in drawn)
    assert f"{w:.3g}" in fig.axes[0].get_title()
    check_figure(fig, "teleop calibrate one-sensor")


def test_diagnose_draws_positions_in_mm():
    assert shown_unit("m") == ("mm", 1e3)
    assert shown_unit("N") == ("N", 1.0)


def test_campaign_grid_labels_carry_units():
    from_grid = point_label_units({"force_scale": 0.1, "kalman_bandwidth": 80.0, "sensor": "fbg"})
    assert from_grid == "force_scale 0.1 [-], kalman_bandwidth 80 [Hz], sensor fbg"
