"""What solving the MPC's program lane by lane costs (``geojax.per_lane.lane_by_lane``, which makes its numbers
independent of the batch's width) against the vmapped solve it replaced.

    python benchmarks/mpc_per_lane.py [--samples 8] [--days 30] [--pairs 2]

``li2022-mpc`` with Li's nominal errors, ``--samples`` samples in one ``simulate_batch`` (the MPC's 8 lanes per
CPU core), timed after a warm-up call; each variant in a process of its own, the two alternated ``--pairs``
times (``vmap``: ``control.mpc.lane_by_lane`` replaced by the identity before the controller is built).  The
figure is the ratio of sample-years per second, lane by lane over vmapped; both give the same ΔV here.
Results: ``benchmarks/results/mpc_per_lane.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def child(variant: str, samples: int, days: float) -> None:
    import time

    import numpy as np

    import geojax.control.mpc as mpc
    if variant == "vmap":
        mpc.lane_by_lane = lambda fn: fn
    from geojax import scenario, simulate_batch

    sc = scenario.load("li2022-mpc", {"duration.days": days, "errors.h_rv": 1.0, "errors.h_att": 1.0})
    simulate_batch([sc] * samples, seeds=np.arange(samples))
    begun = time.perf_counter()
    result = simulate_batch([sc] * samples, seeds=np.arange(samples) + 100)
    wall_s = time.perf_counter() - begun
    print(json.dumps({"variant": variant, "sample_years_per_s": samples * days / 365.25 / wall_s,
                      "dv_per_year_mps": float(np.mean(np.asarray(result.metrics["dv_per_year_mps"])))}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=8)
    parser.add_argument("--days", type=float, default=30.0)
    parser.add_argument("--pairs", type=int, default=2)
    parser.add_argument("--variant", choices=("map", "vmap"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.variant:
        return child(args.variant, args.samples, args.days)
    runs = []
    for _ in range(args.pairs):
        for variant in ("map", "vmap"):
            out = subprocess.run([sys.executable, __file__, "--variant", variant, "--samples", str(args.samples),
                                  "--days", str(args.days)], capture_output=True, text=True, check=True)
            runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    pairs = [(runs[2 * k], runs[2 * k + 1]) for k in range(args.pairs)]
    ratios = [a["sample_years_per_s"] / b["sample_years_per_s"] for a, b in pairs]
    data = {"command": f"python benchmarks/mpc_per_lane.py --samples {args.samples} --days {args.days:g} "
                       f"--pairs {args.pairs}", "device": f"{platform.processor() or platform.machine()} CPU",
            "runs": runs, "ratios": ratios}
    data["device"] += f", {os.cpu_count()} cores"
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "mpc_per_lane.json").write_text(json.dumps(data, indent=1))
    lines = ["# The MPC's solve lane by lane against vmapped", "", f"`{data['command']}` on {data['device']}, "
             "each variant in a process of its own, alternated.", "",
             "| pair | lane by lane (sample-years/s) | vmapped (sample-years/s) | ratio | ΔV equal |", "|---|---:|---:|---:|---|"]
    for k, ((a, b), r) in enumerate(zip(pairs, ratios)):
        lines.append(f"| {k + 1} | {a['sample_years_per_s']:.3f} | {b['sample_years_per_s']:.3f} | {r:.3f} | "
                     f"{a['dv_per_year_mps'] == b['dv_per_year_mps']} |")
    (HERE / "results" / "mpc_per_lane.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
