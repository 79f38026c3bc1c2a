"""Figures from results (matplotlib, no display needed)."""

from __future__ import annotations

import warnings
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
    """Li 2022 Figs. 4-8 from a closed-loop run: longitude history; the (d lambda, d phi),
    (de_x, de_y) and (di_x, di_y) planes with the uncontrolled reference dashed (its
    first 30 days in the ground-track plane); Delta-V_NS per cycle (eq. (45)) and
    the mean pitch angle (eq. (46)).

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
        a.ticklabel_format(style="sci", scilimits=(0, 0))
        a.legend()
    month = ref_days <= 30.0
    ref_lon, ref_lat = ground_track_deg(*(np.asarray(reference[k])[month] for k in ("lon_deg", "ex", "ey", "ix", "iy")))
    lon, lat = ground_track_deg(*(np.asarray(cycles[k]) for k in ("lon_deg", "ex", "ey", "ix", "iy")))
    ax[3].plot(ref_lon - target["lon_deg"], ref_lat, "r--", lw=0.6, label="uncontrolled, 30 days")
    ax[3].plot(lon - target["lon_deg"], lat, lw=0.6, label="controlled")
    ax[3].set(xlabel="δλ (deg)", ylabel="δφ (deg)", xlim=_padded(lon - target["lon_deg"]), ylim=_padded(lat))
    ax[3].legend()
    v_total = np.asarray(cycles["v1_mps"]) + np.asarray(cycles["v2_mps"])
    dv_ns = np.asarray(cycles["dv_ns_mps"])
    ax[4].plot(days, dv_ns)
    ax[4].set(xlabel="days", ylabel="ΔV_NS per cycle (m/s), eq. (45)")
    mean_beta = np.degrees(np.arcsin(np.clip(dv_ns / np.where(v_total > 0, v_total, 1.0), 0.0, 1.0)))
    ax[5].plot(days[v_total > 0], mean_beta[v_total > 0])
    ax[5].set(xlabel="days", ylabel="mean pitch β̄ (deg), eq. (46)")
    return _save(fig, ax, title, path)


def plot_sweep(groups, axes_names: list[str], path: str | Path, metric: str = "dv_per_year_mps", title: str = "",
               label: str = "") -> Path:
    """A sweep's metric against its first swept parameter: mean and spread (min-max) over the
    repetitions, one line per controller (and per value of any further axis), unstable points
    (status 2) marked with a cross.  ``groups`` are the groups of a ``geojax sweep`` file."""
    return plot_sweeps([(label, groups)], axes_names, path, metric, title)


def plot_sweeps(runs, axes_names: list[str], path: str | Path, metric: str = "dv_per_year_mps", title: str = "") -> Path:
    """``plot_sweep`` for several sweeps over the same parameter on one axis: ``runs`` is [(label, groups)]."""
    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    param = axes_names[1]
    for prefix, groups in runs:
        values = np.asarray(groups["metrics"][metric])  # [controller, grid..., reps]
        status = np.asarray(groups["status"]["code"])
        controllers = [c.decode() if isinstance(c, bytes) else str(c) for c in groups["grid"]["controller"]]
        x = np.asarray(groups["grid"][param.replace(".", "__")])
        for i, controller in enumerate(controllers):
            v = values[i].reshape(len(x), -1, values.shape[-1])  # [x, other axes, reps]
            s = status[i].reshape(v.shape)
            for j in range(v.shape[1]):
                label = " ".join(filter(None, [prefix, controller.upper(), f"#{j}" if v.shape[1] > 1 else ""]))
                stable = np.where(s[:, j] == 2, np.nan, v[:, j])
                with warnings.catch_warnings():  # a point whose every repetition is unstable has no spread
                    warnings.simplefilter("ignore", RuntimeWarning)
                    mean, low, high = (f(stable, axis=-1) for f in (np.nanmean, np.nanmin, np.nanmax))
                line, = ax.plot(x, mean, "o-", label=label)
                ax.fill_between(x, low, high, color=line.get_color(), alpha=0.2)
                bad = np.any(s[:, j] == 2, axis=-1)
                if bad.any():
                    ax.plot(x[bad], np.nanmean(np.where(np.isfinite(v[bad, j]), v[bad, j], np.nan), axis=-1), "x",
                            color=line.get_color(), ms=10, mew=2, label=f"{label}: unstable")
    ax.set(xlabel=param, ylabel=metric)
    ax.legend(fontsize="small")
    return _save(fig, [ax], title, path)


def plot_feedback(steps, box_half_width_deg: float, path_stem: str | Path, title: str = "") -> list[Path]:
    """Katz 2025 Figs. 1-7 from a feedback run (``/steps`` of ``geojax simulate --out``): the ground track
    (lambda - lambda_d, latitude) inside the box; the delivered acceleration per ECEF axis and its norm
    over the run; and a two-day close-up of the z axis mid-run (Fig. 5)."""
    days = np.asarray(steps["t_s"]) / 86400.0
    u = np.stack([np.asarray(steps[k]) for k in ("ux_mps2", "uy_mps2", "uz_mps2")], -1) * 1e-3  # km/s^2
    box = box_half_width_deg
    fig, ax = plt.subplots(figsize=(6, 6), constrained_layout=True)
    ax.plot(steps["dlon_deg"], steps["lat_deg"], lw=0.3)
    ax.plot([-box, box, box, -box, -box], [-box, -box, box, box, -box], "r--", label="box")
    ax.set(xlabel="λ − λ_d (deg)", ylabel="latitude (deg)", aspect="equal")
    ax.legend()
    track = _save(fig, [ax], title, f"{path_stem}-ground-track.png")
    fig, axes = plt.subplots(5, 1, figsize=(10, 11), constrained_layout=True)
    for a, series, label in zip(axes, [u[:, 0], u[:, 1], u[:, 2], np.linalg.norm(u, axis=-1)],
                                ["u_x", "u_y", "u_z", "|u|"]):
        a.plot(days, series, lw=0.4)
        a.set(xlabel="days", ylabel=f"{label} (km/s²)")
    mid = days[len(days) // 2]
    close = (days >= mid) & (days <= mid + 2.0)
    axes[4].step(days[close], u[close, 2], where="post")
    axes[4].set(xlabel="days", ylabel="u_z (km/s²), 2 days")
    history = _save(fig, list(axes), title, f"{path_stem}-thrust.png")
    return [track, history]


def ground_track_deg(lon_deg, ex, ey, ix, iy, samples_per_cycle: int = 48):
    """Longitude and latitude (deg) over each cycle, rebuilt from its mean elements [n].

    First order in e and i: the true minus the mean longitude is 2 (f sin L - g cos L)
    and the latitude i sin(L - Omega) = 2 (h sin L - k cos L) for MEE (f, g, h, k),
    with L the true longitude running once round per cycle.  This is the daily
    libration of Li 2022 Fig. 4 drawn from the stored cycle means.
    """
    turn = np.linspace(0.0, 2 * np.pi, samples_per_cycle, endpoint=False)[None, :]
    lon = np.degrees(np.unwrap(np.radians(np.asarray(lon_deg))))[:, None]
    d_lon, lat = libration_rad(turn, *(np.asarray(x)[:, None] for x in (ex, ey, ix, iy)))
    return (lon + np.degrees(d_lon)).ravel(), np.degrees(lat).ravel()


def libration_rad(true_lon_rad, f, g, h, k):
    """(true minus mean longitude, latitude) at true longitude L, first order in MEE (f, g, h, k)."""
    s, c = np.sin(true_lon_rad), np.cos(true_lon_rad)
    return 2 * (f * s - g * c), 2 * (h * s - k * c)


def _padded(values, factor: float = 1.5):
    centre, half = 0.5 * (np.max(values) + np.min(values)), 0.5 * (np.max(values) - np.min(values))
    half = max(half * factor, 1e-6)
    return centre - half, centre + half


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
