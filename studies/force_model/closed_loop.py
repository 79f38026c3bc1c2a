"""What the paper models miss: closed-loop runs of the papers' scenarios with their own force model, with the
degree-2 field (J2 + C22/S22) and with EGM2008 8x8 (which replaces J2 and C22/S22; Sun, Moon, SRP unchanged).

    python studies/force_model/closed_loop.py [--days 365.25] [--scenarios li2022-qffc katz2025-discrete ...]

Per scenario and model: Delta-V per year, its north-south part (planners with burn records: Li 2022 eq. (45)),
the largest longitude and latitude excursions, and the status (0: kept in the box).  No navigation or
attitude errors (seed 0).  Results: ``results/closed_loop.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import geojax
from geojax.loop.metrics import cycle_table

HERE = Path(__file__).resolve().parent
MODELS = {"paper": {}, "J2 + C22/S22": {"forces.c22_s22": True}, "EGM2008 8x8": {"forces.gravity_degree": 8}}


def run(name: str, days: float, overrides: dict) -> dict:
    start = time.perf_counter()
    result = geojax.simulate(geojax.load_scenario(name, {"duration.days": days, "errors.h_rv": 0.0,
                                                         "errors.h_att": 0.0, **overrides}), 0)
    metrics = {k: float(np.asarray(v)) for k, v in result.metrics.items()}
    table = cycle_table(result.records)
    out = {"dv_per_year_mps": metrics["dv_per_year_mps"], "max_abs_dlon_deg": metrics["max_abs_dlon_deg"],
           "max_abs_dlat_deg": metrics["max_abs_dlat_deg"], "status": int(np.asarray(result.status)),
           "wall_s": time.perf_counter() - start}
    if "dv_ns_mps" in table:
        out["dv_ns_per_year_mps"] = float(np.sum(table["dv_ns_mps"])) * 365.25 / days
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--scenarios", nargs="+", default=["li2022-qffc", "li2022-fompc", "katz2025-discrete",
                                                            "ye2022-ex1"])
    args = parser.parse_args()
    results = {"command": "python studies/force_model/closed_loop.py " + " ".join(sys.argv[1:]), "days": args.days,
               "runs": {}}
    for name in args.scenarios:
        for model, overrides in MODELS.items():
            results["runs"].setdefault(name, {})[model] = run(name, args.days, overrides)
            print(name, model, results["runs"][name][model], flush=True)
    lines = ["# Closed loop: the papers' force models against EGM2008 8x8", "",
             f"`{results['command']}`: {args.days:g} days, no errors, seed 0.  ΔV per year (north-south part "
             "where the planner records its burns), largest |Δλ| and |φ| over the run, status.  The papers' "
             "models: li2022 and ye2022 J2 only (no C22/S22), katz2025 J2 + C22/S22; all with Sun, Moon, SRP.", "",
             "| scenario | model | ΔV (m/s/yr) | north-south | in plane (total − north-south) | max abs dlon (deg) "
             "| max abs dlat (deg) | status |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, models in results["runs"].items():
        for model, r in models.items():
            ns = r.get("dv_ns_per_year_mps")
            split = (f"{ns:.3f} | {r['dv_per_year_mps'] - ns:.3f}") if ns is not None else "– | –"
            lines.append(f"| {name} | {model} | {r['dv_per_year_mps']:.3f} | {split} | {r['max_abs_dlon_deg']:.4f} | "
                         f"{r['max_abs_dlat_deg']:.4f} | {r['status']} |")
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "closed_loop.json").write_text(json.dumps(results, indent=1))
    (HERE / "results" / "closed_loop.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
