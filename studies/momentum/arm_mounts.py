"""Li's satellite with its arms' geometry: the nozzle distance each burn's line gets from the arm's base and reach,
against the common nozzle distance, and what it changes for the wheels.

    python studies/momentum/arm_mounts.py [--samples 8] [--days 365.25] [--out studies/momentum/results]

``li2022-momentum`` (QFFC, three 50 N m s wheels, SRP 0.1 m off the centre of mass along the array axis, tilts up to
5 deg) flown ``--days`` with Li's nominal errors and ``--samples`` draws, two ways on the same draws:

1. the common nozzle distance (the scenario: ``attitude.thrust_arm_m`` = 2.5 m for every burn);
2. the arms' geometry (``attitude.thrust_reach_m``, ``thrust_base_north_m``, ``thrust_base_south_m``; a choice,
   Li 2022 gives no arm dimensions): each arm's base 1 m north or south of the centre of the anti-nadir face of
   the 3.5 m bus (1.75 m from the centre of mass), a reach of 2 m; the arm on the north side flies the burns that
   push south (Li's thruster 1).  ``states.momentum.nozzle_distance_m`` puts each burn's nozzle where that arm
   meets the line through the centre of mass.

Reported: the nozzle distance over the burns flown (from the cycles' recorded directions, the same function), the
largest wheel momentum, the Delta-V, the Delta-V the tilts put across the plan, the draws that keep box and wheels.
Writes ``arm_mounts.md`` and ``.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch
from geojax.states import momentum

HERE = Path(__file__).resolve().parent
ERRORS = {"errors.h_rv": 1.0, "errors.h_att": 1.0}  # Li 2022's nominal 3-sigma levels
ARMS = {"attitude.thrust_reach_m": 2.0, "attitude.thrust_base_north_m": [0.0, -1.0, -1.75],
        "attitude.thrust_base_south_m": [0.0, 1.0, -1.75]}  # body axes: x along-track, y anti-normal, z nadir


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=8)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    n = args.samples
    cases = {"common 2.5 m": {}, "arms (2 m reach)": ARMS}
    scenarios = [scenario.load("li2022-momentum", {"duration.days": args.days, **ERRORS, **ov}) for ov in cases.values()]
    result = simulate_batch([sc for sc in scenarios for _ in range(n)], seeds=np.tile(np.arange(n), len(cases)))
    m = {k: np.asarray(v, float).reshape(len(cases), n) for k, v in result.metrics.items()
         if np.ndim(v) == 1 and np.size(v) == len(cases) * n}
    status = np.asarray(result.status).reshape(len(cases), n)
    directions = np.asarray(result.records.cycles.controller["directions_rsw"]).reshape(len(cases), n, -1, 2, 3)
    fired = np.asarray(result.records.cycles.controller["fired_s"]).reshape(len(cases), n, -1, 2) > 0
    attitude = {"thrust_arm_m": jnp.asarray(2.5), "thrust_reach_m": jnp.asarray(ARMS["attitude.thrust_reach_m"]),
                "thrust_base_north_m": jnp.asarray(ARMS["attitude.thrust_base_north_m"]),
                "thrust_base_south_m": jnp.asarray(ARMS["attitude.thrust_base_south_m"])}
    d = directions[1][fired[1]]  # [burns, 3] RSW, the arms' case
    u_body = np.stack([d[:, 1], -d[:, 2], -d[:, 0]], -1)
    u_body /= np.linalg.norm(u_body, axis=-1, keepdims=True)
    arm = np.asarray(jax.vmap(lambda u, w: momentum.nozzle_distance_m(attitude, u, w))(jnp.asarray(u_body),
                                                                                          jnp.asarray(d[:, 2])))
    rows = []
    for i, name in enumerate(cases):
        rows.append({"case": name, "dv_per_year_mps_mean": float(m["dv_per_year_mps"][i].mean()),
                     "max_wheel_momentum_nms": float(m["max_wheel_momentum_nms"][i].max()),
                     "max_wheel_momentum_last_year_nms": float(m["max_wheel_momentum_last_year_nms"][i].max()),
                     "dump_cross_dv_mps_mean": float(m["dump_cross_dv_mps"][i].mean()),
                     "ok": int(np.sum(status[i] == 0)), "status": [STATUS_MEANINGS[int(s)] for s in status[i]]})
    arms = {"burns": int(arm.size), "min_m": float(arm.min()), "median_m": float(np.median(arm)),
            "max_m": float(arm.max()), "pushing_south_median_m": float(np.median(arm[d[:, 2] < 0])),
            "pushing_north_median_m": float(np.median(arm[d[:, 2] >= 0]))}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "arm_mounts.json").write_text(json.dumps({"samples": n, "days": args.days, "geojax": geojax.__version__,
                                                          "rows": rows, "nozzle_distance": arms}, indent=1))
    lines = [f"# Li's arms' geometry against the common nozzle distance: li2022-momentum, {n} draws, {args.days:g} days",
             "", f"`python studies/momentum/arm_mounts.py --samples {n} --days {args.days:g}`; geojax "
             f"{geojax.__version__}. Arms: bases 1 m north and south of the anti-nadir face's centre (1.75 m from the "
             "centre of mass), reach 2 m (a choice; Li 2022 gives no dimensions).", "",
             f"Nozzle distance over the {arms['burns']} burns flown with the arms: {arms['min_m']:.3f}-"
             f"{arms['max_m']:.3f} m, median {arms['median_m']:.3f} (burns pushing south "
             f"{arms['pushing_south_median_m']:.3f}, north {arms['pushing_north_median_m']:.3f}); the common distance "
             "is 2.5 m.", "",
             "| nozzle distance | ΔV (m/s/yr) | largest wheel momentum (N m s) | last year's (N m s) | tilts' cross ΔV "
             "(m/s) | box and wheels kept |", "|---|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['dv_per_year_mps_mean']:.3f} | {r['max_wheel_momentum_nms']:.2f} | "
                     f"{r['max_wheel_momentum_last_year_nms']:.2f} | {r['dump_cross_dv_mps_mean']:.3f} | "
                     f"{r['ok']}/{n} |")
    (args.out / "arm_mounts.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
