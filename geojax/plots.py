"""Figures from results (matplotlib, no display needed)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_cycles(cycles: dict[str, np.ndarray], path: str | Path, title: str = "") -> Path:
    """Mean-element histories of a run: longitude, drift, eccentricity and inclination vectors, a.

    ``cycles`` holds the ``/cycles`` datasets of ``geojax propagate``.
    """
    days = np.asarray(cycles["t_s"]) / 86400.0
    fig, axes = plt.subplots(2, 3, figsize=(13, 7), constrained_layout=True)
    ax = axes.ravel()
    ax[0].plot(days, np.degrees(np.unwrap(np.radians(cycles["lon_deg"]))))
    ax[0].set(xlabel="days", ylabel="mean longitude (deg E)")
    ax[1].plot(days, cycles["drift_deg_per_day"])
    ax[1].set(xlabel="days", ylabel="drift (deg/day)")
    ax[2].plot(days, (np.asarray(cycles["a_m"]) - 42164.17e3) / 1e3)
    ax[2].set(xlabel="days", ylabel="mean a - 42164.17 km (km)")
    ax[3].plot(cycles["ex"], cycles["ey"])
    ax[3].plot(cycles["ex"][:1], cycles["ey"][:1], "o", label="start")
    ax[3].set(xlabel="e_x", ylabel="e_y", aspect="equal")
    ax[3].legend()
    ax[4].plot(cycles["ix"], cycles["iy"])
    ax[4].plot(cycles["ix"][:1], cycles["iy"][:1], "o", label="start")
    ax[4].set(xlabel="i_x = h", ylabel="i_y = k")
    ax[4].legend()
    ax[5].plot(days, np.degrees(2 * np.arctan(np.hypot(cycles["ix"], cycles["iy"]))))
    ax[5].set(xlabel="days", ylabel="mean inclination (deg)")
    for a in ax:
        a.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
