"""How long must a tuning's horizon be for the yearly Delta-V it minimises to be the year's?

    python studies/ablation/tuning_horizon.py

One year at the papers' gains of three laws (``katz2025-continuous`` clipped, ``katz2025-discrete``,
``li2022-qffc``); from the per-cycle Delta-V, the yearly Delta-V extrapolated from the first T days (what a
tuning over T days minimises) and from every T-day window of the year, against the year's own.  The
threshold of ``geojax.tune.spec.MIN_HORIZON_DAYS`` (half a year) comes from this table.

Writes ``studies/ablation/results/tuning_horizon.md``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import geojax
from geojax.physics.constants import SIDEREAL_DAY_S

CASES = [("katz2025-continuous", {"controller.thrust_mode": "continuous-clipped"}), ("katz2025-discrete", {}),
         ("li2022-qffc", {})]
HORIZONS_DAYS = (3, 7, 10, 14, 20, 28, 42, 56, 91, 182)
YEAR_S = 365.25 * 86400.0
OUT = Path(__file__).resolve().parent / "results" / "tuning_horizon.md"


def per_year(dv_mps, cycles) -> np.ndarray:
    return np.asarray(dv_mps) * YEAR_S / (cycles * SIDEREAL_DAY_S)


def main() -> None:
    lines = ["# Yearly ΔV extrapolated from a horizon of T cycles, against the year's (papers' gains)", "",
             "`python studies/ablation/tuning_horizon.py`; per case, the year's ΔV (m/s/yr) and, per T, the "
             "difference of the extrapolation from the first T cycles (what a tuning over T days minimises) and "
             "the range over every T-cycle window of the year.", ""]
    for name, overrides in CASES:
        result = geojax.simulate(geojax.load_scenario(name, {"duration.days": 365.25, **overrides}))
        dv = np.asarray(result.records.cycles.dv_mps)
        year = float(per_year(dv.sum(), dv.size))
        lines += [f"## {name} {' '.join(f'{k} = {v}' for k, v in overrides.items())}".rstrip(), "",
                  f"year: {year:.3f} m/s/yr", "", "| T (cycles) | from the epoch | any window of the year |",
                  "|---|---|---|"]
        for days in HORIZONS_DAYS:
            first = float(per_year(dv[:days].sum(), days))
            windows = per_year(np.convolve(dv, np.ones(days), "valid"), days)
            lines.append(f"| {days} | {100 * (first / year - 1):+.1f} % | {100 * (windows.min() / year - 1):+.1f} "
                         f"… {100 * (windows.max() / year - 1):+.1f} % |")
        lines.append("")
        print("\n".join(lines[-len(HORIZONS_DAYS) - 6:]), flush=True)
    OUT.write_text("\n".join(lines))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
