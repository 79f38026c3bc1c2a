"""The figures of one run against time: a closed loop's mean elements (``plot_cycles``) and station keeping
(``plot_station_keeping``, Li 2022 Figs. 4-8), a feedback run (``plot_feedback``, Katz 2025 Figs. 1-7), a
transfer (``plot_transfer``) and a fuel bound's plan (``plot_bound``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import MaxNLocator

from geojax.plots.ground_track import ground_track_deg
from geojax.plots.labels import _label, _scaled, decade
from geojax.plots.layout import _extent, _legend_above, _padded, _square, _zoom
from geojax.plots.style import FORMATS, _save, styled

DAY_S = 86400.0
UNCONTROLLED_DAYS = 30.0  # the uncontrolled ground track shown beside a closed loop (Li 2022 Fig. 4)
# The frame of the thrust figure's u_x, u_y, u_z (the loop records the delivered acceleration in it).
ECEF_AXES = "delivered thrust acceleration u, Earth-fixed (ECEF) axes: x to the Greenwich meridian, z to the pole"
INSET_RATIO = 0.2  # the controlled path gets a zoomed inset when it spans less than this of the uncontrolled one


@styled
def plot_cycles(cycles: dict[str, np.ndarray], path: str | Path, title: str = "", dpi: int = 150) -> Path:
    """Mean-element histories of a run: longitude, drift, eccentricity and inclination vectors, a.

    ``cycles`` holds the ``/cycles`` datasets of ``geojax propagate`` (t_s, lon_deg, drift_deg_per_day, ex, ey,
    ix, iy, a_m; one value per cycle).
    """
    days = np.asarray(cycles["t_s"]) / DAY_S
    fig, axes = plt.subplots(2, 3, figsize=(7.2, 4.6), constrained_layout=True)
    ax = axes.ravel()
    ax[0].plot(days, np.degrees(np.unwrap(np.radians(cycles["lon_deg"]))))
    ax[0].set(xlabel="days", ylabel="mean longitude (deg E)")
    label, (drift,) = _scaled("drift", "deg/day", cycles["drift_deg_per_day"])
    ax[1].plot(days, drift)
    ax[1].set(xlabel="days", ylabel=label)
    label, (da,) = _scaled("mean a − 42164.17", "km", (np.asarray(cycles["a_m"]) - 42164.17e3) / 1e3)
    ax[2].plot(days, da)
    ax[2].set(xlabel="days", ylabel=label)
    for a, (x, y, xname, yname) in zip(ax[3:5], [("ex", "ey", "e_x", "e_y"), ("ix", "iy", "i_x = h", "i_y = k")]):
        power = decade(cycles[x], cycles[y])
        xs, ys = (np.asarray(cycles[k]) / 10.0**power for k in (x, y))
        a.plot(xs, ys)
        a.plot(xs[:1], ys[:1], "o", ms=4, label="start")
        a.set(xlabel=_label(xname, "", power), ylabel=_label(yname, "", power))
        _square(a, xs, ys)
        a.legend(loc="best")
    label, (incl,) = _scaled("mean inclination", "deg", np.degrees(2 * np.arctan(np.hypot(cycles["ix"], cycles["iy"]))))
    ax[5].plot(days, incl)
    ax[5].set(xlabel="days", ylabel=label)
    for a in ax[[0, 1, 2, 5]]:
        a.xaxis.set_major_locator(MaxNLocator(5))
        a.yaxis.set_major_locator(MaxNLocator(5))
    return _save(fig, ax, title, path, dpi)


@styled
def plot_station_keeping(cycles, reference, target, path: str | Path, title: str = "",
                         box_half_width_deg: float | None = None, dpi: int = 150) -> Path:
    """Li 2022 Figs. 4-8 from a closed-loop run: mean longitude offset; the (δe_x, δe_y) and (δi_x, δi_y) planes
    with the uncontrolled reference dashed and, when the controlled path is small beside it, a zoomed inset; the
    ground track (δλ, δφ) with the reference's first 30 days and the ±box; ΔV_NS per cycle (eq. (45)) and the
    mean pitch angle (eq. (46)).

    ``cycles``, ``reference`` and ``target`` are the /cycles, /reference and /target groups of
    ``geojax simulate --out``; ``box_half_width_deg`` draws the station's box on the ground track.
    """
    days = np.asarray(cycles["t_s"]) / DAY_S
    ref_days = np.asarray(reference["t_s"]) / DAY_S
    run = f"controlled, {_days_text(_run_days(cycles['t_s']))} days"
    fig, axes = plt.subplots(2, 3, figsize=(7.2, 5.2), constrained_layout=True)
    ax = axes.ravel()
    label, (dlon,) = _scaled("mean δλ", "deg", np.asarray(cycles["lon_deg"]) - target["lon_deg"])
    ax[0].plot(days, dlon)
    ax[0].set(xlabel="days", ylabel=label)
    for a, (x, y, name) in zip(ax[1:3], [("ex", "ey", "e"), ("ix", "iy", "i")]):
        offsets = [np.asarray(g[k]) - target[k] for g in (reference, cycles) for k in (x, y)]
        power = decade(*offsets)
        ref_x, ref_y, x_, y_ = (o / 10.0**power for o in offsets)
        a.plot(ref_x, ref_y, "r--", lw=0.8, label=f"uncontrolled, {_days_text(np.ptp(ref_days))} days")
        a.plot(x_, y_, "C0", label=run)
        a.plot(0.0, 0.0, "k+", ms=7, label="target")
        a.set(xlabel=_label(f"δ{name}_x", "", power), ylabel=_label(f"δ{name}_y", "", power))
        _square(a, np.r_[ref_x, x_, 0.0], np.r_[ref_y, y_, 0.0])
        if 0.0 < _extent(x_, y_) < INSET_RATIO * _extent(ref_x, ref_y):
            _zoom(a, x_, y_, np.r_[ref_x, x_], np.r_[ref_y, y_])
        _legend_above(a)
    month = ref_days - ref_days[0] <= UNCONTROLLED_DAYS
    ref_lon, ref_lat = ground_track_deg(*(np.asarray(reference[k])[month] for k in ("lon_deg", "ex", "ey", "ix", "iy")))
    lon, lat = ground_track_deg(*(np.asarray(cycles[k]) for k in ("lon_deg", "ex", "ey", "ix", "iy")))
    dlon, box = lon - target["lon_deg"], box_half_width_deg
    ax[3].plot(ref_lon - target["lon_deg"], ref_lat, "r--", lw=0.6,
               label=f"uncontrolled, first {_days_text(np.ptp(ref_days[month]))} days")
    ax[3].plot(dlon, lat, "C0", lw=0.6, label=run)
    if box is None:
        ax[3].set(xlim=_padded(dlon), ylim=_padded(lat))
    else:
        ax[3].plot([-box, box, box, -box, -box], [-box, -box, box, box, -box], "k--", lw=0.8, label=f"box ±{box:g}°")
        ax[3].set(xlim=_padded(np.r_[dlon, -box, box], 1.15), ylim=_padded(np.r_[lat, -box, box], 1.15), aspect="equal")
    ax[3].set(xlabel="δλ (deg)", ylabel="δφ (deg)")
    ax[3].xaxis.set_major_locator(MaxNLocator(4, symmetric=box is not None))
    ax[3].yaxis.set_major_locator(MaxNLocator(4, symmetric=box is not None))
    _legend_above(ax[3])
    v_total = np.asarray(cycles["v1_mps"]) + np.asarray(cycles["v2_mps"])
    dv_ns = np.asarray(cycles["dv_ns_mps"])
    label, (dv_ns_shown,) = _scaled("ΔV_NS per cycle", "m/s", dv_ns)
    ax[4].plot(days, dv_ns_shown)
    ax[4].set(xlabel="days", ylabel=label)
    mean_beta = np.degrees(np.arcsin(np.clip(dv_ns / np.where(v_total > 0, v_total, 1.0), 0.0, 1.0)))
    ax[5].plot(days[v_total > 0], mean_beta[v_total > 0])
    ax[5].set(xlabel="days", ylabel=r"mean pitch $\bar{\beta}$ (deg)")
    for a in ax[[0, 4, 5]]:
        a.xaxis.set_major_locator(MaxNLocator(5))
    return _save(fig, ax, title, path, dpi)


@styled
def plot_feedback(steps, box_half_width_deg: float, path_stem: str | Path, title: str = "", dpi: int = 150,
                  fmt: str = "png") -> list[Path]:
    """Katz 2025 Figs. 1-7 from a feedback run (``/steps`` of ``geojax simulate --out``: t_s, dlon_deg, lat_deg and
    the delivered ECEF acceleration ux_mps2, uy_mps2, uz_mps2): the ground track (λ − λ_d, latitude) inside the
    box, to ``{path_stem}-ground-track.{fmt}``; the acceleration per axis and its norm over the run and a two-day
    close-up of the z axis mid-run (Fig. 5), in µm/s² on one scale for the three axes, the frame named above, to
    ``{path_stem}-thrust.{fmt}``."""
    if fmt not in FORMATS:
        raise ValueError(f"fmt: one of {', '.join(FORMATS)}, got {fmt!r}")
    days = np.asarray(steps["t_s"]) / DAY_S
    u_um = np.stack([np.asarray(steps[k]) for k in ("ux_mps2", "uy_mps2", "uz_mps2")], -1) * 1e6  # µm/s²
    box = box_half_width_deg
    dlon, lat = np.asarray(steps["dlon_deg"]), np.asarray(steps["lat_deg"])
    fig, ax = plt.subplots(figsize=(3.6, 3.9), constrained_layout=True)
    ax.plot(dlon, lat, lw=0.3, label=f"track, {_days_text(_run_days(steps['t_s']))} days")
    ax.plot([-box, box, box, -box, -box], [-box, -box, box, box, -box], "r--", lw=0.8, label=f"box ±{box:g}°")
    ax.set(xlabel="λ − λ_d (deg)", ylabel="latitude (deg)", aspect="equal",
           xlim=_padded(np.r_[dlon, -box, box], 1.1), ylim=_padded(np.r_[lat, -box, box], 1.1))
    ax.xaxis.set_major_locator(MaxNLocator(5, symmetric=True))
    ax.yaxis.set_major_locator(MaxNLocator(5, symmetric=True))
    _legend_above(ax)
    track = _save(fig, [ax], title, f"{path_stem}-ground-track.{fmt}", dpi)
    fig, axes = plt.subplots(5, 1, figsize=(7.2, 7.6), constrained_layout=True)
    for a, series, name in zip(axes, [u_um[:, 0], u_um[:, 1], u_um[:, 2], np.linalg.norm(u_um, axis=-1)],
                               ["u_x", "u_y", "u_z", "|u|"]):
        a.plot(days, series, lw=0.4)
        a.set(xlabel="days", ylabel=f"{name} (µm/s²)")
    axes[0].set_title(ECEF_AXES, loc="left")
    for a in axes[[1, 2, 4]]:  # one scale for the three axes: a component at rounding level (1e-16) reads as zero
        a.sharey(axes[0])
    mid = days[len(days) // 2]
    close = (days >= mid) & (days <= mid + 2.0)
    axes[4].step(days[close], u_um[close, 2], where="post", lw=0.8)
    axes[4].set(xlabel="days", ylabel="u_z (µm/s²)")
    axes[4].set_title("u_z, two days mid-run", loc="left")
    history = _save(fig, list(axes), title, f"{path_stem}-thrust.{fmt}", dpi)
    return [track, history]


@styled
def plot_transfer(records, path: str | Path, title: str = "", dpi: int = 150) -> Path:
    """A transfer's orbit and mass against time (``/records`` of ``geojax transfer --out``: t_days, a_km, e,
    i_deg, mass_kg, one row per record interval)."""
    days = np.asarray(records["t_days"])
    fig, axes = plt.subplots(2, 2, figsize=(7.2, 4.6), constrained_layout=True)
    ax = axes.ravel()
    for a, (key, name, unit) in zip(ax, [("a_km", "semi-major axis", "km"), ("e", "eccentricity", ""),
                                          ("i_deg", "inclination", "deg"), ("mass_kg", "mass", "kg")]):
        a.plot(days, records[key], "o-" if len(days) < 30 else "-", ms=3)  # a short transfer: its few records seen
        a.set(xlabel="days", ylabel=_label(name, unit))
        a.xaxis.set_major_locator(MaxNLocator(5))
    return _save(fig, ax, title, path, dpi)


@styled
def plot_bound(slots, box_half_width_deg: float, path: str | Path, title: str = "", dpi: int = 150) -> Path:
    """A fuel bound's plan: the Delta-V of each slot in R, S, W, and the flown longitude offset and latitude at
    every step start inside the ±box (``/slots`` of ``geojax bound --out``)."""
    t_s = np.asarray(slots["t_s"])
    slot_s = 2 * t_s[0]  # slot mid-times: (k + 1/2) slot_s
    steps = np.asarray(slots["dlon_deg"]).shape[1]
    step_days = ((t_s[:, None] - slot_s / 2) + np.arange(steps) * slot_s / steps).ravel() / DAY_S
    fig, ax = plt.subplots(2, 1, figsize=(7.2, 4.6), sharex=True, constrained_layout=True)
    for key, name in (("dv_r_mps", "R"), ("dv_s_mps", "S"), ("dv_w_mps", "W")):
        ax[0].step(t_s / DAY_S, slots[key], where="mid", label=name)
    ax[0].set(ylabel="ΔV per slot (m/s)")
    _legend_above(ax[0])
    for key, name in (("dlon_deg", "δλ"), ("lat_deg", "δφ")):
        ax[1].plot(step_days, np.asarray(slots[key]).ravel(), label=name)
    box = box_half_width_deg
    ax[1].plot(step_days[[0, -1]], [box, box], "k--", lw=0.8, label=f"box ±{box:g}°")
    ax[1].plot(step_days[[0, -1]], [-box, -box], "k--", lw=0.8)
    ax[1].set(xlabel="days", ylabel="flown (deg)")
    _legend_above(ax[1])
    return _save(fig, ax, title, path, dpi)


def _run_days(t_s) -> float:
    """The days a run of equally spaced samples at ``t_s`` covers: their count times their spacing."""
    t_s = np.asarray(t_s, float)
    return t_s.size * float(np.median(np.diff(t_s))) / DAY_S if t_s.size > 1 else 0.0


def _days_text(days: float) -> str:
    return f"{days:.0f}" if days >= 2.0 else f"{days:.1f}"
