"""Li's satellite losing an arm on a random day: a Monte Carlo of the one-arm keeping, told against not told, and
four thrusters against two.

    python studies/contingencies/arm_lost.py [--samples 64] [--days 365.25] [--out studies/contingencies/results]

``li2022-qffc`` (the QFFC, Li's two arms, no errors) flown ``--days`` with ``--samples`` draws of the day thruster 0
stops for good (``faults.out_from_day = "uniform"``: uniform over the run, one draw per sample from the faults
part's own stream, seeds 0 .. samples - 1), in three cases: two thrusters and the planner told (``control.burns.
one_arm``: arm 1 flies both nodes), two thrusters not told (it plans the pair as if nothing were wrong), the same
with the re-acquisition law (``controller.recovery``) taking over out of the box, and four thrusters told (thruster
2, arm 0's second, takes over).  The nominal run (no fault; without errors every sample is
the same) gives the Delta-V penalty.  Writes ``arm_lost.json`` and ``arm_lost.md`` into ``--out``: the fraction of
samples that keep the box, the Delta-V penalty over the nominal (mean, and the largest), the days out of the box and
to re-acquire it, and the wall time.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
CASES = {
    "2 thrusters, told": {"thrusters.count": 2},
    "2 thrusters, not told": {"thrusters.count": 2, "faults.planner_told": False},
    "2 thrusters, not told, re-acquisition law": {"thrusters.count": 2, "faults.planner_told": False,
                                                  "controller.recovery": True},
    "4 thrusters, told": {"thrusters.count": 4},
}


def run_case(overrides: dict, days: float, samples: int) -> dict:
    sc = scenario.load("li2022-qffc", {"duration.days": days, "faults.thruster_out": 0,
                                       "faults.out_from_day": "uniform", **overrides})
    begun = time.perf_counter()
    result = simulate_batch([sc] * samples, seeds=np.arange(samples))
    wall_s = time.perf_counter() - begun
    m = {k: np.asarray(v, float) for k, v in result.metrics.items()}
    start_days = np.asarray(result.records.cycles.states["faults"].out_from_s)[:, 0] / 86400.0
    status = [STATUS_MEANINGS[int(s)] for s in result.status]
    return {"status": status, "kept": float(np.mean(np.asarray(result.status) == 0)),
            "out_from_day": start_days.tolist(), "dv_per_year_mps": m["dv_per_year_mps"].tolist(),
            "days_out_of_box": m["days_out_of_box"].tolist(), "reacquire_days": m["reacquire_days"].tolist(),
            "max_abs_dlon_deg": m["max_abs_dlon_deg"].tolist(), "wall_s": wall_s}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    nominal = geojax.simulate(scenario.load("li2022-qffc", {"duration.days": args.days}), seed=0)
    dv_nominal = float(nominal.metrics["dv_per_year_mps"])
    rows = {}
    for label, overrides in CASES.items():
        rows[label] = run_case(overrides, args.days, args.samples)
        print(label, f"kept {rows[label]['kept']:.3f}", f"{rows[label]['wall_s']:.0f} s", flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    payload = {"samples": args.samples, "days": args.days, "geojax": geojax.__version__,
               "dv_nominal_per_year_mps": dv_nominal, "cases": rows}
    (args.out / "arm_lost.json").write_text(json.dumps(payload, indent=1))
    (args.out / "arm_lost.md").write_text(table(payload))
    print(table(payload))


def table(payload: dict) -> str:
    """The study's table from its results (``arm_lost.json``)."""
    lines = [f"Thruster 0 lost for good on a day drawn uniform over the run: {payload['samples']} samples of "
             f"li2022-qffc, {payload['days']:g} days (`python studies/contingencies/arm_lost.py --samples "
             f"{payload['samples']} --days {payload['days']:g}`; geojax {payload['geojax']}). ΔV penalty: over the "
             f"run without the fault, {payload['dv_nominal_per_year_mps']:.2f} m/s/yr. Days out: of the samples "
             "that left the box, the mean; re-acquired: of those, the ones back in it at the run's end.", "",
             "| case | box kept | ΔV penalty, mean (m/s/yr) | largest | left the box | days out (mean) | "
             "re-acquired | wall (s) |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for label, r in payload["cases"].items():
        penalty = np.asarray(r["dv_per_year_mps"]) - payload["dv_nominal_per_year_mps"]
        out = np.asarray(r["days_out_of_box"])
        left = out > 0
        back = left & (np.asarray(r["reacquire_days"]) > 0)
        lines.append(f"| {label} | {r['kept']:.3f} ({sum(s == 'ok' for s in r['status'])}/{len(r['status'])}) | "
                     f"{penalty.mean():+.2f} | {penalty.max():+.2f} | {int(left.sum())} | "
                     f"{out[left].mean() if left.any() else 0.0:.1f} | {int(back.sum())}/{int(left.sum())} | "
                     f"{r['wall_s']:.0f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
