"""A tuning's figure: the convergence of a ``geojax tune`` results file against iteration (``plot_tuning``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import MaxNLocator

from geojax.plots.labels import label_for
from geojax.plots.layout import _finite_or_nan
from geojax.plots.style import _save, styled


@styled
def plot_tuning(groups, path: str | Path, title: str = "", dpi: int = 150, best_values=()) -> Path:
    """The convergence of a ``geojax tune`` results file against iteration: the exact-law ΔV of every start (thin
    lines; a diverged start's iterations are left out) with the best feasible ΔV so far (thick steps) and the best
    point (star, its legend entry followed by the lines of ``best_values``, e.g. "k_h = 1.6e-15 1/(km² s)"); the
    larger of each start's two box constraints, (excursion / half-width)² − 1, with the box edge at 0 (inside
    below); and, when recorded, each start's step length (log scale).  Only what is drawn is in a legend.

    ``groups`` are the groups of the file: ``iterations`` (dv_per_year_mps [it, starts], constraint
    [it, starts, 2], step_norm [it, starts], active [it, starts], best_dv_per_year_mps [it], ...) and, when a
    feasible point was found, ``metrics`` (dv_per_year_mps, constraint_lon, constraint_lat).
    """
    hist = groups["iterations"]
    alive = np.asarray(hist["active"]) > 0 if "active" in hist else True
    dv = _finite_or_nan(np.where(alive, hist["dv_per_year_mps"], np.nan))
    g = _finite_or_nan(np.where(alive, np.max(np.asarray(hist["constraint"], float), axis=-1), np.nan))
    it = np.arange(dv.shape[0])
    panels = 3 if "step_norm" in hist else 2
    fig, axes = plt.subplots(panels, 1, figsize=(5.0, 2.1 * panels + 0.4), constrained_layout=True)
    for a, series in zip(axes, [dv, g]):
        for start in range(series.shape[1]):
            a.plot(it, series[:, start], lw=0.6, alpha=0.7, color=f"C{start % 10}",
                   label="starts (exact law)" if start == 0 else None)
    best = _finite_or_nan(hist["best_dv_per_year_mps"])
    metrics = groups.get("metrics") or {}
    if np.isfinite(best).any():  # nothing feasible yet: no line, and no legend entry for one
        axes[0].step(it, best, where="post", color="k", lw=2.0, label="best feasible so far")
        found = int(np.argmax(best == np.nanmin(best)))
        best_dv = float(metrics.get("dv_per_year_mps", best[found]))
        axes[0].plot(found, best_dv, "*", color="C3", ms=11, mec="k", mew=0.5,
                     label="\n".join([f"best: {best_dv:.2f} m/s/yr", *best_values]))
        if {"constraint_lon", "constraint_lat"} <= set(metrics):
            axes[1].plot(found, max(float(metrics["constraint_lon"]), float(metrics["constraint_lat"])), "*",
                         color="C3", ms=11, mec="k", mew=0.5, label="best point")
    axes[0].set(xlabel="iteration", ylabel=label_for("dv_per_year_mps"))
    axes[1].axhline(0.0, color="k", ls="--", lw=0.8, label="box edge (inside below)")
    if np.nanmax(np.abs(g), initial=0.0) > 10.0:  # a start far outside would flatten the rest
        axes[1].set_yscale("symlog", linthresh=1.0)
        axes[1].set_ylim(bottom=np.nanmin(g) - 0.1)  # the constraint is at least -1 (no excursion at all)
    axes[1].set(xlabel="iteration", ylabel="max box constraint")
    if panels == 3:
        step = _finite_or_nan(np.where(alive, hist["step_norm"], np.nan))
        for start in range(step.shape[1]):
            axes[2].plot(it, np.where(step[:, start] > 0, step[:, start], np.nan), lw=0.6, alpha=0.7,
                         color=f"C{start % 10}", label="starts' accepted steps" if start == 0 else None)
        if np.nanmax(step, initial=0.0) > 0:
            axes[2].set_yscale("log")
        axes[2].set(xlabel="iteration", ylabel="step length (θ units)")
    for a in axes:
        if a.get_legend_handles_labels()[0]:
            a.legend(loc="best", fontsize="small")
    for a in axes:
        a.xaxis.set_major_locator(MaxNLocator(integer=True))
    return _save(fig, list(axes), title, path, dpi)
