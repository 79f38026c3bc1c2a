"""The momentum MPC with and without the price on the momentum along its burns' common line (the operator's satellite of studies/momentum/mpc_capacity.py at 0.2-0.4 m offsets).

    python studies/momentum/mpc_line_price.py [--days 365.25] [--out studies/momentum/results]

One draw of Li's nominal errors (seed 0) per case, ``li2022-momentum-mpc``'s keys, on the 3000 kg satellite at
19.2° E of ``mpc_capacity.py`` (``OPERATOR``) over the SRP offset and the wheels' capacity, and on Li's satellite
(the shipped scenario, 0.1 m with 50 N m s wheels); each case flown with the default ``momentum_line_price`` and
with it 0 (the program as it was).  Per case: the status, the largest wheel momentum and per wheel, the cycle of
the first excursion past the capacity, the ΔV.  Writes ``mpc_line_price.md`` and ``mpc_line_price.json``.
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
from geojax.control.mpc_momentum import FIELDS
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("mpc_capacity", HERE / "mpc_capacity.py")
capacity_study = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(capacity_study)
PRICE = "controller.momentum_line_price"
# (satellite, its overrides, offset m, capacity N m s)
CASES = [("3000 kg, 19.2° E", capacity_study.OPERATOR, offset, capacity)
         for offset, capacity in ((0.2, 50.0), (0.2, 75.0), (0.3, 50.0), (0.4, 50.0))] + [
    ("Li's, 96° E (li2022-momentum-mpc)", {}, 0.1, 50.0)]
PRICES = {f"price {FIELDS['momentum_line_price'].default:g} (default)": FIELDS["momentum_line_price"].default,
          "price 0 (before)": 0.0}


def fly(price: float, days: float) -> tuple[list[dict], float]:
    scenarios = [scenario.load("li2022-momentum-mpc", {"duration.days": days, **capacity_study.ERRORS, **overrides,
                                                       capacity_study.OFFSET: offset,
                                                       capacity_study.CAPACITY: capacity, PRICE: price})
                 for _, overrides, offset, capacity in CASES]
    begun = time.perf_counter()
    result = simulate_batch(scenarios, seeds=[0] * len(CASES))
    wall_s = time.perf_counter() - begun
    peaks = np.asarray(result.records.cycles.states["wheels"].max_abs_nms)  # [case, cycle, wheel]
    out = []
    for k, (_, _, _, capacity) in enumerate(CASES):
        over = np.flatnonzero(peaks[k].max(-1) > capacity)
        out.append({"status": STATUS_MEANINGS[int(result.status[k])],
                    "max_wheel_momentum_nms": float(result.metrics["max_wheel_momentum_nms"][k]),
                    "per_wheel_nms": peaks[k].max(0).tolist(),
                    "first_cycle_over_capacity": int(over[0]) if over.size else None,
                    "dv_per_year_mps": float(result.metrics["dv_per_year_mps"][k])})
    return out, wall_s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--days", type=float, default=365.25)
    ap.add_argument("--out", type=Path, default=HERE / "results")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    runs, walls = {}, {}
    for name, price in PRICES.items():
        runs[name], walls[name] = fly(price, args.days)
    lines = ["# The momentum MPC with and without the price on the momentum along the burns' common line", "",
             f"`python studies/momentum/mpc_line_price.py --days {args.days:g}` (geojax {geojax.__version__}); Li's "
             "nominal errors, seed 0; li2022-momentum-mpc's keys; the 3000 kg satellite is `mpc_capacity.py`'s "
             "`OPERATOR`; the offset along the solar array's axis. Cells: status, largest wheel momentum (N m s; "
             "x, y, z wheels), first cycle past the capacity, ΔV (m/s/yr).", "",
             "| satellite | offset (m) | capacity (N m s) | " + " | ".join(PRICES) + " |",
             "|---|---|---|" + "---|" * len(PRICES)]
    for k, (sat, _, offset, capacity) in enumerate(CASES):
        cells = []
        for name in PRICES:
            r = runs[name][k]
            first = r["first_cycle_over_capacity"]
            cells.append(f"{r['status']}, {r['max_wheel_momentum_nms']:.1f} ("
                         + ", ".join(f"{h:.1f}" for h in r["per_wheel_nms"]) + "), "
                         + ("never past" if first is None else f"past at cycle {first}")
                         + f", {r['dv_per_year_mps']:.3f}")
        lines.append(f"| {sat} | {offset:g} | {capacity:g} | " + " | ".join(cells) + " |")
    lines += ["", "Wall time (2 CPU cores, compilation included): "
              + ", ".join(f"{k} {v:.0f} s" for k, v in walls.items()) + ".", ""]
    (args.out / "mpc_line_price.json").write_text(json.dumps({"cases": [c[:1] + c[2:] for c in CASES],
                                                              "runs": runs, "wall_s": walls}, indent=1))
    (args.out / "mpc_line_price.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
