"""Shared figure conventions of the commands' PNGs: a legend placed outside the data (beside or below the axes),
so that no trace or point is hidden behind it. `save_figure`
(teleop.io.outputs) saves with a tight bounding box, which keeps a legend outside the axes on the page."""

from __future__ import annotations


BELOW_PT = 36.0  # [pt] from the axes' bottom edge to a legend below it: clear of tick labels and the x label


def legend_outside(ax, side: str = "right", **kw):
    """The legend of `ax` outside its data area: `side` "right" (top-left corner beside the axes) or
    "below" (centred under the axes, BELOW_PT under its bottom edge, below the x label). Extra keywords go
    to `Axes.legend`."""
    if side == "right":
        place = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0}
    elif side == "below":
        from matplotlib.transforms import ScaledTranslation  # heavy: loaded only to draw

        down = ax.transAxes + ScaledTranslation(0.0, -BELOW_PT / 72.0, ax.figure.dpi_scale_trans)
        place = {"loc": "upper center", "bbox_to_anchor": (0.5, 0.0), "bbox_transform": down,
                 "borderaxespad": 0.0}
    else:
        raise ValueError(f"legend side {side!r}: expected 'right' or 'below'")
    return ax.legend(**{"fontsize": 7, **place, **kw})
