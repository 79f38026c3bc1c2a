"""The momentum MPC beside the dumping law over the SRP offset and the wheels' capacity, on two satellites.

    python studies/momentum/mpc_capacity.py [--samples 1] [--days 365.25] [--out studies/momentum/results]

Each case flies a year with Li's nominal errors (``errors.h_rv = 1``, ``errors.h_att = 1``; ``--samples`` draws,
the same draws in every case) twice: ``mpc_momentum`` (``li2022-momentum-mpc``'s keys) and the QFFC with the dumping
law (``li2022-momentum``'s), on

* Li's satellite (5000 kg, 200 m² of SRP area, η 0.6, 0.5 N thrusters at 2.5 m, 96° E): the shipped scenarios;
* a 3000 kg all-electric satellite at 19.2° E (``OPERATOR``): 30 m² and η 0.3 (the ``geo`` starting point's
  spacecraft), 0.3 N thrusters of 1800 s on Li's arms, the nozzles 2.0 m from the centre of mass, a stated inertia
  estimate; its SRP torque per metre of offset is 0.12 of Li's.

The offset is the centre of pressure's along the solar array's axis (``attitude.srp_offset_array_m[0]``), the tilt
limit 5°.  A case is held when every draw keeps its box (status ok) and its wheels within their capacity all year.
The criterion: a larger wheel never does worse, and the MPC holds at least what the law holds.  Beside
them: the momentum MPC as it was, its band half of each capacity (``momentum_band_nms`` out of the way), and on the
second satellite the MPC without momentum (``controller.kind = "mpc"``) flying the dumping law, the law under the
MPC's burns.  Writes ``mpc_capacity.md`` and ``mpc_capacity.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import math
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
OFFSET = "attitude.srp_offset_array_m[0]"
CAPACITY = "attitude.wheel_capacity_nms"
# The second satellite, as overrides of Li's scenarios: a 3000 kg all-electric satellite at 19.2 deg E.  Its
# spacecraft is the ``geo`` starting point's (3000 kg, 30 m^2, eta 0.3); SPT-140-class thrusters (0.3 N, 1800 s)
# on Li's arms; the nozzles 2.0 m out (a 3.0 m bus's anti-nadir face 1.5 m out plus 0.5 m of arm); the start at
# Li's osculating elements moved to 19.2 deg E (L shifted by the longitudes' difference).  The inertia, principal,
# from a 2700 kg bus 2.2 x 2.2 x 3.0 m and two 150 kg wings of 7.5 x 2 m centred 5.35 m out along y:
# Ixx = 3114 + 8587 + 1406 + 50, Iyy = 3114 + 100, Izz = 2178 + 8587 + 1406 + 50 kg m^2.
OPERATOR = {
    "station.lon_deg": 19.2, "orbit.L_rad": 0.289893 + math.radians(19.2 - 96.0),
    "spacecraft.mass_kg": 3000.0, "spacecraft.srp_area_m2": 30.0, "spacecraft.reflectivity": 0.3,
    "thrusters.thrust_n": 0.3, "thrusters.isp_s": 1800.0, "attitude.thrust_arm_m": 2.0,
    "attitude.inertia_kg_m2": [13157.0, 3214.0, 12221.0, 0.0, 0.0, 0.0],
}
SATELLITES = {
    "Li's satellite (5000 kg, 96° E)": ({}, (0.1, 0.2)),
    "the 3000 kg satellite at 19.2° E": (OPERATOR, (0.2, 0.3, 0.4)),  # OPERATOR_SAT
}
CAPACITIES_NMS = (50.0, 75.0, 100.0)
OPERATOR_SAT = "the 3000 kg satellite at 19.2° E"
# (scenario, overrides, the cases it flies): the momentum MPC plans its tilts (and as it was before the band: half
# of each capacity, ``momentum_band_nms`` out of the way; the same as now for 50 N m s wheels); the QFFC and the MPC
# without momentum fly the law's
PLANNERS = {
    "mpc_momentum": ("li2022-momentum-mpc", {}, lambda case: True),
    "mpc_momentum, band half the capacity (before)": ("li2022-momentum-mpc", {"controller.momentum_band_nms": 1e5},
                                                      lambda case: case["capacity_nms"] > 50.0),
    "QFFC, dumping law": ("li2022-momentum", {}, lambda case: True),
    "MPC, dumping law": ("li2022-momentum", {"controller.kind": "mpc"},
                         lambda case: case["satellite"] == OPERATOR_SAT),
}
METRICS = ("dv_per_year_mps", "max_wheel_momentum_nms", "max_abs_mean_dlon_deg", "external_momentum_per_day_nms",
           "max_wheel_growth_per_day_nms", "time_above_80pct_capacity_fraction")


def cases(capacities=CAPACITIES_NMS, offsets=None) -> list[dict]:
    """Every (satellite, offset, capacity); ``offsets`` {satellite: offsets} in place of ``SATELLITES``' own."""
    offsets = offsets or {}
    return [{"satellite": sat, "offset_m": offset, "capacity_nms": capacity,
             "overrides": {**overrides, OFFSET: offset, CAPACITY: capacity}}
            for sat, (overrides, own) in SATELLITES.items() for offset in offsets.get(sat, own)
            for capacity in capacities]


def fly(base: str, planner: dict, all_cases: list[dict], days: float, samples: int) -> tuple[list[dict], float]:
    """Every case's ``samples`` draws in one compiled batch: per case {metric: [draws]}, statuses; the wall time."""
    scenarios = [scenario.load(base, {"duration.days": days, **ERRORS, **planner, **case["overrides"]})
                 for case in all_cases for _ in range(samples)]
    begun = time.perf_counter()
    result = simulate_batch(scenarios, seeds=np.tile(np.arange(samples), len(all_cases)))
    wall_s = time.perf_counter() - begun
    out = []
    for k in range(len(all_cases)):
        part = slice(k * samples, (k + 1) * samples)
        metrics = {m: np.asarray(result.metrics[m], float)[part].tolist() for m in METRICS}
        out.append({"metrics": metrics, "status": [STATUS_MEANINGS[int(s)] for s in result.status[part]]})
    return out, wall_s


def summary(run: dict, capacity: float) -> dict:
    m = {k: np.asarray(v) for k, v in run["metrics"].items()}
    ok = [s == "ok" for s in run["status"]]
    return {"held": bool(all(ok) and np.all(m["max_wheel_momentum_nms"] <= capacity)), "draws_ok": int(sum(ok)),
            "draws": len(ok), "max_wheel_momentum_nms": float(m["max_wheel_momentum_nms"].max()),
            "dv_mean_mps": float(m["dv_per_year_mps"].mean()),
            "external_momentum_per_day_nms": float(m["external_momentum_per_day_nms"].mean()),
            "max_wheel_growth_per_day_nms": float(m["max_wheel_growth_per_day_nms"].max()),
            "statuses": sorted(set(run["status"]))}


def held_offsets(rows: list[dict], planner: str, satellite: str, capacity: float) -> list[float] | None:
    """The offsets ``planner`` held with ``capacity``; None where it did not fly them."""
    flown = [r for r in rows if r["satellite"] == satellite and r["capacity_nms"] == capacity and planner in r]
    return [r["offset_m"] for r in flown if r[planner]["held"]] if flown else None


def checks(rows: list[dict]) -> list[str]:
    """The criterion, case by case: the larger wheel never worse (held where a smaller one is), the MPC holding
    what the law holds."""
    out = []
    for sat in SATELLITES:
        for planner in ("mpc_momentum", "QFFC, dumping law"):
            worse = [f"{r['offset_m']:g} m: {r['capacity_nms']:g} N m s" for r in rows if r["satellite"] == sat
                     and not r[planner]["held"] and any(
                         q["satellite"] == sat and q["offset_m"] == r["offset_m"] and q[planner]["held"]
                         and q["capacity_nms"] < r["capacity_nms"] for q in rows)]
            out.append(f"{sat}, {planner}: a larger wheel never does worse: "
                       f"{'met' if not worse else 'NOT met (' + ', '.join(worse) + ')'}.")
        short = [f"{r['offset_m']:g} m with {r['capacity_nms']:g} N m s" for r in rows
                 if r["satellite"] == sat and r["QFFC, dumping law"]["held"] and not r["mpc_momentum"]["held"]]
        out.append(f"{sat}: the MPC holds every case the law holds: "
                   f"{'met' if not short else 'NOT met (' + ', '.join(short) + ')'}.")
    return out


def table(rows: list[dict], args, walls: dict) -> str:
    lines = [
        "# The momentum MPC beside the dumping law, over the SRP offset and the wheels' capacity",
        "",
        f"`{args.command}` (geojax {geojax.__version__}); {args.samples} draw(s) of Li's nominal errors per case, the same draws in "
        "every case; tilt limit 5°, the offset along the solar array's axis. Cells: held ✓ / ✗, the largest wheel "
        "momentum over the draws (N m s), the ΔV (m/s/yr, mean). Held: every draw in its box (status ok) and its "
        "wheels within their capacity all year.",
        "",
        "The 3000 kg satellite at 19.2° E: 30 m² of SRP area, η 0.3, 0.3 N thrusters of 1800 s on Li's arms, "
        "nozzles 2.0 m from the centre of mass, inertia (13157, 3214, 12221) kg m² principal "
        "(`OPERATOR` in the script).",
        "",
    ] + ([f"Carried from the earlier run of this file (not flown again, to fit the time; the program as it was then): "
          f"{', '.join(args.carried)}.", ""] if args.carried else [])
    for sat in SATELLITES:
        lines += [f"## {sat}", "",
                  "| offset (m) | external momentum (N m s/day) | capacity (N m s) | " + " | ".join(PLANNERS) + " |",
                  "|---|---|---|" + "---|" * len(PLANNERS)]
        for r in rows:
            if r["satellite"] != sat:
                continue
            cells = [f"{'✓' if r[p]['held'] else '✗'} {r[p]['max_wheel_momentum_nms']:.1f}, "
                     f"{r[p]['dv_mean_mps']:.2f}" if p in r else "" for p in PLANNERS]
            lines.append(f"| {r['offset_m']:g} | {r['mpc_momentum']['external_momentum_per_day_nms']:.2f} | "
                         f"{r['capacity_nms']:g} | " + " | ".join(cells) + " |")
        for capacity in args.capacities:
            lines.append("")
            held = {p: held_offsets(rows, p, sat, capacity) for p in PLANNERS}
            lines.append(f"Held with {capacity:g} N m s: " + "; ".join(
                f"{p} {', '.join(f'{o:g}' for o in offsets) or 'none'}" for p, offsets in held.items()
                if offsets is not None) + " (m).")
        lines.append("")
    lines += ["## The criterion", ""] + [f"- {c}" for c in checks(rows)] + [
        "",
        "External momentum: `external_momentum_per_day_nms`, the SRP and gravity-gradient torques' net impulse over "
        "each cycle, averaged (what the wheels store a day without dumping).",
        "",
        "Wall time (2 CPU cores, compilation included): " + ", ".join(f"{k} {v:.0f} s" for k, v in walls.items()) + ".",
        ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1)
    ap.add_argument("--days", type=float, default=365.25)
    ap.add_argument("--out", type=Path, default=HERE / "results")
    ap.add_argument("--fly", nargs="+", choices=PLANNERS, default=list(PLANNERS),
                    help="the planners to fly; the others' cells are read from the --out JSON of an earlier run")
    ap.add_argument("--capacities", type=float, nargs="+", default=list(CAPACITIES_NMS))
    ap.add_argument("--li-offsets", type=float, nargs="+", help="Li's satellite's offsets (m)")
    ap.add_argument("--operator-offsets", type=float, nargs="+", help="the 3000 kg satellite's offsets (m)")
    args = ap.parse_args(argv)
    args.command = " ".join(["python studies/momentum/mpc_capacity.py"]
                            + [shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv)])
    args.out.mkdir(parents=True, exist_ok=True)
    sats = list(SATELLITES)
    all_cases = cases(args.capacities, {sat: o for sat, o in zip(sats, (args.li_offsets, args.operator_offsets)) if o})
    rows = [{k: v for k, v in case.items() if k != "overrides"} for case in all_cases]
    runs, walls = {}, {}
    earlier = json.loads((args.out / "mpc_capacity.json").read_text()) if set(args.fly) != set(PLANNERS) else None
    args.carried = [p for p in PLANNERS if p not in args.fly]
    for planner, (base, overrides, flies) in PLANNERS.items():
        chosen = [k for k, case in enumerate(all_cases) if flies(case)]
        if planner not in args.fly:  # the earlier run's cells, case by case
            key = {(r["satellite"], r["offset_m"], r["capacity_nms"]): i for i, r in enumerate(earlier["rows"])}
            at = {k: key.get((rows[k]["satellite"], rows[k]["offset_m"], rows[k]["capacity_nms"])) for k in chosen}
            found = [k for k in chosen if at[k] is not None and planner in earlier["rows"][at[k]]]
            order = [i for i, r in enumerate(earlier["rows"]) if planner in r]
            runs[planner] = [earlier["runs"][planner][order.index(at[k])] for k in found]
            walls[planner] = earlier["wall_s"][planner]
            for k in found:
                rows[k][planner] = earlier["rows"][at[k]][planner]
            continue
        runs[planner], walls[planner] = fly(base, overrides, [all_cases[k] for k in chosen], args.days, args.samples)
        for k, run in zip(chosen, runs[planner], strict=True):
            rows[k][planner] = summary(run, rows[k]["capacity_nms"])
    (args.out / "mpc_capacity.json").write_text(json.dumps({"rows": rows, "runs": runs, "wall_s": walls,
                                                            "operator": OPERATOR}, indent=1))
    (args.out / "mpc_capacity.md").write_text(table(rows, args, walls))
    print((args.out / "mpc_capacity.md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
