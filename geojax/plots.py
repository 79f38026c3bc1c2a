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
    return _save(fig, ax, title, path)


def plot_station_keeping(cycles, reference, target, path: str | Path, title: str = "") -> Path:
    """Li 2022 Figs. 4-8 from a closed-loop run: longitude history, the (de_x, de_y) and
    (di_x, di_y) planes with the uncontrolled reference dashed, Delta-V_NS per cycle
    (eq. (45)) and the mean pitch angle (eq. (46)).

    ``cycles``, ``reference`` and ``target`` are the /cycles, /reference and /target
    groups of ``geojax simulate --out``.
    """
    days = np.asarray(cycles["t_s"]) / 86400.0
    ref_days = np.asarray(reference["t_s"]) / 86400.0
    fig, axes = plt.subplots(2, 3, figsize=(14, 8), constrained_layout=True)
    ax = axes.ravel()
    ax[0].plot(days, np.asarray(cycles["lon_deg"]) - target["lon_deg"], label="controlled")
    ax[0].set(xlabel="days", ylabel="mean δλ (deg)")
    ax[0].legend()
    for a, (x, y, label) in zip(ax[1:3], [("ex", "ey", "e"), ("ix", "iy", "i")]):
        a.plot(np.asarray(reference[x]) - target[x], np.asarray(reference[y]) - target[y], "r--", label="uncontrolled")
        a.plot(np.asarray(cycles[x]) - target[x], np.asarray(cycles[y]) - target[y], label="controlled")
        a.set(xlabel=f"δ{label}_x", ylabel=f"δ{label}_y")
        a.legend()
    ax[3].plot(ref_days, np.asarray(reference["lon_deg"]) - target["lon_deg"], "r--")
    ax[3].set(xlabel="days", ylabel="uncontrolled mean δλ (deg)")
    v_total = np.asarray(cycles["v1_mps"]) + np.asarray(cycles["v2_mps"])
    dv_ns = np.asarray(cycles["dv_ns_mps"])
    ax[4].plot(days, dv_ns)
    ax[4].set(xlabel="days", ylabel="ΔV_NS per cycle (m/s), eq. (45)")
    mean_beta = np.degrees(np.arcsin(np.clip(dv_ns / np.where(v_total > 0, v_total, 1.0), 0.0, 1.0)))
    ax[5].plot(days[v_total > 0], mean_beta[v_total > 0])
    ax[5].set(xlabel="days", ylabel="mean pitch β̄ (deg), eq. (46)")
    return _save(fig, ax, title, path)


def _save(fig, axes, title: str, path: str | Path) -> Path:
    for a in axes:
        a.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
