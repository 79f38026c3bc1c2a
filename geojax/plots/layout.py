"""Where things sit on an axes: square and padded data ranges, a zoomed inset, a legend above the data."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import MaxNLocator


def _finite_or_nan(values) -> np.ndarray:
    values = np.asarray(values, float)
    return np.where(np.isfinite(values), values, np.nan)


def _extent(x, y) -> float:
    """The larger side of the bounding box of a path."""
    return float(max(np.ptp(x), np.ptp(y))) if np.size(x) else 0.0


def _padded(values, factor: float = 1.5):
    values = np.asarray(values, float)
    values = values[np.isfinite(values)]
    centre, half = 0.5 * (np.max(values) + np.min(values)), 0.5 * (np.max(values) - np.min(values))
    half = max(half * factor, 1e-6 * max(1.0, abs(centre)))
    return centre - half, centre + half


def _zoom(ax, x, y, all_x, all_y, size: float = 0.38):
    """A zoomed inset of the path (x, y), with its tick values and its magnification written in it, in the
    corner of ``ax`` holding the fewest of the points (all_x, all_y); the zoomed region is marked on ``ax``."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    u, v = (np.asarray(all_x) - x0) / (x1 - x0), (np.asarray(all_y) - y0) / (y1 - y0)
    corners = [(0.02, 0.02), (1 - size - 0.02, 0.02), (0.02, 1 - size - 0.02), (1 - size - 0.02, 1 - size - 0.02)]
    crowd = [np.sum((u > cx - 0.05) & (u < cx + size + 0.05) & (v > cy - 0.05) & (v < cy + size + 0.05))
             for cx, cy in corners]
    corner = corners[int(np.argmin(crowd))]
    inset = ax.inset_axes([*corner, size, size])
    inset.plot(x, y, "C0", lw=0.8)
    _square(inset, x, y, 1.3)
    # Tick values in the parent's units, small, on the inset's sides towards the parent's middle (outside sides
    # would fall on the parent's own tick labels).
    left, bottom = corner[0] < 0.5, corner[1] < 0.5
    inset.tick_params(labelsize=5, length=2, pad=1, direction="in", labelbottom=not bottom, labeltop=bottom,
                      labelleft=not left, labelright=left, bottom=True, top=True, left=True, right=True)
    inset.xaxis.set_major_locator(MaxNLocator(3))
    inset.yaxis.set_major_locator(MaxNLocator(3))
    zoom = float(f"{(x1 - x0) / np.ptp(inset.get_xlim()):.2g}")
    inset.text(0.04, 0.96, f"×{zoom:g}", transform=inset.transAxes, ha="left", va="top", fontsize=6)
    ax.indicate_inset_zoom(inset, edgecolor="0.4")
    return inset


def _square(ax, x, y, pad: float = 1.1) -> None:
    """Equal, square data ranges around the points (x, y), ``pad`` times their larger extent: a square box with
    equal aspect, whatever the shape of the path (an inset in it is then square too)."""
    x, y = _finite_or_nan(x), _finite_or_nan(y)
    cx, cy = 0.5 * (np.nanmax(x) + np.nanmin(x)), 0.5 * (np.nanmax(y) + np.nanmin(y))
    half = max(0.5 * pad * max(np.nanmax(x) - np.nanmin(x), np.nanmax(y) - np.nanmin(y)),
               1e-9 * max(1.0, abs(cx), abs(cy)))
    ax.set(xlim=(cx - half, cx + half), ylim=(cy - half, cy + half), aspect="equal")
    ax.xaxis.set_major_locator(MaxNLocator(4))
    ax.yaxis.set_major_locator(MaxNLocator(4))


def _legend_above(ax) -> None:
    """The legend in a band above the axes, so it covers no data."""
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=1, frameon=False, borderaxespad=0.0,
              handlelength=1.8, fontsize=7)
