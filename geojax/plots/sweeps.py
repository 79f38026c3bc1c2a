"""A sweep's figure: its metric against its first swept parameter, mean and spread over the repetitions that held
(status 0: the 5–95 % percentile band within the min–max one), one line per controller and point of the further
swept keys (named by their values), the points where samples failed marked and counted apart, the legend beside the
axes (``plot_sweep``; several sweeps on one axis: ``plot_sweeps``); a sweep of repetitions alone (no grid), the
histogram of its samples (``plot_repetitions``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.ticker import MaxNLocator
import numpy as np

from geojax.plots.labels import _label, _quantity, decade
from geojax.plots.style import _save, styled
from geojax.results import held_percentiles, held_statistics

SPREAD_PCT = (5.0, 95.0)  # the percentile band of the repetitions that held


@styled
def plot_sweep(groups, axes_names: list[str], path: str | Path, metric: str = "dv_per_year_mps", title: str = "",
               label: str = "", dpi: int = 150) -> Path:
    """A sweep's metric against its first swept parameter: mean and spread over the repetitions that held
    (status 0: the 5th to 95th percentile, ``SPREAD_PCT``, in a band within the lighter min–max one), one line
    per controller (and per value of any further axis); the failed samples are left out of the mean and the bands
    and counted apart: a point where samples failed is marked with a cross at their mean and labelled with their
    count ("3/20 failed").  ``groups`` are the groups of a ``geojax sweep`` file."""
    return plot_sweeps([(label, groups)], axes_names, path, metric, title, dpi=dpi)


def _numeric(values) -> np.ndarray:
    """A swept axis as numbers: dates (an ``epoch.utc`` axis) as decimal years."""
    values = np.asarray(values)
    if values.dtype.kind in "SUO":
        from geojax.sweep.epochs import as_years

        return as_years(values)
    return values.astype(float)


@styled
def plot_sweeps(runs, axes_names: list[str], path: str | Path, metric: str = "dv_per_year_mps", title: str = "",
                dpi: int = 150) -> Path:
    """``plot_sweep`` for several sweeps over the same parameter on one axis: ``runs`` is [(label, groups)]."""
    from matplotlib.patches import Patch

    fig, ax = plt.subplots(figsize=(7.2, 3.4), constrained_layout=True)
    param = axes_names[1]
    x_power = decade(*(_numeric(g["grid"][param.replace(".", "__")]) for _, g in runs))
    y_power = decade(*(np.asarray(g["metrics"][metric], float) for _, g in runs))
    grid_values, bands = set(), []
    for prefix, groups in runs:
        values = np.asarray(groups["metrics"][metric], float) / 10.0**y_power  # [controller, grid..., reps]
        status = np.asarray(groups["status"]["code"])
        controllers = [c.decode() if isinstance(c, bytes) else str(c) for c in groups["grid"]["controller"]]
        x = _numeric(groups["grid"][param.replace(".", "__")]) / 10.0**x_power
        grid_values.update(x.tolist())
        further = _further_points(groups["grid"], axes_names[2:], controllers)
        for i, controller in enumerate(controllers):
            v = values[i].reshape(len(x), -1, values.shape[-1])  # [x, other axes, reps]
            s = status[i].reshape(v.shape)
            for j in range(v.shape[1]):
                name = " ".join(filter(None, [prefix, controller])) + (f", {further[j]}" if further else "")
                stats = held_statistics(v[:, j], s[:, j])
                low, high = held_percentiles(v[:, j], s[:, j], SPREAD_PCT)
                bad = stats.failed > 0
                line, = ax.plot(x, stats.mean, "o-", ms=3.5, label=f"{name}: mean (held)")
                if v.shape[-1] > 1:
                    spread = f"{SPREAD_PCT[0]:g}–{SPREAD_PCT[1]:g} %"
                    ax.fill_between(x, low, high, color=line.get_color(), alpha=0.3, lw=0, gid=f"{name}: {spread}")
                    ax.fill_between(x, stats.min, stats.max, color=line.get_color(), alpha=0.1, lw=0,
                                    gid=f"{name}: min–max")
                    bands += [Patch(color=line.get_color(), alpha=0.3, lw=0,
                                    label=f"{name}: {spread} (held, {v.shape[-1]} repetitions)"),
                              Patch(color=line.get_color(), alpha=0.1, lw=0, label=f"{name}: min–max (held)")]
                if bad.any():
                    failed_mean = np.nanmean(np.where(s[bad, j] != 0, v[bad, j], np.nan), axis=-1)
                    ax.plot(x[bad], failed_mean, "x", color=line.get_color(), ms=8, mew=1.5,
                            label=f"{name}: failed (status not 0): mean, count")
                    for xi, yi, k in zip(x[bad], failed_mean, stats.failed[bad], strict=True):
                        ax.annotate(f"{k}/{v.shape[-1]} failed", (xi, yi), xytext=(3, 3), textcoords="offset points",
                                    fontsize="x-small", color=line.get_color())
    if len(grid_values) <= 12:  # the ticks on the grid's values, not between them
        ax.set_xticks(sorted(grid_values), [f"{v:g}" for v in sorted(grid_values)])
    names = [c.decode() if isinstance(c, bytes) else str(c) for _, g in runs for c in g["grid"]["controller"]]
    ax.set(xlabel=_label(*_quantity(param, names), x_power), ylabel=_label(*_quantity(metric), y_power))
    handles, _ = ax.get_legend_handles_labels()
    # beside the axes, not on them: a legend inside covers the bands wherever it is put
    ax.legend(handles=handles + bands, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
              frameon=False, fontsize="small")
    return _save(fig, [ax], title, path, dpi)


def _further_points(grid, keys: list[str], controllers) -> list[str]:
    """The points of the swept axes after the first, in the grid's order (the last varying fastest), each named by
    its keys' symbols and values ("Δi_max = 4e-05, H_rv = 2"); [] for a sweep over one key."""
    import itertools

    named = []
    for key in keys:
        symbol, unit = _quantity(key, controllers)
        values = [v.decode() if isinstance(v, bytes) else v for v in np.asarray(grid[key.replace(".", "__")]).tolist()]
        named.append([f"{symbol} = {v:g}{' ' + unit if unit else ''}" if isinstance(v, (int, float))
                      else f"{symbol} = {v}" for v in values])
    return [", ".join(point) for point in itertools.product(*named)] if keys else []


@styled
def plot_repetitions(groups, path: str | Path, metric: str = "dv_per_year_mps", title: str = "",
                     dpi: int = 150) -> Path:
    """A sweep of repetitions alone (no grid; metrics [controller, repetition]): the histogram of ``metric`` over
    each controller's samples that held (status 0), their mean and 5th-95th percentiles marked, the failed
    samples counted in the legend (never drawn among the held)."""
    fig, ax = plt.subplots(figsize=(7.2, 3.4), constrained_layout=True)
    values = np.asarray(groups["metrics"][metric], float)  # [controller, repetition]
    status = np.asarray(groups["status"]["code"])
    controllers = [c.decode() if isinstance(c, bytes) else str(c) for c in groups["grid"]["controller"]]
    power = decade(values[status == 0])
    for i, controller in enumerate(controllers):
        held = values[i][status[i] == 0] / 10.0**power
        failed = int(np.sum(status[i] != 0))
        counted = f"{held.size} held" + (f", {failed} failed (status not 0)" if failed else "")
        if held.size == 0:
            ax.plot([], [], " ", label=f"{controller}: {counted}")
            continue
        _, _, bars = ax.hist(held, bins=min(30, max(5, held.size // 5)), alpha=0.5, label=f"{controller}: {counted}")
        color = bars[0].get_facecolor()[:3]
        low, high = np.percentile(held, [5, 95])
        ax.axvline(np.mean(held), color=color, lw=1.5, label=f"{controller}: mean {np.mean(held):.4g}")
        ax.axvspan(low, high, color=color, alpha=0.1, lw=0, label=f"{controller}: 5th-95th percentile")
    ax.set(xlabel=_label(*_quantity(metric), power), ylabel="samples")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, frameon=False, fontsize="small")
    return _save(fig, [ax], title, path, dpi)
