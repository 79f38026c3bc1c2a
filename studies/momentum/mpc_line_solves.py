"""The momentum MPC's line iteration at the operator's hardest held case: how many solves hold 0.35 m with 50 N m s.

    python studies/momentum/mpc_line_solves.py [--solves 2 3 4] [--days 365.25] [--out studies/momentum/results]

The 3000 kg satellite at 19.2° E of ``mpc_capacity.py`` (``OPERATOR``) with its array's centre of pressure 0.35 m
off and 50 N m s wheels, Li's nominal errors (seed 0), ``li2022-momentum-mpc``'s keys, a year from Li's epoch,
flown with ``controller.line_solves`` each of ``--solves`` (the program solved that many times a cycle, first on
last cycle's planned lines, then on the lines the solve before planned).  ``mpc_capacity.md`` found this case held
with the default (2) before the width-independent arithmetic of a4325ad (``physics.trig``'s tan and atan, the
interior point's sums in a fixed order); this says what it does now.  Per case: the status, the largest wheel
momentum and the cycle it peaks in, the ΔV.  Writes ``mpc_line_solves.md`` and ``mpc_line_solves.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("mpc_capacity", HERE / "mpc_capacity.py")
capacity_study = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(capacity_study)
OFFSET_M, CAPACITY_NMS = 0.35, 50.0


def run(solves: list[int], days: float) -> list[dict]:
    scenarios = [scenario.load("li2022-momentum-mpc", {
        "duration.days": days, **capacity_study.ERRORS, **capacity_study.OPERATOR, capacity_study.OFFSET: OFFSET_M,
        capacity_study.CAPACITY: CAPACITY_NMS, "controller.line_solves": n}) for n in solves]
    result = simulate_batch(scenarios, seeds=[0] * len(scenarios))
    peaks = np.asarray(result.records.cycles.states["wheels"].max_abs_nms).max(-1)  # [case, cycle]
    return [{"line_solves": n, "status": STATUS_MEANINGS[int(result.status[k])],
             "max_wheel_momentum_nms": float(result.metrics["max_wheel_momentum_nms"][k]),
             "peak_cycle": int(np.argmax(peaks[k])), "dv_per_year_mps": float(result.metrics["dv_per_year_mps"][k])}
            for k, n in enumerate(solves)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solves", type=int, nargs="+", default=[2, 3, 4])
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    begun = time.perf_counter()
    rows = run(args.solves, args.days)
    command = (f"python studies/momentum/mpc_line_solves.py --solves {' '.join(map(str, args.solves))} "
               f"--days {args.days:g}")
    data = {"command": command, "geojax": geojax.__version__, "offset_m": OFFSET_M, "capacity_nms": CAPACITY_NMS,
            "wall_s": time.perf_counter() - begun, "rows": rows}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "mpc_line_solves.json").write_text(json.dumps(data, indent=1))
    lines = ["# The momentum MPC's line solves at 0.35 m with 50 N m s", "",
             f"`{command}` ({data['wall_s']:.0f} s): the operator's satellite, seed 0, a year.", "",
             "| line_solves | status | largest wheel momentum (N m s) | its cycle | ΔV (m/s/yr) |",
             "|---:|---|---:|---:|---:|",
             *(f"| {r['line_solves']} | {r['status']} | {r['max_wheel_momentum_nms']:.2f} | {r['peak_cycle']} | "
               f"{r['dv_per_year_mps']:.3f} |" for r in rows)]
    (args.out / "mpc_line_solves.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
