"""Figures from results (matplotlib, no display needed).

Every figure is drawn under one style, ``STYLE`` (applied per call, never to matplotlib's global state),
and written at ``dpi`` in the format its path's suffix names (``FORMATS``).  No axis carries offset text:
small quantities are shown in a power of ten named in the axis label (``e_x (10⁻⁵)``, ``decade``).
"""

from __future__ import annotations

import contextlib
import functools
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from geojax.results import split_unit  # noqa: E402
from matplotlib.ticker import MaxNLocator, ScalarFormatter  # noqa: E402

FORMATS = ("png", "pdf", "svg")

STYLE = {
    "font.size": 9, "axes.labelsize": 9, "axes.titlesize": 9, "figure.titlesize": 10,
    "xtick.labelsize": 8, "ytick.labelsize": 8, "legend.fontsize": 8, "legend.framealpha": 0.85,
    "axes.formatter.useoffset": False, "axes.formatter.use_mathtext": True,
    "axes.grid": True, "grid.alpha": 0.3, "grid.linewidth": 0.5, "lines.linewidth": 1.0,
    "savefig.bbox": "tight", "savefig.pad_inches": 0.03,
    "pdf.fonttype": 42,  # TrueType in the PDF: text stays text, as journals ask
}

DAY_S = 86400.0
UNCONTROLLED_DAYS = 30.0  # the uncontrolled ground track shown beside a closed loop (Li 2022 Fig. 4)
INSET_RATIO = 0.2  # the controlled path gets a zoomed inset when it spans less than this of the uncontrolled one

# Axis labels (name, unit) of the metrics; a scenario or controller key is labelled by its ``Field`` (``_quantity``).
QUANTITIES = {
    "dv_per_year_mps": ("ΔV per year", "m/s/yr"), "max_abs_dlon_deg": ("max |δλ|", "deg"),
    "max_abs_dlat_deg": ("max |δφ|", "deg"), "max_abs_mean_dlon_deg": ("max |mean δλ|", "deg"),
    "mean_dlon_deg": ("mean δλ", "deg"), "dlon_half_range_deg": ("δλ half-range", "deg"),
    "dlat_half_range_deg": ("δφ half-range", "deg"), "max_abs_de": ("max |δe|", ""), "max_abs_di": ("max |δi|", ""),
    "mass_used_kg": ("propellant used", "kg"), "cycles_without_solution": ("cycles without solution", ""),
}
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def styled(plot):
    """``plot`` drawn under ``STYLE`` whatever the caller's rcParams, which it leaves as they were."""
    @functools.wraps(plot)
    def styled(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return plot(*args, **kwargs)
    return styled


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
    label, (da,) = _scaled("mean a − 42164.17 km", "km", (np.asarray(cycles["a_m"]) - 42164.17e3) / 1e3)
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
def plot_sweep(groups, axes_names: list[str], path: str | Path, metric: str = "dv_per_year_mps", title: str = "",
               label: str = "", dpi: int = 150) -> Path:
    """A sweep's metric against its first swept parameter: mean and spread (min-max) over the
    repetitions, one line per controller (and per value of any further axis), unstable points
    (status 2) marked with a cross.  ``groups`` are the groups of a ``geojax sweep`` file."""
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

    fig, ax = plt.subplots(figsize=(5.0, 3.4), constrained_layout=True)
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
        for i, controller in enumerate(controllers):
            v = values[i].reshape(len(x), -1, values.shape[-1])  # [x, other axes, reps]
            s = status[i].reshape(v.shape)
            for j in range(v.shape[1]):
                name = " ".join(filter(None, [prefix, controller, f"#{j}" if v.shape[1] > 1 else ""]))
                stable = np.where(s[:, j] == 2, np.nan, v[:, j])
                bad = np.any(s[:, j] == 2, axis=-1)
                with warnings.catch_warnings():  # a point whose every repetition is unstable has no spread
                    warnings.simplefilter("ignore", RuntimeWarning)
                    mean, low, high = (f(stable, axis=-1) for f in (np.nanmean, np.nanmin, np.nanmax))
                    unstable = np.nanmean(np.where(np.isfinite(v[bad, j]), v[bad, j], np.nan), axis=-1)
                line, = ax.plot(x, mean, "o-", ms=3.5, label=f"{name}: mean")
                if v.shape[-1] > 1:
                    ax.fill_between(x, low, high, color=line.get_color(), alpha=0.2, lw=0)
                    bands.append(Patch(color=line.get_color(), alpha=0.2, lw=0,
                                       label=f"{name}: min–max of {v.shape[-1]} repetitions"))
                if bad.any():
                    ax.plot(x[bad], unstable, "x", color=line.get_color(), ms=8, mew=1.5, label=f"{name}: unstable")
    if len(grid_values) <= 12:  # the ticks on the grid's values, not between them
        ax.set_xticks(sorted(grid_values), [f"{v:g}" for v in sorted(grid_values)])
    names = [c.decode() if isinstance(c, bytes) else str(c) for _, g in runs for c in g["grid"]["controller"]]
    ax.set(xlabel=_label(*_quantity(param, names), x_power), ylabel=_label(*_quantity(metric), y_power))
    handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + bands, loc="best", fontsize="small")
    return _save(fig, [ax], title, path, dpi)


@styled
def plot_feedback(steps, box_half_width_deg: float, path_stem: str | Path, title: str = "", dpi: int = 150,
                  fmt: str = "png") -> list[Path]:
    """Katz 2025 Figs. 1-7 from a feedback run (``/steps`` of ``geojax simulate --out``: t_s, dlon_deg, lat_deg and
    the delivered ECEF acceleration ux_mps2, uy_mps2, uz_mps2): the ground track (λ − λ_d, latitude) inside the
    box, to ``{path_stem}-ground-track.{fmt}``; the acceleration per axis and its norm over the run and a two-day
    close-up of the z axis mid-run (Fig. 5), in µm/s² on one scale for the three axes, to
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


def label_for(key: str, controllers=()) -> str:
    """A readable axis label with its unit for a sweep axis, metric or tuned parameter key:
    "thrusters.beta_max_deg" -> "β_max (deg)", "dv_per_year_mps" -> "ΔV per year (m/s/yr)"."""
    return _label(*_quantity(key, controllers))


def field_of(key: str, controllers=()):
    """The ``Field`` that declares a dotted scenario key ("thrusters.beta_max_deg"; a ``controller.`` key from
    the first of ``controllers``, shipped names or import paths, that declares it; of the shipped ones where
    none is named), or None."""
    from geojax.control import REGISTRY, lookup
    from geojax.scenario import SCHEMA

    table, _, name = key.rpartition(".")
    if table != "controller":
        return SCHEMA.get(table, {}).get(name)
    for controller in controllers or REGISTRY:
        with contextlib.suppress(ValueError):
            fields = lookup(controller).FIELDS
            if name in fields:
                return fields[name]
    return None


def _quantity(key: str, controllers=()) -> tuple[str, str]:
    """(name, unit) of a key: a metric's from ``QUANTITIES``; a scenario or controller key's from its ``Field``
    (``symbol``, ``unit``) where it declares them; else the key's last dotted part with a unit suffix read as the
    unit ("spacecraft.mass_kg" -> ("mass", "kg")); a compound unit (``_per_``) is left in the name."""
    if key in QUANTITIES:
        return QUANTITIES[key]
    field = field_of(key, controllers) if "." in key else None
    name = key.rsplit(".", 1)[-1]
    stem, unit = ("", "") if "_per_" in name else split_unit(name)  # the results files' units (geojax.results)
    stem = stem or name
    if field is not None and field.unit is not None:  # the unit declared: the name as written, or its symbol
        stem, unit = field.symbol or name, field.unit
    elif field is not None:
        stem = field.symbol or stem
    return stem, unit.replace("^2", "²")


def decade(*arrays) -> int:
    """The power of ten to show ``arrays`` in (as values / 10**power): 0 while their largest finite magnitude is
    between 0.01 and 99,999 (ΔV in m/s/yr, H_rv = 1000 read best as they are), else that magnitude's power of
    ten (1.2e-4 -> -4)."""
    finite = np.concatenate([np.ravel(np.asarray(a, float)) for a in arrays])
    finite = np.abs(finite[np.isfinite(finite)])
    largest = float(np.max(finite, initial=0.0))
    if largest == 0.0:
        return 0
    power = int(np.floor(np.log10(largest)))
    return 0 if -2 <= power <= 4 else power


def _label(name: str, unit: str = "", power: int = 0) -> str:
    """"e_x (10⁻⁵)", "drift (10⁻³ deg/day)", "β_max (deg)", "H_rv"."""
    scale = f"10{str(power).translate(SUPERSCRIPT)}" if power else ""
    inside = " ".join(filter(None, [scale, unit]))
    return f"{name} ({inside})" if inside else name


def _scaled(name: str, unit: str, *arrays):
    """The label and ``arrays`` in the power of ten that suits them (``decade``)."""
    power = decade(*arrays)
    return _label(name, unit, power), [np.asarray(a, float) / 10.0**power for a in arrays]


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


def _run_days(t_s) -> float:
    """The days a run of equally spaced samples at ``t_s`` covers: their count times their spacing."""
    t_s = np.asarray(t_s, float)
    return t_s.size * float(np.median(np.diff(t_s))) / DAY_S if t_s.size > 1 else 0.0


def _days_text(days: float) -> str:
    return f"{days:.0f}" if days >= 2.0 else f"{days:.1f}"


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
    """A zoomed inset of the path (x, y), its magnification written in it, in the corner of ``ax`` holding the
    fewest of the points (all_x, all_y); the zoomed region is marked on ``ax``."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    u, v = (np.asarray(all_x) - x0) / (x1 - x0), (np.asarray(all_y) - y0) / (y1 - y0)
    corners = [(0.02, 0.02), (1 - size - 0.02, 0.02), (0.02, 1 - size - 0.02), (1 - size - 0.02, 1 - size - 0.02)]
    crowd = [np.sum((u > cx - 0.05) & (u < cx + size + 0.05) & (v > cy - 0.05) & (v < cy + size + 0.05))
             for cx, cy in corners]
    inset = ax.inset_axes([*corners[int(np.argmin(crowd))], size, size])
    inset.plot(x, y, "C0", lw=0.8)
    _square(inset, x, y, 1.3)
    # Tick labels would crowd a box this small; its magnification says the scale instead.
    inset.tick_params(labelbottom=False, labelleft=False, length=2, direction="in")
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


def _save(fig, axes, title: str, path: str | Path, dpi: int = 150) -> Path:
    """Write ``fig`` to ``path`` in the format of its suffix (one of ``FORMATS``) at ``dpi`` under ``STYLE``, with a
    grid on ``axes``, no offset text on any axes and ``title`` above; closes ``fig``."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    try:
        if fmt not in FORMATS:
            raise ValueError(f"figure {str(path)!r}: the suffix must be one of {', '.join('.' + f for f in FORMATS)}")
        with matplotlib.rc_context(STYLE):
            for a in axes:
                a.grid(True, alpha=STYLE["grid.alpha"], linewidth=STYLE["grid.linewidth"])
            for parent in fig.axes:  # insets, and figures built outside STYLE (studies/), included
                for axis in (axis for a in (parent, *parent.child_axes) for axis in (a.xaxis, a.yaxis)):
                    if isinstance(axis.get_major_formatter(), ScalarFormatter):
                        axis.get_major_formatter().set_useOffset(False)
            if title:
                fig.suptitle(title)
            path.parent.mkdir(parents=True, exist_ok=True)
            fig.savefig(path, dpi=dpi, format=fmt)
    finally:
        plt.close(fig)
    return path
