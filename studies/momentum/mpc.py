"""The MPC over orbit and wheel momentum (Caverly, Di Cairano & Weiss 2021's combined problem) on Li's satellite.

    python studies/momentum/mpc.py [--samples 8] [--days 365.25] [--out studies/momentum/results]

``li2022-momentum-mpc`` (``geojax.control.mpc_momentum``: the MPC's minimum-fuel program with the wheels' momentum
as states, |h| within half the capacity at each boundary and between the burns, each burn's tilt about its nozzle
as decisions) flown a year with Li's nominal errors (``errors.h_rv = 1``, ``errors.h_att = 1``), ``--samples``
draws, against the MPC without momentum (``li2022-mpc``) on the torque-free satellite, on the same draws:

1. the issue's check: li2022-momentum-mpc (0.1 m SRP offset along the array's axis, 50 N m s wheels, 5 deg
   tilt) keeps the box and the wheels at a Delta-V within 3 % of li2022-mpc's, draw by draw;
2. the momentum MPC on the torque-free satellite (offset 0): what carrying the momentum costs when there is none;
3. a map over the offset (0.1, 0.2, 0.4 m) and the wheels' capacity (25, 50, 100 N m s), the tilt limit 5 deg:
   where the planner-agnostic dumping law under the QFFC and FOMPC stops (``capacity_map.md``: 0.1 m with 50 N m s,
   nothing at 0.2 m), does a planner that chooses its burns with the momentum hold?

Writes ``mpc.md`` and ``mpc.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
ERRORS = {"errors.h_rv": 1.0, "errors.h_att": 1.0}  # Li 2022's nominal 3-sigma levels (eqs. (45)-(48))
OFFSETS_M = (0.1, 0.2, 0.4)
CAPACITIES_NMS = (25.0, 50.0, 100.0)
METRICS = ("dv_per_year_mps", "max_wheel_momentum_nms", "max_abs_mean_dlon_deg", "max_abs_dlat_deg",
           "thrust_torque_impulse_nms", "dump_cross_dv_mps", "cycles_without_solution")


def cases(offsets=OFFSETS_M, capacities=CAPACITIES_NMS) -> list[tuple[str, dict]]:
    """(label, overrides of li2022-momentum-mpc) of every momentum-MPC run: the torque-free satellite, then the map."""
    out = [("offset 0 m, 50 N m s", {"attitude.srp_offset_array_m[0]": 0.0})]
    for offset in offsets:
        for capacity in capacities:
            out.append((f"offset {offset:g} m, {capacity:g} N m s", {"attitude.srp_offset_array_m[0]": offset,
                                                                      "attitude.wheel_capacity_nms": capacity}))
    return out


def batch(name: str, overrides: list[dict], days: float, samples: int) -> tuple[list[dict], float]:
    """Every overrides' ``samples`` draws (seeds 0..samples-1) in one compiled batch: per case {metric: [draws]},
    statuses; and the wall time."""
    scenarios = [scenario.load(name, {"duration.days": days, **ERRORS, **o}) for o in overrides for _ in range(samples)]
    seeds = np.tile(np.arange(samples), len(overrides))
    begun = time.perf_counter()
    result = simulate_batch(scenarios, seeds=seeds)
    wall_s = time.perf_counter() - begun
    out = []
    for k in range(len(overrides)):
        part = slice(k * samples, (k + 1) * samples)
        metrics = {m: np.asarray(result.metrics[m], float)[part].tolist() for m in METRICS if m in result.metrics}
        out.append({"metrics": metrics, "status": [STATUS_MEANINGS[int(s)] for s in result.status[part]]})
    return out, wall_s


def summarize(plain: dict, managed: list[dict], labels: list[str], capacities: list[float]) -> list[dict]:
    rows = []
    dv_plain = np.asarray(plain["metrics"]["dv_per_year_mps"])
    for label, run, capacity in zip(labels, managed, capacities, strict=True):
        m = {k: np.asarray(v) for k, v in run["metrics"].items()}
        ratio = m["dv_per_year_mps"] / dv_plain
        ok = [s == "ok" for s in run["status"]]
        rows.append({
            "case": label, "capacity_nms": capacity, "held": bool(all(ok) and np.all(m["max_wheel_momentum_nms"] <= capacity)),
            "draws_ok": int(sum(ok)), "draws": len(ok),
            "max_wheel_momentum_nms": float(m["max_wheel_momentum_nms"].max()),
            "dv_mean_mps": float(m["dv_per_year_mps"].mean()),
            "dv_ratio_mean": float(ratio.mean()), "dv_ratio_max": float(ratio.max()), "dv_ratio_min": float(ratio.min()),
            "max_abs_mean_dlon_deg": float(m["max_abs_mean_dlon_deg"].max()),
            "thrust_torque_impulse_nms": float(m["thrust_torque_impulse_nms"].mean()),
            "dump_cross_dv_mps": float(m["dump_cross_dv_mps"].mean()),
            "statuses": sorted(set(run["status"])),
        })
    return rows


def table(plain: dict, rows: list[dict], args, walls: dict) -> str:
    dv = np.asarray(plain["metrics"]["dv_per_year_mps"])
    lines = [
        "# The MPC over orbit and wheel momentum on Li's satellite",
        "",
        f"`{args.command}` (geojax {geojax.__version__}); "
        f"{args.samples} draws of Li's nominal errors (h_rv = h_att = 1) per case, the same draws in every case. "
        "ΔV ratio: the momentum MPC's ΔV over the MPC's without momentum (`li2022-mpc`, the torque-free satellite), "
        "draw by draw. Held: every draw in the box (status ok) and its wheels within their capacity all year.",
        "",
    ] + ([f"A reduced grid (the full one: {8} draws, offsets {', '.join(f'{o:g}' for o in OFFSETS_M)} m, capacities "
          f"{', '.join(f'{c:g}' for c in CAPACITIES_NMS)} N m s), to fit the time it was run in.", ""]
         if (args.samples, tuple(args.offsets), tuple(args.capacities)) != (8, OFFSETS_M, CAPACITIES_NMS) else []) + [
        "",
        f"The MPC without momentum (li2022-mpc): ΔV {dv.mean():.3f} m/s/yr (draws {dv.min():.3f} to {dv.max():.3f}), "
        f"statuses {sorted(set(plain['status']))}.",
        "",
        "| case (tilt 5°) | held | largest wheel momentum (N m s) | ΔV (m/s/yr) | ΔV ratio mean (min, max) "
        "| max mean Δλ (°) | thrust torque impulse (N m s) | tilts' ΔV across the plan (m/s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['case']} | {'✓' if r['held'] else '✗'} ({r['draws_ok']}/{r['draws']} ok) | "
                     f"{r['max_wheel_momentum_nms']:.1f} | {r['dv_mean_mps']:.3f} | {r['dv_ratio_mean']:.4f} "
                     f"({r['dv_ratio_min']:.4f}, {r['dv_ratio_max']:.4f}) | {r['max_abs_mean_dlon_deg']:.4f} | "
                     f"{r['thrust_torque_impulse_nms']:.0f} | {r['dump_cross_dv_mps']:.3f} |")
    nominal = next(r for r in rows if r["case"] == "offset 0.1 m, 50 N m s")
    free = rows[0]
    worst = max(abs(nominal["dv_ratio_max"] - 1), abs(nominal["dv_ratio_min"] - 1))
    held = [r["case"] for r in rows if r["held"]]
    lines += [
        "",
        f"The shipped scenario's check (li2022-momentum-mpc, offset 0.1 m, 50 N m s): {'held' if nominal['held'] else 'NOT held'}, "
        f"largest wheel momentum {nominal['max_wheel_momentum_nms']:.1f} N m s, ΔV within "
        f"{100 * worst:.2f} % of the MPC without momentum on every draw (criterion 3 %: "
        f"{'met' if nominal['held'] and worst < 0.03 else 'NOT met'}).",
        "",
        f"On the torque-free satellite the momentum MPC flies ΔV ratio {free['dv_ratio_mean']:.4f} "
        f"(largest wheel momentum {free['max_wheel_momentum_nms']:.1f} N m s: what its own tilts store).",
        "",
        f"Held: {', '.join(held) if held else 'none'}.",
        "",
        "Wall time (2 CPU cores, compilation included): " + ", ".join(f"{k} {v:.0f} s" for k, v in walls.items()) + ".",
        "",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=8)
    ap.add_argument("--days", type=float, default=365.25)
    ap.add_argument("--out", type=Path, default=HERE / "results")
    ap.add_argument("--offsets", type=float, nargs="+", default=list(OFFSETS_M), help="the map's offsets (m)")
    ap.add_argument("--capacities", type=float, nargs="+", default=list(CAPACITIES_NMS), help="and capacities")
    args = ap.parse_args(argv)
    args.command = " ".join(["python studies/momentum/mpc.py"]
                            + [shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv)])
    args.out.mkdir(parents=True, exist_ok=True)
    (plain,), wall_plain = batch("li2022-mpc", [{}], args.days, args.samples)
    labels, overrides = zip(*cases(args.offsets, args.capacities), strict=True)
    managed, wall_managed = batch("li2022-momentum-mpc", list(overrides), args.days, args.samples)
    capacities = [o.get("attitude.wheel_capacity_nms", 50.0) for o in overrides]
    rows = summarize(plain, managed, list(labels), capacities)
    walls = {"li2022-mpc": wall_plain, "li2022-momentum-mpc (all cases, one batch)": wall_managed}
    (args.out / "mpc.json").write_text(json.dumps({"rows": rows, "plain": plain, "runs": dict(zip(labels, managed)),
                                                   "wall_s": walls}, indent=1))
    (args.out / "mpc.md").write_text(table(plain, rows, args, walls))
    print((args.out / "mpc.md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
