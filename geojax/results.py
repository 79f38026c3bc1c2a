"""Results as labelled arrays: units, descriptions and dimension names of every dataset geojax writes, and
``open_results`` (an ``xarray.Dataset``).

The labels live in the HDF5 file itself, so any HDF5 reader sees them: each dataset carries ``units``
and ``description`` attributes, its axes are named with HDF5 dimension labels (``h5py``'s
``dataset.dims[i].label``; ``controller``, every swept key, ``repetition``, ``cycle``, ``step``,
``iteration``, ``start``), and the ``/grid`` datasets of a sweep are attached as dimension scales (the
coordinates).  ``open_results`` turns that into one ``xarray.Dataset``: the ``/metrics`` datasets under
their own names (``dv_per_year_mps``), every other group's as ``GROUP__NAME`` (``cycles__lon_deg``),
the status as ``status``, the file's attributes (provenance, the scenario's TOML) as the Dataset's.

A sample whose status is not 0 (it left the box, drifted off the station, ran out of propellant, met a cycle
without a solution) has failed: its numbers are not a station keeping's.  ``held`` masks them out of a Dataset,
``summary_table`` gives the failed count and the statistics over the samples that held, and both rest on
``held_statistics`` (with ``held_percentiles``), the one computation the sweep's printed summary and its figure use
too.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from geojax.loop.metrics import STATUS_OK, STATUS_TEXT
from geojax.states import descriptions as part_descriptions

# Unit of a dataset by the end of its name (the project's naming rule: the name says the unit).
UNIT_SUFFIXES = (
    ("_per_year_mps", "m/s/yr"), ("_s_per_orbit", "s/orbit"), ("_deg_per_day", "deg/day"), ("_mps2", "m/s^2"),
    ("_mps", "m/s"), ("_deg", "deg"), ("_rad", "rad"), ("_km", "km"), ("_kg", "kg"), ("_m2", "m^2"), ("_m", "m"),
    ("_s", "s"), ("_n", "N"), ("_days", "days"), ("_nms", "N m s"),
)
DIMENSIONLESS = {"ex", "ey", "ix", "iy", "max_abs_de", "max_abs_di", "duty_fraction", "duty_x", "duty_y", "duty_z",
                 "ns_fraction", "burns_per_thruster_per_orbit", "burns_total", "cycles_without_solution", "code",
                 "active", "loss", "step_norm", "theta", "temperature", "trust_radius", "constraint", "constraint_lon",
                 "constraint_lat", "status", "time_above_80pct_capacity_fraction"}
DESCRIPTIONS = {
    "dv_per_year_mps": "delta-V per year of the whole run",
    "dv_steady_per_year_mps": "delta-V per year in steady state: the mean of the years after the first",
    **{f"dv_year{k}_mps": f"delta-V of year {k} of the run (366 cycles), per 365.25 days" for k in range(1, 101)},
    "mass_used_kg": "propellant used",
    "max_abs_dlon_deg": "largest |longitude - station| at any step (osculating sub-satellite point)",
    "max_abs_dlat_deg": "largest |latitude| at any step",
    "mean_dlon_deg": "mean longitude offset from the station over every step",
    "dlon_half_range_deg": "half the range of the longitude offset over the run",
    "dlat_half_range_deg": "half the range of the latitude over the run",
    "max_abs_mean_dlon_deg": "largest |one-cycle mean longitude - station| after the first cycle (Li 2022's measure)",
    "max_abs_de": "largest |mean e vector (MEE f, g) - target| after the first cycle; dimensionless (e)",
    "max_abs_di": "largest |mean i vector (MEE h, k) - target| after the first cycle; dimensionless (tan(i/2), "
                  "so 1e-4 is 0.0115 deg of inclination)",
    "duty_fraction": "fraction of the run's time a thruster fires (a planner's burns, eclipse suspensions left out; "
                     "with [faults], as flown: missed burns and thrusters out count nothing)",
    **{f"duty_{axis}": f"fraction of the steps whose thrust has an ECEF {axis} component (Katz 2025's duty of "
                       f"per-axis thrusters; for thrust in any other direction, the firing fraction)"
       for axis in "xyz"},
    "dv_radial_per_year_mps": "radial (RTN R) component of the delta-V per year (a planner's burns, |R| of each "
                              "burn's delta-V): with the robotic arms, the geometry's cosine loss (thrust lines aimed "
                              "through the centre of mass from anti-nadir arms)",
    "dv_ew_per_year_mps": "along-track (RTN T) component of the delta-V per year (a planner's burns, |T| of each "
                          "burn's delta-V): the east-west control of drift and eccentricity",
    "dv_ns_per_year_mps": "cross-track (RTN N) component of the delta-V per year (a planner's burns, |N| of each "
                          "burn's delta-V): the north-south control of inclination; the three components add up to "
                          "more than dv_per_year_mps where a burn is not along one axis; with [faults], all three "
                          "as flown (per thruster, step by step)",
    "cpu_s_per_orbit": "wall seconds per cycle of the compiled closed loop and its metrics alone (no set-up, no "
                       "compilation; with them where a result carries no run time of its own)",
    "burns_total": "burns fired in the run",
    "burns_per_thruster_per_orbit": "burns per thruster per orbit",
    "mean_beta_deg": "mean pitch angle of the burns",
    "cycles_without_solution": "cycles whose plan had no solution",
    # controller.recovery (geojax.control.recovery)
    "recovery_cycles": "cycles flown by the re-acquisition law (controller.recovery), out of the box or unsolved",
    "dv_recovery_mps": "delta-V of the re-acquisition law's cycles (included in dv_per_year_mps)",
    "recovering": "whether the re-acquisition law flew this cycle (controller.recovery)",
    "code": "status: " + STATUS_TEXT,
    "lon_deg": "one-cycle mean longitude (east)",
    "ex": "one-cycle mean eccentricity vector, x (MEE f)", "ey": "one-cycle mean eccentricity vector, y (MEE g)",
    "ix": "one-cycle mean inclination vector, x (MEE h)", "iy": "one-cycle mean inclination vector, y (MEE k)",
    "dv_mps": "delta-V delivered: in /cycles/, within that cycle (not a running total); in a transfer's "
              "/records/, used so far; in /metrics/, over the whole run", "t_s": "time since the start of the run",
    "dlon_deg": "longitude - station longitude", "lat_deg": "latitude",
    "ux_mps2": "delivered acceleration, ECEF x", "uy_mps2": "delivered acceleration, ECEF y",
    "uz_mps2": "delivered acceleration, ECEF z",
    "constraint": "box constraints (longitude, latitude): (largest excursion / box half-width)^2 - 1, <= 0 inside",
    **{f"constraint_{axis}": f"box constraint of the {name}: (largest excursion / box half-width)^2 - 1, <= 0 inside"
       for axis, name in (("lon", "longitude"), ("lat", "latitude"))},
    "best_dv_per_year_mps": "best feasible delta-V per year so far",
    **part_descriptions(),  # each part's own (geojax.states: the wheels', the filter's)
}


# Axis names of the groups every single-run file has (a sweep's and a tuning's are given by their writers).
DEFAULT_DIMS = {"cycles": ("cycle",), "reference": ("reference_cycle",), "steps": ("step",)}


def split_unit(name: str) -> tuple[str, str]:
    """(stem, unit) of a name that ends in a unit suffix ("mass_kg" -> ("mass", "kg")), else (name, "")."""
    for suffix, unit in UNIT_SUFFIXES:
        if name.endswith(suffix) and len(name) > len(suffix):
            return name[: -len(suffix)], unit
    return name, ""


def units_of(name: str) -> str:
    """The unit of a dataset named ``name`` ("" where dimensionless or unknown)."""
    return "" if name in DIMENSIONLESS else split_unit(name)[1]


def label_datasets(f, dims: dict[str, tuple[str, ...]]) -> None:
    """Write units, descriptions and dimension labels into an open ``h5py.File``; attach ``/grid`` as scales.

    ``dims``: {"GROUP" or "GROUP/NAME": names of the leading axes}; a longer dataset's further axes are
    named ``NAME_axisK``.
    """
    import h5py

    dims = {**DEFAULT_DIMS, **dims}
    scales = {}
    if "grid" in f and isinstance(f["grid"], h5py.Group):
        for name, ds in f["grid"].items():
            dim = "controller" if name == "controller" else name.replace("__", ".")
            ds.make_scale(dim)
            scales[dim] = ds
    for group_name, group in f.items():
        if not isinstance(group, h5py.Group):
            continue
        for name, ds in group.items():
            if ds.attrs.get("CLASS") == b"DIMENSION_SCALE":
                _set_units(ds, name)
                continue
            _set_units(ds, name)
            names = dims.get(f"{group_name}/{name}", dims.get(group_name, ()))
            for axis in range(ds.ndim):
                label = names[axis] if axis < len(names) else f"{name}_axis{axis}"
                ds.dims[axis].label = label
                if label in scales and scales[label].shape == (ds.shape[axis],):
                    ds.dims[axis].attach_scale(scales[label])


def _set_units(ds, name: str) -> None:
    ds.attrs["units"] = units_of(name)
    if name in DESCRIPTIONS:
        ds.attrs["description"] = DESCRIPTIONS[name]


def open_results(path: str | Path):
    """A geojax results file (sweep, simulate, propagate, tune) as an ``xarray.Dataset`` with named dimensions,
    coordinates (the swept values and the controllers of a sweep) and units.

    >>> ds = geojax.open_results("fig09.h5")
    >>> ds.dv_per_year_mps.sel(controller="fompc").mean("repetition")      # ΔV against β_max
    """
    import h5py
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{str(path)!r}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise ValueError(f"{str(path)!r}: not an HDF5 file") from None
    with f:
        if "config_toml" not in f.attrs:
            raise ValueError(f"{str(path)!r}: not a geojax results file")
        coords, variables = {}, {}
        fallback = dict(DEFAULT_DIMS)  # files written before the axes were labelled in the file
        if f.attrs.get("kind") == "sweep" and "grid_axes" in f.attrs:
            axes = str(f.attrs["grid_axes"]).split(",")
            fallback.update(dims_of_sweep(axes[1:], cycles=True))
        for group_name, group in f.items():
            if not isinstance(group, h5py.Group):
                continue
            for name, ds in group.items():
                if group_name == "grid":
                    dim = "controller" if name == "controller" else name.replace("__", ".")
                    values = ds[()]
                    if dim == "epoch.utc":  # dates, as datetime64 (``ds.sel({"epoch.utc": "2030"})``)
                        from geojax.sweep.epochs import as_datetime64

                        values = as_datetime64(values)
                    elif values.dtype.kind == "S":
                        values = [v.decode() for v in values]
                    coords[dim] = xr.Variable(dim, values, _attrs(ds))
                    continue
                known = fallback.get(group_name, ())
                dims = [ds.dims[axis].label or (known[axis] if axis < len(known) else f"{name}_axis{axis}")
                        for axis in range(ds.ndim)]
                key = name if group_name == "metrics" else ("status" if group_name == "status" and name == "code"
                                                            else f"{group_name}__{name}")
                variables[key] = xr.Variable(dims, ds[()], _attrs(ds))
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    return xr.Dataset(variables, coords={k: v for k, v in coords.items()}, attrs=attrs)


def _attrs(ds) -> dict:
    out = {}
    for key in ("units", "description"):
        if key in ds.attrs:
            value = ds.attrs[key]
            out[key] = value.decode() if isinstance(value, bytes) else str(value)
    return out


def dims_of_sweep(grid_keys, cycles: bool) -> dict[str, tuple[str, ...]]:
    """The dimension names of a sweep file's groups."""
    axes = ("controller", *grid_keys, "repetition")
    return {"metrics": axes, "status": axes, **({"cycles": (*axes, "cycle")} if cycles else {})}


class HeldStatistics(NamedTuple):
    """Statistics of a metric along one axis over the samples that held (status 0), and how many did not.

    Each field has the shape of the metric less that axis; ``mean``, ``std``, ``min`` and ``max`` are NaN
    where no sample held."""

    samples: np.ndarray  # samples along the axis
    failed: np.ndarray  # of them, those with a status other than 0
    mean: np.ndarray  # over the held samples
    std: np.ndarray  # population standard deviation (ddof 0) over the held samples
    min: np.ndarray
    max: np.ndarray


def held_statistics(values, status, axis: int = -1) -> HeldStatistics:
    """``HeldStatistics`` of ``values`` along ``axis`` over the samples whose ``status`` (same shape) is 0."""
    values, status = np.asarray(values, float), np.asarray(status)
    ok = status == STATUS_OK
    kept = np.where(ok, values, np.nan)
    with warnings.catch_warnings():  # a point where every sample failed has no statistics: NaN, said by `failed`
        warnings.simplefilter("ignore", RuntimeWarning)
        stats = [f(kept, axis=axis) for f in (np.nanmean, np.nanstd, np.nanmin, np.nanmax)]
    return HeldStatistics(np.full(np.sum(ok, axis=axis).shape, values.shape[axis]), np.sum(~ok, axis=axis), *stats)


def held_percentiles(values, status, q=(5.0, 95.0), axis: int = -1) -> np.ndarray:
    """The percentiles ``q`` (%) of ``values`` along ``axis`` over the samples whose ``status`` is 0, stacked first:
    [len(q), shape less ``axis``] (NumPy's linear interpolation between the sorted held values); NaN where none
    held."""
    values, status = np.asarray(values, float), np.asarray(status)
    kept = np.where(status == STATUS_OK, values, np.nan)
    with warnings.catch_warnings():  # a point where every sample failed: NaN, as in ``held_statistics``
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanpercentile(kept, np.asarray(q, float), axis=axis)


def held(ds):
    """``ds`` (an ``open_results`` Dataset) with every per-sample number of a failed sample (status not 0) set
    to NaN: its metrics, and its per-cycle series where the file kept them.  xarray's reductions skip NaN, so
    ``held(ds).dv_per_year_mps.mean("repetition")`` is the mean over the samples that held; count the others
    with ``(ds.status != 0).sum("repetition")`` (``summary_table`` gives both)."""
    if "status" not in ds:
        raise ValueError("status: this file has no per-sample status (a propagation, a bound, a transfer)")
    ok = ds.status == STATUS_OK
    masked = {name: var.where(ok) for name, var in ds.data_vars.items()
              if name != "status" and set(ds.status.dims) <= set(var.dims) and var.dtype.kind in "fiu"}
    return ds.assign(masked)


def summary_table(ds, metric: str = "dv_per_year_mps", over: str | tuple[str, ...] = "repetition"):
    """A ``Dataset`` of ``metric``'s statistics over the axes ``over`` (default the repetitions; a file without
    them: every sample axis) per remaining coordinate (controller, grid point): ``samples``, ``failed`` (status
    not 0) and ``held_mean``, ``held_std``, ``held_min``, ``held_max``, over the samples that held
    (``held_statistics``; NaN where none held).

    >>> summary_table(geojax.open_results("fig09.h5")).sel(controller="qffc")[["failed", "held_mean"]]
    """
    import xarray as xr

    if "status" not in ds:
        raise ValueError("status: this file has no per-sample status (a propagation, a bound, a transfer)")
    if metric not in ds:
        raise ValueError(f"{metric}: not a metric of this file; it has {', '.join(sorted(map(str, ds.data_vars)))}")
    over = tuple(d for d in ((over,) if isinstance(over, str) else over) if d in ds.status.dims) or ds.status.dims
    kept = [d for d in ds.status.dims if d not in over]
    flat = lambda var: var.transpose(*kept, *over).values.reshape(  # noqa: E731
        *(ds.sizes[d] for d in kept), -1)
    stats = held_statistics(flat(ds[metric]), flat(ds.status))
    units = ds[metric].attrs.get("units", "")
    counts = {"samples": stats.samples, "failed": stats.failed}
    variables = {**{name: xr.Variable(kept, value) for name, value in counts.items()},
                 **{f"held_{name}": xr.Variable(kept, getattr(stats, name), {"units": units})
                    for name in ("mean", "std", "min", "max")}}
    return xr.Dataset(variables, coords={d: ds[d] for d in kept if d in ds.coords},
                      attrs={"metric": metric, "over": ",".join(over)})
