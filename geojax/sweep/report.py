"""What is printed and drawn of a sweep's file (``geojax sweep``, ``geojax plot``): one summary line per
controller and grid point, and the figure's title."""

from __future__ import annotations

import itertools

import numpy as np

SUMMARY_ROWS = 40  # grid points listed per controller; the rest: geojax plot or geojax.open_results


def summary(spec, groups) -> list[str]:
    """One line per controller and grid point: over the repetitions that held (status 0), ΔV per year (mean ±
    std; said to be extrapolated where the samples fly less than a year) and the largest longitude and latitude excursions; then how many failed, by status
    (``results.held_statistics``: a failed sample is counted, never averaged in); a warning where the
    repetitions of a point are identical (nothing random in them)."""
    from geojax.loop.metrics import STATUS_MEANINGS
    from geojax.results import held_statistics

    metrics, codes = groups["metrics"], groups["status"]["code"]
    per_year = f"m/s/yr{extrapolated(spec)}"
    keys = list(spec.grid)
    points = list(itertools.product(*spec.grid.values()))
    lines, identical = [], []
    for i, controller in enumerate(spec.controllers):
        lines.append(f"  {controller}:")
        flat = {k: np.asarray(v[i]).reshape(len(points), spec.repetitions) for k, v in metrics.items()}
        status = np.asarray(codes[i]).reshape(len(points), spec.repetitions)
        dv, dlon, dlat = (held_statistics(flat[k], status) for k in
                          ("dv_per_year_mps", "max_abs_dlon_deg", "max_abs_dlat_deg"))
        for j, point in enumerate(points[:SUMMARY_ROWS]):
            where = ", ".join(f"{k.rpartition('.')[2]} {v if isinstance(v, str) else format(v, 'g')}"
                              for k, v in zip(keys, point, strict=True))
            where = where or f"{spec.repetitions} repetitions"  # a sweep without a grid: one point
            lines.append(f"    {where}: {_point(dv, dlon, dlat, j, status[j], STATUS_MEANINGS, per_year)}")
            if "min_separation_km" in flat:  # a sweep of clusters
                lines.append(f"      {separation_line(flat['min_separation_km'][j], flat['alert_km'][j])}")
        if len(points) > SUMMARY_ROWS:
            lines.append(f"    ... {len(points) - SUMMARY_ROWS} more grid points (geojax plot, geojax.open_results)")
        failed = int(np.sum(dv.failed))
        if failed:
            lines.append(f"    {failed} of {status.size} samples failed (status not 0): left out of every mean, "
                         f"spread and maximum above (geojax.results.held, summary_table)")
        if spec.repetitions > 1:
            same = all(np.array_equal(v, v[:, :1].repeat(spec.repetitions, 1), equal_nan=True) for v in flat.values())
            if same:
                identical.append(controller)
    if identical:
        lines.append(f"  warning: the {spec.repetitions} repetitions of every grid point are identical for "
                     f"{', '.join(identical)}: nothing random in them (no orbit-determination or attitude errors, no "
                     f"[dispersion], a deterministic controller); use repetitions = 1, or add errors or a dispersion")
    return lines


def separation_line(min_km, alert_km) -> str:
    """A cluster sweep's grid point: the least separation's percentiles over its samples (every sample, held or
    not: a close approach counts whatever the box did) and the fraction of samples closer than the alert."""
    p5, p50, p95 = np.percentile(min_km, [5, 50, 95])
    below = float(np.mean(min_km < alert_km))
    return (f"min separation {np.min(min_km):.3f} km (percentiles 5/50/95: {p5:.3f} / {p50:.3f} / {p95:.3f} km); "
            f"{below:.1%} of {min_km.size} samples below the alert {float(np.max(alert_km)):g} km")


def extrapolated(spec) -> str:
    """What a yearly rate of the sweep's samples is, where they fly less than a year: " (extrapolated from 10
    days)" ("" for a year or more), as ``geojax simulate``'s summary says it (``runner.report.row_notes``)."""
    from geojax.loop.metrics import YEAR_CYCLES
    from geojax.runner.setup import cycle_count
    from geojax.physics.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S
    from geojax.sweep.spec import _scenario

    # a grid cannot vary the duration (it fixes the compiled loop's shape): the base scenario's with [set]
    days = spec.fixed.get("duration.days") or _scenario(spec, spec.controllers[0], {}).days
    n_cycles = cycle_count(days)
    if n_cycles >= YEAR_CYCLES:
        return ""
    return f" (extrapolated from {n_cycles * SIDEREAL_DAY_S / SECONDS_PER_DAY:.4g} days, {n_cycles} cycles)"


def _point(dv, dlon, dlat, j: int, status, meanings, per_year: str = "m/s/yr") -> str:
    """One grid point's line: the held samples' statistics, then the failed ones by status."""
    n, failed = int(dv.samples[j]), int(dv.failed[j])
    counts = ", ".join(f"{int(np.sum(status == c))} {meanings[c]}" for c in range(1, len(meanings))
                       if np.any(status == c))
    if failed == n:
        return f"all {n} failed ({counts}): no statistics"
    spread = f" ± {dv.std[j]:.2f}" if n - failed > 1 else ""
    held = f"{n - failed} held" if failed else "all ok"
    text = (f"ΔV {dv.mean[j]:.2f}{spread} {per_year}, max |δλ| {dlon.max[j]:.4f}°, max |δφ| {dlat.max[j]:.4f}°; "
            f"{held}")
    return text + (f", {failed} failed ({counts})" if failed else "")


def title(attrs, axes: list[str]) -> str:
    """What a sweep figure shows: its swept keys, the sweep's name and the run's length
    ("thrusters.beta_max_deg: fig09, 365.25 days"; "thrusters.beta_max_deg × errors.h_rv: ..."; without a grid,
    "repetitions alone: mc, 10 days")."""
    from geojax import scenario

    days = ""
    try:
        base = scenario.tomllib.loads(str(attrs.get("base_scenario_toml", "")))
        days = f", {base['duration']['days']:g} days"
    except (ValueError, KeyError, TypeError):
        pass
    swept = " × ".join(axes[1:]) or "repetitions alone"  # a sweep without a grid
    return f"{swept}: {attrs.get('name', 'sweep')}{days}"
