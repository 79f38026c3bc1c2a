"""The figures of the loop's parts, from a run's per-cycle records (the ``/cycles`` datasets): the wheels' momentum
against their capacity (``plot_wheels``), the navigation filter's error against its ±3σ (``plot_navigation_error``)
and its NEES and NIS against their χ² intervals (``plot_consistency``).  Each part declares its figures
(``states.base.Part.figures``) by a small function of its module that calls ``wheel_figures`` or
``navigation_figures`` here, so that the engine imports no matplotlib.

A part's figures take ``(run, folder)``: ``run`` a single run's ``Result`` or a results file read back
(``geojax.figures.FileRun``), each with ``cycles()``, ``scenario`` and ``params``; they are written as
``FOLDER/NAME-WHAT.FMT`` (``figure_path``).

The records' times: ``/cycles/t_s`` is each cycle's middle, so a cycle k runs from t_s[k] - t_s[0] to
t_s[k] + t_s[0]; the filter's error, σ and NEES are taken at a cycle's start (its decision time), the wheels'
momentum at its end, the largest |momentum| and the NIS over the whole cycle.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import MaxNLocator

from geojax.plots.style import _save, styled

DAY_S = 86400.0
AXES = (("radial", "radial"), ("along", "along-track"), ("cross", "cross-track"))  # navigation's column names
NEES_DOF = 6  # the filter's NEES: position and velocity (``states.navigation``)
PROBABILITY = 0.95  # the two-sided χ² intervals, as the filter's tests and studies bound its metrics


def cycle_edges_s(t_s) -> tuple[np.ndarray, np.ndarray]:
    """(start [n], end [n]) of each cycle, s since the run's start, from the cycles' middles ``t_s``."""
    t_s = np.asarray(t_s, float)
    return t_s - t_s[0], t_s + t_s[0]


@styled
def plot_wheels(cycles: dict, capacity_nms: float, path: str | Path, title: str = "", dpi: int = 150) -> Path:
    """The reaction wheels' momentum per cycle, one panel per wheel (body axes x, y, z): the momentum at each cycle
    end (``wheel_{x,y,z}_nms``), ± the largest |momentum| within the cycle (``wheel_max_abs_{x,y,z}_nms``, steps
    over the cycle) and ± the capacity ``capacity_nms`` (beyond it the run fails: wheels saturated)."""
    start, end = cycle_edges_s(cycles["t_s"])
    edges = np.append(start, end[-1]) / DAY_S
    fig, axes = plt.subplots(3, 1, figsize=(7.2, 5.6), constrained_layout=True)
    for ax, axis in zip(axes, "xyz"):
        peak = np.asarray(cycles[f"wheel_max_abs_{axis}_nms"], float)
        ax.stairs(peak, edges, baseline=None, color="C1", lw=0.8, label="± largest |h| within the cycle",
                  gid="max_abs")
        ax.stairs(-peak, edges, baseline=None, color="C1", lw=0.8, gid="-max_abs")
        ax.plot(end / DAY_S, cycles[f"wheel_{axis}_nms"], "o-", ms=3, color="C0", label="h at the cycle end",
                gid="end")
        for sign in (1, -1):
            ax.axhline(sign * capacity_nms, color="C3", ls="--", lw=0.9, gid=f"{'+-'[sign < 0]}capacity",
                       label=f"± capacity {capacity_nms:g} N m s" if sign > 0 else None)
        ax.set(xlabel="days", ylabel=f"h_{axis} (N m s)", xlim=(edges[0], edges[-1]))
        ax.yaxis.set_major_locator(MaxNLocator(5, symmetric=True))
    for ax in axes:
        ax.xaxis.set_major_locator(MaxNLocator(6))
    axes[0].set_title("reaction wheels, body axes (x along-track, y anti-normal, z nadir)", loc="left")
    axes[0].legend(loc="lower left", bbox_to_anchor=(0.0, 1.12), ncol=3, frameon=False, borderaxespad=0.0)
    return _save(fig, list(axes), title, path, dpi)


@styled
def plot_navigation_error(cycles: dict, path: str | Path, title: str = "", dpi: int = 150) -> Path:
    """The navigation filter's error (estimate − truth) at each decision time (a cycle's start) against ± its 3σ,
    per RSW axis (radial, along-track, cross-track): position (m) above, velocity (mm/s) below
    (``nav_error_{axis}_{m,mps}``, ``nav_sigma_{axis}_{m,mps}``)."""
    start, _ = cycle_edges_s(cycles["t_s"])
    days = start / DAY_S
    fig, axes = plt.subplots(2, 3, figsize=(7.2, 4.4), constrained_layout=True)
    for row, (unit, scale, shown) in enumerate((("m", 1.0, "m"), ("mps", 1e3, "mm/s"))):
        for ax, (axis, name) in zip(axes[row], AXES):
            error = np.asarray(cycles[f"nav_error_{axis}_{unit}"], float) * scale
            three_sigma = 3.0 * np.asarray(cycles[f"nav_sigma_{axis}_{unit}"], float) * scale
            ax.fill_between(days, -three_sigma, three_sigma, color="0.85", lw=0)
            ax.plot(days, three_sigma, "k--", lw=0.8, label="±3σ (the filter's)", gid="+3sigma")
            ax.plot(days, -three_sigma, "k--", lw=0.8, gid="-3sigma")
            ax.plot(days, error, "o-", ms=3, color="C0", label="error (estimate − truth)", gid="error")
            ax.set(xlabel="days", ylabel=f"{name} ({shown})")
            ax.yaxis.set_major_locator(MaxNLocator(5, symmetric=True))
    for ax in axes.ravel():
        ax.xaxis.set_major_locator(MaxNLocator(4))
    axes[0, 0].set_title("position", loc="left")
    axes[1, 0].set_title("velocity", loc="left")
    axes[0, 1].legend(loc="lower center", bbox_to_anchor=(0.5, 1.1), ncol=2, frameon=False, borderaxespad=0.0)
    return _save(fig, list(axes.ravel()), title, path, dpi)


def nis_dof(cycles: dict) -> np.ndarray:
    """The degrees of freedom of each cycle's NIS: the measurement components it processed (each a 0/1 weight
    times its size, ``states.navigation``)."""
    return np.rint(np.asarray(cycles["measurements"], float)).astype(int)


@styled
def plot_consistency(cycles: dict, path: str | Path, title: str = "", dpi: int = 150) -> Path:
    """The navigation filter's consistency per cycle against χ² intervals (two-sided 95 %,
    ``navigation.ekf.chi2_bounds``): the NEES at each decision time (a cycle's start; 6 dof: each a χ²(6) value)
    with the run's mean and its interval (N values: what bounds ``nees_mean``); the NIS per degree of freedom over
    each cycle's updates (steps over the cycle; its interval from the cycle's measurement components) with the
    run's over every update (what bounds ``nis_mean_per_dof``).  A cycle without measurements has no NIS: a gap."""
    from geojax.navigation.ekf import chi2_bounds

    start, end = cycle_edges_s(cycles["t_s"])
    edges = np.append(start, end[-1]) / DAY_S
    fig, axes = plt.subplots(2, 1, figsize=(7.2, 4.8), constrained_layout=True)
    nees = np.asarray(cycles["nees"], float)
    low, high = chi2_bounds(NEES_DOF, 1, PROBABILITY)
    for value, gid in ((low, "low"), (high, "high")):
        axes[0].plot(edges[[0, -1]], [value, value], "k--", lw=0.8, gid=gid,
                     label=f"χ²({NEES_DOF}) 95 %, each value" if gid == "low" else None)
    axes[0].plot(start / DAY_S, nees, "o-", ms=3, color="C0", label="NEES at the cycle start", gid="values")
    _run_mean(axes[0], float(np.mean(nees)), chi2_bounds(NEES_DOF, len(nees), PROBABILITY), f"mean of {len(nees)}")
    axes[0].set(xlabel="days", ylabel="NEES (6 dof)")
    dof = nis_dof(cycles)
    used = dof > 0
    nis = np.where(used, np.asarray(cycles["nis_per_dof"], float), np.nan)
    bounds = np.array([chi2_bounds(1, int(k), PROBABILITY) if k > 0 else (np.nan, np.nan) for k in dof])
    for column, gid in ((0, "low"), (1, "high")):
        axes[1].stairs(bounds[:, column], edges, baseline=None, color="k", ls="--", lw=0.8, gid=gid,
                       label="χ²(dof)/dof 95 %, each cycle's dof" if gid == "low" else None)
    axes[1].stairs(nis, edges, baseline=None, color="C0", lw=1.2, label="NIS per dof over the cycle's updates",
                   gid="values")
    total = int(dof.sum())
    if total:
        _run_mean(axes[1], float(np.nansum(nis * dof) / total), chi2_bounds(1, total, PROBABILITY),
                  f"over the run's {total} dof")
    axes[1].set(xlabel="days", ylabel="NIS per degree of freedom")
    for ax, values, (lo, hi) in ((axes[0], nees, (low, high)), (axes[1], nis, (np.nanmin(bounds), np.nanmax(bounds)))):
        finite = values[np.isfinite(values)]
        if finite.size and (finite.max() > 10 * hi or finite.min() < 0.1 * lo):  # far outside: a log axis
            ax.set_yscale("log")
        ax.set_xlim(edges[0], edges[-1])
        ax.xaxis.set_major_locator(MaxNLocator(6))
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, borderaxespad=0.0, fontsize="small")
    return _save(fig, list(axes), title, path, dpi)


def _run_mean(ax, mean: float, interval: tuple[float, float], run: str) -> None:
    """The run's average as a line, its χ² interval as a band across the axes."""
    ax.axhline(mean, color="C1", lw=1.2, label=f"{run}: {mean:.3g}", gid="mean")
    ax.axhspan(*interval, color="C1", alpha=0.15, lw=0, label=f"95 % interval, {run}", gid="mean_band")


def figure_path(run, folder: str | Path, what: str) -> Path:
    """``FOLDER/NAME-WHAT.FMT``: NAME the run's scenario's (a ``Result``) or its file's stem, FMT png, or those a
    results file read back names (``geojax.figures.FileRun``: ``stem``, ``fmt``)."""
    return Path(folder) / f"{getattr(run, 'stem', run.scenario.name)}-{what}.{getattr(run, 'fmt', 'png')}"


def _title_dpi(run) -> tuple[str, int]:
    from geojax.runner.report import run_title

    return getattr(run, "title", None) or run_title(run.scenario), getattr(run, "dpi", 150)


def wheel_figures(run, folder: str | Path) -> list[Path]:
    """The wheels' figure of a run (``plot_wheels``, ``NAME-wheels.png``), against the capacity it ran with
    (``params.states["wheels"]["wheel_capacity_nms"]``)."""
    title, dpi = _title_dpi(run)
    capacity = float(np.asarray(run.params.states["wheels"]["wheel_capacity_nms"]))
    return [plot_wheels(run.cycles(), capacity, figure_path(run, folder, "wheels"), title=title, dpi=dpi)]


def navigation_figures(run, folder: str | Path) -> list[Path]:
    """The navigation filter's figures of a run: its error against ±3σ (``NAME-navigation-error.png``) and its
    NEES and NIS against their χ² intervals (``NAME-navigation-consistency.png``)."""
    title, dpi = _title_dpi(run)
    cycles = run.cycles()
    return [plot_navigation_error(cycles, figure_path(run, folder, "navigation-error"), title=title, dpi=dpi),
            plot_consistency(cycles, figure_path(run, folder, "navigation-consistency"), title=title, dpi=dpi)]
