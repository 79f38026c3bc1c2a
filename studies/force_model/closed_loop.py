"""What the paper models miss: closed-loop runs of the papers' scenarios with their own force model, with the
degree-2 field (J2 + C22/S22) and with EGM2008 8x8 (which replaces J2 and C22/S22; Sun, Moon, SRP unchanged).

    python studies/force_model/closed_loop.py [--days 365.25] [--scenarios li2022-qffc katz2025-discrete ...]

Per scenario and model: Delta-V per year split north-south / in plane, the largest longitude and latitude
excursions, and the status (0: kept in the box).  The split: for the planners, the north-south part from
their burn records (Li 2022 eq. (45)) and the rest in plane; for Katz's feedback laws, which act on the
Earth-fixed axes, the integrals of |a_z| and of |(a_x, a_y)| of the delivered acceleration over the steps
(the Earth's axis is the orbit normal to within the inclination; the discrete law's per-axis thrusters make
the first exactly its z thrusters' Delta-V; for the continuous and constant laws both are parts of one
thrust vector, and they add to more than its norm).  No navigation or attitude errors (seed 0).  Results:
``results/closed_loop.json`` and ``.md``.
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
    scenario = geojax.load_scenario(name, {"duration.days": days, "errors.h_rv": 0.0, "errors.h_att": 0.0,
                                           **overrides})
    feedback = scenario.controller == "lyapunov"  # Katz's laws: the split from the step records
    result = geojax.simulate(scenario, 0, keep_steps=feedback)
    metrics = {k: float(np.asarray(v)) for k, v in result.metrics.items()}
    table = cycle_table(result.records)
    per_year = 365.25 / days
    out = {"dv_per_year_mps": metrics["dv_per_year_mps"], "max_abs_dlon_deg": metrics["max_abs_dlon_deg"],
           "max_abs_dlat_deg": metrics["max_abs_dlat_deg"], "status": int(np.asarray(result.status)),
           "wall_s": time.perf_counter() - start}
    if feedback:
        a = np.asarray(result.records.steps.accel_ecef_mps2) * result.step_s  # [cycle, step, 3] m/s per step
        out["dv_ns_per_year_mps"] = float(np.sum(np.abs(a[..., 2]))) * per_year
        out["dv_in_plane_per_year_mps"] = float(np.sum(np.hypot(a[..., 0], a[..., 1]))) * per_year
        out["dv_from_steps_per_year_mps"] = float(np.sum(np.linalg.norm(a, axis=-1))) * per_year
    elif "dv_ns_mps" in table:
        out["dv_ns_per_year_mps"] = float(np.sum(table["dv_ns_mps"])) * per_year
        out["dv_in_plane_per_year_mps"] = out["dv_per_year_mps"] - out["dv_ns_per_year_mps"]
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--scenarios", nargs="+", default=[
        "katz2025-continuous", "katz2025-discrete", "katz2025-constant", "ye2022-ex1", "ye2022-ex2", "ye2022-ex3",
        "ye2022-ex4", "ye2022-ex5", "li2022-qffc", "li2022-fompc"])
    args = parser.parse_args()
    results = {"command": "python studies/force_model/closed_loop.py " + " ".join(sys.argv[1:]), "days": args.days,
               "runs": {}}
    for name in args.scenarios:  # the tables are written after each scenario, the completed ones in them
        for model, overrides in MODELS.items():
            results["runs"].setdefault(name, {})[model] = run(name, args.days, overrides)
            print(name, model, results["runs"][name][model], flush=True)
        write(results, args.days)


def write(results: dict, days: float) -> None:
    lines = ["# Closed loop: the papers' force models against EGM2008 8x8", "",
             f"`{results['command']}`: {days:g} days, no errors, seed 0.  ΔV per year, its north-south and "
             "in-plane parts (planners: from the burn records, in plane = total − north-south; Katz's laws: "
             "∫|a_z| dt and ∫|(a_x, a_y)| dt of the delivered Earth-fixed acceleration, which for the continuous "
             "and constant laws add to more than the total), largest |Δλ| and |φ| over the run, status "
             "(0: in the box).  The papers' models: li2022 and ye2022 J2 only (no C22/S22), katz2025 J2 + C22/S22; "
             "all with Sun, Moon, SRP.", "",
             "| scenario | model | ΔV (m/s/yr) | north-south | in plane | max abs dlon (deg) | max abs dlat (deg) "
             "| status |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, models in results["runs"].items():
        for model, r in models.items():
            lines.append(f"| {name} | {model} | {r['dv_per_year_mps']:.3f} | {_cell(r, 'dv_ns_per_year_mps')} | "
                         f"{_cell(r, 'dv_in_plane_per_year_mps')} | {r['max_abs_dlon_deg']:.4f} | "
                         f"{r['max_abs_dlat_deg']:.4f} | {r['status']} |")
    lines += ["", "EGM2008 8x8 against each paper's own model (m/s/yr, and relative to the paper's model's total):", "",
              "| scenario | total | north-south | in plane |", "|---|---:|---:|---:|"]
    for name, models in results["runs"].items():
        paper, field = models["paper"], models["EGM2008 8x8"]
        cells = [f"{field[k] - paper[k]:+.3f} ({(field[k] - paper[k]) / paper['dv_per_year_mps']:+.1%})"
                 if k in paper else "–" for k in ("dv_per_year_mps", "dv_ns_per_year_mps", "dv_in_plane_per_year_mps")]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "closed_loop.json").write_text(json.dumps(results, indent=1))
    (HERE / "results" / "closed_loop.md").write_text("\n".join(lines) + "\n")


def _cell(run: dict, key: str) -> str:
    return f"{run[key]:.3f}" if key in run else "–"


if __name__ == "__main__":
    main()
