"""The file, the summary and the figure of a fuel bound: what ``BoundResult.save``, ``summary`` and ``plot`` give
(``geojax bound --out`` calls them; ``geojax plot`` draws the figure of the file).

The file (``kind = "bound"``): ``/metrics`` (the bound, the plan and the re-simulation per year, their gap, the
re-simulation's box and status, the linear model's error, the acquisition and end condition), ``/rounds`` (one
row per linearisation) and ``/slots`` (per slot: its mid-time, the RSW and per-thruster Delta-V, the flown
longitude offset and latitude at every step start); attributes ``scenario``, ``geometry``, ``epoch_tt_s`` and
``slot_s`` beside ``store.write_h5``'s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

DIMS = {"rounds": ("round",), "slots": ("slot",), "slots/dv_thruster_mps": ("slot", "thruster"),
        "slots/dlon_deg": ("slot", "step"), "slots/lat_deg": ("slot", "step")}


# A bound below this (m/s over the horizon) is the solver's tolerance, not fuel: measured 3e-9 m/s where no thrust
# is needed (a 2-day free-end bound of a run that keeps the box uncontrolled).
ZERO_BOUND_MPS = 1e-6


def gap_percent(r) -> float:
    """How far the re-simulated plan's Delta-V is above the bound, % (0 for a bound of 0: one under
    ``ZERO_BOUND_MPS``, the linear program's tolerance, where the box holds without thrust)."""
    if r.lower_mps <= ZERO_BOUND_MPS:
        return 0.0
    return 100 * (r.resim["dv_per_year_mps"] - r.bound_per_year_mps) / r.bound_per_year_mps


def groups(r) -> dict[str, dict]:
    """The datasets of the bound's file, ``{group: {name: array}}``."""
    metrics = {"bound_per_year_mps": r.bound_per_year_mps, "plan_per_year_mps": r.plan_per_year_mps,
               "resim_dv_per_year_mps": r.resim["dv_per_year_mps"], "gap_percent": gap_percent(r),
               "resim_max_abs_dlon_deg": r.resim["max_abs_dlon_deg"],
               "resim_max_abs_dlat_deg": r.resim["max_abs_dlat_deg"], "status": r.resim_status,
               "linear_error_deg": r.linear_error_deg, "max_abs_box_after_acquisition_deg": r.max_abs_box_deg,
               "acquisition_days": r.acquisition_days, "free_end": int(r.free_end)}
    rounds = {k: np.array([row[k] for row in r.rounds]) for k in r.rounds[0]}
    slots = {"t_s": r.t_s, "dv_r_mps": r.u_rsw_mps[:, 0], "dv_s_mps": r.u_rsw_mps[:, 1],
             "dv_w_mps": r.u_rsw_mps[:, 2], "dv_thruster_mps": r.thruster_mps,
             "dlon_deg": r.lon_deg, "lat_deg": r.lat_deg}
    return {"metrics": {k: np.asarray(v) for k, v in metrics.items()}, "rounds": rounds, "slots": slots}


def save(r, path: str | Path) -> Path:
    """Write the bound's file to ``path`` (atomically); returns the path."""
    from geojax import store

    return store.write_h5(path, groups(r), r.config_toml, r.wall_s, dims=DIMS,
                          attrs={"kind": "bound", "scenario": r.scenario, "geometry": r.geometry,
                                 "epoch_tt_s": r.epoch_tt_s, "slot_s": r.slot_s})


def plot(r, folder: str | Path) -> list[Path]:
    """The plan's Delta-V per slot and the flown box, ``FOLDER/NAME-bound.png``; returns its path in a list."""
    from geojax import plots
    from geojax.scenario import tomllib

    box = tomllib.loads(r.config_toml)["station"]["box_half_width_deg"]
    return [plots.plot_bound(groups(r)["slots"], box, Path(folder) / f"{r.scenario}-bound.png",
                             title=f"{r.scenario}: the least Delta-V ({r.geometry} thrusters, {r.days:.2f} days)")]


def summary(r) -> list[str]:
    """What ``geojax bound`` prints after the program: the bound, the plan, its re-simulation and the box (its
    yearly rates said to be extrapolated where the plan is shorter than a year)."""
    from geojax.loop.metrics import STATUS_MEANINGS

    after = f"; after day {r.acquisition_days:g}: {r.max_abs_box_deg:.5f} deg" if r.acquisition_days else ""
    short = f"; every m/s/yr extrapolated from {r.days:.2f} days" if r.days < 365.0 else ""  # a year: 365.24
    return [
        f"{r.scenario} ({r.geometry} thrusters, {r.days:.2f} days, {r.slot_s:.0f} s slots{short}):",
        f"  bound                 {r.bound_per_year_mps:10.3f} m/s/yr  (lower bound over every direction the thrusters allow)",
        f"  optimal plan          {r.plan_per_year_mps:10.3f} m/s/yr  (the linear program's, {len(r.rounds)} linearisations)",
        f"  re-simulated plan     {r.resim['dv_per_year_mps']:10.3f} m/s/yr  ({gap_percent(r):+.3f} % over the bound), "
        f"status {r.resim_status} ({STATUS_MEANINGS[r.resim_status]})",
        f"  box                   max |dlon| {r.resim['max_abs_dlon_deg']:.5f} deg, max |lat| "
        f"{r.resim['max_abs_dlat_deg']:.5f} deg{after}; linear model within {r.linear_error_deg:.2e} deg of the flight",
    ]
