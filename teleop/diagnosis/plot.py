"""The diagnosis figure: per link, measured vs baseline vs improved, and the residual before/after, on the
held-out part with the located windows shaded; plus the input-output loop (hysteresis) of each link."""

from __future__ import annotations

from teleop.core.physics.links import predict
from teleop.io.figures import legend_outside

ATTRIBUTION = "Contains data from the MRDLab mis-tool-characterization dataset, ODbL 1.0."
SHOWN_IN = {"m": ("mm", 1e3)}  # a recording's unit -> the unit drawn and its factor (positions read in mm)


def shown_unit(unit: str) -> tuple[str, float]:
    """(unit drawn, factor from the recording's unit): metres as millimetres, others as they are."""
    return SHOWN_IN.get(unit, (unit, 1.0))


def figure(diag, findings: list | None = None):
    """A matplotlib Figure (Agg) of Diagnosis `diag`."""
    import matplotlib  # heavy: loaded only to draw
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    findings = diag.findings() if findings is None else findings
    links = diag.links
    fig, axes = plt.subplots(len(links), 4, figsize=(20, 4.6 * len(links)), squeeze=False,
                             gridspec_kw={"width_ratios": [2.2, 2.2, 1.3, 1.2]})
    hold = diag.hold
    for row, res in zip(axes, links):
        d = res.data
        u_out, ky = shown_unit(diag.rec.units.get(d.link.output, ""))
        u_in, ku = shown_unit(diag.rec.units.get(d.link.input, ""))
        y = d.y * ky
        yb, yf = predict(d, res.baseline.model) * ky, predict(d, res.final.model) * ky
        t = d.t[hold]
        mine = [f for f in findings if f["channel"] == d.link.output]
        names = "+".join(f["effect"] + (" (general form)" if f.get("general_form_of_baseline") else "")
                         for f in mine) or "no finding"
        base_names = "+".join(res.baseline.model.baseline_names)
        base_label = f"baseline{' (' + base_names + ')' if base_names else ''}"
        y_label = f"{d.link.output} [{u_out}]"
        wins = [w for f in mine for w in f["where"]["windows"]]
        # the held-out part (its first 10 s when longer)
        t0 = t[0]
        t1 = min(t[-1], t0 + 10.0)
        sel = (t >= t0) & (t <= t1)
        ax = row[0]
        ax.plot(t[sel], y[hold][sel], "k.", ms=1.5, label="measured")
        ax.plot(t[sel], yb[hold][sel], "-", c="tab:blue", lw=1,
                label=f"{base_label} (rmse {res.baseline.rmse_hold * ky:.3g} {u_out})")
        ax.plot(t[sel], yf[hold][sel], "-", c="tab:red", lw=1,
                label=f"+ {names} (rmse {res.final.rmse_hold * ky:.3g} {u_out})")
        ax.set_title(f"{d.link.name}: held-out", fontsize=10)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(y_label)
        legend_outside(ax, "below")
        ax = row[1]
        ax.plot(t[sel], (y - yb)[hold][sel], "-", c="tab:blue", lw=0.8, label=f"residual {base_label}")
        ax.plot(t[sel], (y - yf)[hold][sel], "-", c="tab:red", lw=0.8, label=f"residual + {names}")
        for a in (row[0], row[1]):
            for w0, w1 in wins:
                if w1 >= t0 and w0 <= t1:
                    a.axvspan(max(w0, t0), min(w1, t1), color="orange", alpha=0.2, lw=0)
        ax.set_title("residual before/after (shaded: located windows)", fontsize=10)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"residual [{u_out}]")
        legend_outside(ax, "below")
        ax = row[2]
        held = [w for w in wins if w[0] >= t[0]]
        if held:  # zoom on the first located window of the held-out part
            w0, w1 = held[0]
            pad = max(2 * (w1 - w0), 0.05)
            z = (d.t >= w0 - pad) & (d.t <= w1 + pad)
            ax.axvspan(w0, w1, color="orange", alpha=0.2, lw=0)
            ax.plot(d.t[z], y[z], "k.", ms=2, label="measured")
            ax.plot(d.t[z], yb[z], "-", c="tab:blue", lw=1, label=base_label)
            ax.plot(d.t[z], yf[z], "-", c="tab:red", lw=1, label=f"+ {names}")
            ax.set_ylabel(y_label)
            ax.set_title(f"located window {w0:.2f}-{w1:.2f} s", fontsize=10)
            ax.set_xlabel("t [s]")
            legend_outside(ax, "below")
        else:  # nothing to draw: the panel says so
            ax.set_axis_off()
            ax.text(0.5, 0.5, "no located window in the held-out part" if mine else "no located window\n(no finding)",
                    ha="center", va="center", transform=ax.transAxes, fontsize=10)
        ax = row[3]
        ax.plot(d.u[hold] * ku, y[hold], "k.", ms=1, label="measured")
        ax.plot(d.u[hold] * ku, yf[hold], "-", c="tab:red", lw=0.8, label=f"model (+ {names})")
        ax.set_xlabel(f"{d.link.input} [{u_in}]")
        ax.set_ylabel(y_label)
        ax.xaxis.set_major_locator(plt.MaxNLocator(4))
        legend_outside(ax, "below")
        ax.set_title("input-output loop (held-out)", fontsize=10)
    title = (f"teleop diagnose: measured vs the baseline model and the model with the named effects, per link\n"
             f"{diag.rec.path}" + (f" ({diag.rec.metadata['source']})" if diag.rec.metadata.get("source") else ""))
    if "mrdlab" in diag.rec.path.lower() or "MRDLab" in diag.rec.metadata.get("source", ""):
        title += f"\n{ATTRIBUTION}"
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig
