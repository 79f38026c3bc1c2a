"""What is printed and drawn of a sweep's file (``geojax sweep``, ``geojax plot``): one summary line per
controller and grid point, and the figure's title."""

from __future__ import annotations

import itertools

import numpy as np

SUMMARY_ROWS = 40  # grid points listed per controller; the rest: geojax plot or geojax.open_results


def summary(spec, groups) -> list[str]:
    """One line per controller and grid point: ΔV per year (mean ± std over the repetitions), box half-ranges
    and the statuses; a warning where the repetitions of a point are identical (nothing random in them)."""
    from geojax.loop.metrics import STATUS_MEANINGS

    metrics, codes = groups["metrics"], groups["status"]["code"]
    keys = list(spec.grid)
    points = list(itertools.product(*spec.grid.values()))
    lines, identical = [], []
    for i, controller in enumerate(spec.controllers):
        lines.append(f"  {controller}:")
        flat = {k: np.asarray(v[i]).reshape(len(points), spec.repetitions) for k, v in metrics.items()}
        status = np.asarray(codes[i]).reshape(len(points), spec.repetitions)
        for j, point in enumerate(points[:SUMMARY_ROWS]):
            dv = flat["dv_per_year_mps"][j]
            counts = ", ".join(f"{int(np.sum(status[j] == c))} {STATUS_MEANINGS[c]}"
                               for c in range(1, len(STATUS_MEANINGS)) if np.any(status[j] == c))
            where = ", ".join(f"{k.rpartition('.')[2]} {v if isinstance(v, str) else format(v, 'g')}"
                              for k, v in zip(keys, point, strict=True))
            spread = f" ± {np.std(dv):.2f}" if spec.repetitions > 1 else ""
            lines.append(f"    {where}: ΔV {np.mean(dv):.2f}{spread} m/s/yr, max |δλ| "
                         f"{np.max(flat['max_abs_dlon_deg'][j]):.4f}°, max |δφ| {np.max(flat['max_abs_dlat_deg'][j]):.4f}°; "
                         f"{counts or 'all ok'}")
        if len(points) > SUMMARY_ROWS:
            lines.append(f"    ... {len(points) - SUMMARY_ROWS} more grid points (geojax plot, geojax.open_results)")
        if spec.repetitions > 1:
            same = all(np.array_equal(v, v[:, :1].repeat(spec.repetitions, 1), equal_nan=True) for v in flat.values())
            if same:
                identical.append(controller)
    if identical:
        lines.append(f"  warning: the {spec.repetitions} repetitions of every grid point are identical for "
                     f"{', '.join(identical)}: nothing random in them (no orbit-determination or attitude errors, no "
                     f"[dispersion], a deterministic controller); use repetitions = 1, or add errors or a dispersion")
    return lines


def title(attrs, axes: list[str]) -> str:
    """What a sweep figure shows: its swept keys, the sweep's name and the run's length
    ("thrusters.beta_max_deg: fig09, 365.25 days"; "thrusters.beta_max_deg × errors.h_rv: ...")."""
    from geojax import scenario

    days = ""
    try:
        base = scenario.tomllib.loads(str(attrs.get("base_scenario_toml", "")))
        days = f", {base['duration']['days']:g} days"
    except (ValueError, KeyError, TypeError):
        pass
    return f"{' × '.join(axes[1:])}: {attrs.get('name', 'sweep')}{days}"
