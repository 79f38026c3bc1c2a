"""A thruster degraded by 5-15 %, the planner told against not told.

    python studies/contingencies/degradation.py [--days 365.25] [--scales 0.85,0.9,0.95] [--out studies/contingencies/results]

``li2022-qffc`` (the QFFC, Li's two arms, no errors: one run per case is every sample) flown ``--days`` with
thruster 0 (arm 0, the southward burns) delivering a fraction s of its thrust from the start
(``faults.thrust_scale = [s, 1, 1, 1]``), and with both thrusters at s.  Told (the default), the planner fires the
degraded thruster's burns 1 / s as long for their planned Delta-V (``control.burns.fly``); not told, it plans as if
nothing were wrong and the loop's next plans see the Delta-V that was not delivered.  Writes ``degradation.json``
and ``degradation.md`` into ``--out``: status, Delta-V (and its difference from the run without the fault), the
largest longitude and latitude excursions, and the thrust lost to the degradation as firing time.
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


def cases(scales: list[float]) -> dict:
    out = {}
    for s in scales:
        for told in (True, False):
            word = "told" if told else "not told"
            out[f"thruster 0 at {s:g}, {word}"] = {"faults.thrust_scale": [s, 1.0, 1.0, 1.0],
                                                    "faults.planner_told": told}
            out[f"both at {s:g}, {word}"] = {"faults.thrust_scale": s, "faults.planner_told": told}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--scales", default="0.85,0.9,0.95")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    labelled = {"no fault": {"faults.enabled": True}, **cases([float(x) for x in args.scales.split(",")])}
    scenarios = [scenario.load("li2022-qffc", {"duration.days": args.days, **o}) for o in labelled.values()]
    begun = time.perf_counter()
    result = simulate_batch(scenarios, seeds=np.zeros(len(scenarios), int))  # one batch, one compiled loop
    wall_s = time.perf_counter() - begun
    m = {k: np.asarray(v, float) for k, v in result.metrics.items()}
    rows = {label: {"status": STATUS_MEANINGS[int(result.status[i])], "dv_per_year_mps": float(m["dv_per_year_mps"][i]),
                    "max_abs_dlon_deg": float(m["max_abs_dlon_deg"][i]),
                    "max_abs_dlat_deg": float(m["max_abs_dlat_deg"][i]),
                    "fault_lost_firing_s": float(m["fault_lost_firing_s"][i]),
                    "days_out_of_box": float(m["days_out_of_box"][i])}
            for i, label in enumerate(labelled)}
    args.out.mkdir(parents=True, exist_ok=True)
    payload = {"days": args.days, "geojax": geojax.__version__, "wall_s": wall_s, "cases": rows,
               "command": f"python studies/contingencies/degradation.py --days {args.days:g} --scales {args.scales}"}
    (args.out / "degradation.json").write_text(json.dumps(payload, indent=1))
    (args.out / "degradation.md").write_text(table(payload))
    print(table(payload))


def table(payload: dict) -> str:
    """The study's table from its results (``degradation.json``)."""
    nominal = payload["cases"]["no fault"]["dv_per_year_mps"]
    lines = [f"Thrust degraded from the start, li2022-qffc, {payload['days']:g} days (`{payload['command']}`; geojax "
             f"{payload['geojax']}; {payload['wall_s']:.0f} s for all cases in one batch). ΔV difference: over "
             f"the run without the fault, {nominal:.2f} m/s/yr.", "",
             "| case | status | ΔV (m/s/yr) | difference | max abs Δλ (deg) | max abs latitude (deg) | "
             "thrust lost (s at full thrust) |", "|---|---|---:|---:|---:|---:|---:|"]
    for label, r in payload["cases"].items():
        lines.append(f"| {label} | {r['status']} | {r['dv_per_year_mps']:.2f} | "
                     f"{r['dv_per_year_mps'] - nominal:+.2f} | {r['max_abs_dlon_deg']:.4f} | "
                     f"{r['max_abs_dlat_deg']:.4f} | {r['fault_lost_firing_s']:.0f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
