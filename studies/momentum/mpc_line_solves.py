"""The momentum MPC's line iteration at the operator's hardest held case: how many solves hold 0.35 m with 50 N m s.

    python studies/momentum/mpc_line_solves.py [--solves 2 3 4 6 6:0.1] [--days 365.25] [--out studies/momentum/results]

The 3000 kg satellite at 19.2° E of ``mpc_capacity.py`` (``OPERATOR``) with its array's centre of pressure 0.35 m
off and 50 N m s wheels, Li's nominal errors (seed 0), ``li2022-momentum-mpc``'s keys, a year from Li's epoch,
flown with each of ``--solves`` (``controller.line_solves``, the most solves a cycle, first on last cycle's planned
lines, then on the lines the solve before planned; ``N:T`` adds ``controller.line_tolerance_deg = T``).  The
program flies the solve whose lines moved least; before, it flew the last (``mpc_line_solves-last-solve.md``: two
and three solves saturated, four held, after the width-independent arithmetic of a4325ad moved the last bit).
Per case: the status, the largest wheel momentum and the cycle it peaks in, the ΔV, the solves a cycle and how far
the flown solve's lines moved.  Writes ``mpc_line_solves.md`` and ``mpc_line_solves.json``.
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


def case(text: str) -> tuple[int, float]:
    """``N`` or ``N:T``: the most solves a cycle and the line tolerance (deg)."""
    solves, _, tolerance = text.partition(":")
    return int(solves), float(tolerance or 0.0)


def run(cases: list[tuple[int, float]], days: float) -> list[dict]:
    scenarios = [scenario.load("li2022-momentum-mpc", {
        "duration.days": days, **capacity_study.ERRORS, **capacity_study.OPERATOR, capacity_study.OFFSET: OFFSET_M,
        capacity_study.CAPACITY: CAPACITY_NMS, "controller.line_solves": n, "controller.line_tolerance_deg": t})
        for n, t in cases]
    result = simulate_batch(scenarios, seeds=[0] * len(scenarios))
    peaks = np.asarray(result.records.cycles.states["wheels"].max_abs_nms).max(-1)  # [case, cycle]
    solves = np.asarray(result.records.cycles.controller["line_solves"])
    moved_deg = np.degrees(np.asarray(result.records.cycles.controller["line_change_rad"]))
    return [{"line_solves": n, "line_tolerance_deg": t, "status": STATUS_MEANINGS[int(result.status[k])],
             "max_wheel_momentum_nms": float(result.metrics["max_wheel_momentum_nms"][k]),
             "peak_cycle": int(np.argmax(peaks[k])), "dv_per_year_mps": float(result.metrics["dv_per_year_mps"][k]),
             "solves_mean": float(solves[k].mean()),
             "moved_deg_median": float(np.median(moved_deg[k])),
             "moved_deg_p90": float(np.percentile(moved_deg[k], 90)), "moved_deg_max": float(moved_deg[k].max())}
            for k, (n, t) in enumerate(cases)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solves", type=case, nargs="+", default=[case(c) for c in ("2", "3", "4", "6", "6:0.1")],
                        help="N (the most solves a cycle) or N:T (and the line tolerance T, deg)")
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    begun = time.perf_counter()
    rows = run(args.solves, args.days)
    spelled = " ".join(f"{n}:{t:g}" if t else str(n) for n, t in args.solves)
    command = f"python studies/momentum/mpc_line_solves.py --solves {spelled} --days {args.days:g}"
    data = {"command": command, "geojax": geojax.__version__, "offset_m": OFFSET_M, "capacity_nms": CAPACITY_NMS,
            "wall_s": time.perf_counter() - begun, "rows": rows}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "mpc_line_solves.json").write_text(json.dumps(data, indent=1))
    lines = ["# The momentum MPC's line solves at 0.35 m with 50 N m s", "",
             f"`{command}` ({data['wall_s']:.0f} s, 2 CPU cores): the operator's satellite, seed 0, a year; the "
             "program flies the solve whose lines moved least (before, the last: "
             "[mpc_line_solves-last-solve.md](mpc_line_solves-last-solve.md)). Moved: the largest angle between a "
             "flown solve's planned lines and the lines it was solved on (the chord, deg), over the cycles.", "",
             "| line_solves | line_tolerance_deg | status | largest wheel momentum (N m s) | its cycle | ΔV (m/s/yr) "
             "| solves a cycle | moved, median / 90 % / max (deg) |",
             "|---:|---:|---|---:|---:|---:|---:|---|",
             *(f"| {r['line_solves']} | {r['line_tolerance_deg']:g} | {r['status']} | "
               f"{r['max_wheel_momentum_nms']:.2f} | {r['peak_cycle']} | {r['dv_per_year_mps']:.3f} | "
               f"{r['solves_mean']:.2f} | {r['moved_deg_median']:.3f} / {r['moved_deg_p90']:.2f} / "
               f"{r['moved_deg_max']:.1f} |" for r in rows)]
    (args.out / "mpc_line_solves.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
