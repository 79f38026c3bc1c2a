"""Why the momentum MPC saturated the wheels at the autumn equinox, and what holds them, part by part.

A year of the operator's satellite (3000 kg at 19.2° E, ``mpc_capacity.py``'s ``OPERATOR``).

    python studies/momentum/mpc_equinox.py [--days 365.25] [--offset 0.3] [--capacity 50] [--out studies/momentum/results]

One draw of Li's nominal errors (seed 0), ``li2022-momentum-mpc``'s keys, the offset along the solar array's axis;
the program as it was (one solve on last cycle's lines, a 25 N m s band, a price of 1e-4 on the momentum along the
burns' common line), each part of the fix alone (``line_solves``, the band 35 N m s at 0.7 of the capacity, the
price 1e-3) and together (the defaults), and beside them the dumping law under the MPC's own burns
(``li2022-momentum``, ``controller.kind = "mpc"``).  Per run: status, the largest wheel momentum, the first cycle
past the capacity, the ΔV; per window of the year: how far the burns' lines move from one cycle to the next (what
one solve plans on: last cycle's lines), the angle between a cycle's two lines in inertial space (the only reach of
the tilts on the momentum along their common line), how much it moves a cycle, the share of burns tilted to the
cone's limit, and the peak.  Writes ``mpc_equinox.md`` and ``mpc_equinox.json``.
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
BEFORE = {"controller.momentum_band_nms": 25.0, "controller.momentum_fraction": 0.5,
          "controller.momentum_line_price": 1e-4}
VARIANTS = {
    "one solve, band 25 N m s, price 1e-4 (before)": {**BEFORE, "controller.line_solves": 1},
    "two solves": BEFORE,
    "three solves": {**BEFORE, "controller.line_solves": 3},
    "two solves, band 35 N m s": {"controller.momentum_line_price": 1e-4},
    "two solves, price 1e-3": {k: v for k, v in BEFORE.items() if k != "controller.momentum_line_price"},
    "two solves, band 35, price 1e-3 (the defaults)": {},
}
LAW = "the dumping law under the MPC's burns"
WINDOWS = ((0, 60), (60, 200), (200, 245), (245, 330), (330, 366))  # cycles; 245-330: the autumn equinox
SIDEREAL_RATE = 2 * np.pi / 86164.0905


def to_start(v, past):
    """Vectors [..., 3] in the RSW axes at ``past`` rad after the cycle's start, in the start's RSW axes."""
    c, s = np.cos(past), np.sin(past)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1], v[..., 2]], -1)


def degrees(a, b):
    return np.degrees(np.arccos(np.clip(np.sum(a * b, -1), -1.0, 1.0)))


def diagnose(controller: dict, peaks: np.ndarray, capacity: float) -> dict:
    dirs, fired = np.asarray(controller["directions_rsw"]), np.asarray(controller["fired_s"])  # [cycle, 2, ...]
    u = to_start(dirs, SIDEREAL_RATE * (np.asarray(controller["start_s"]) + fired / 2))
    angle = degrees(u[:, 0], -u[:, 1])  # [cycle] the two lines' angle in inertial space
    moved = np.concatenate([np.zeros((1, 2)), degrees(dirs[1:], dirs[:-1])])  # [cycle, 2]
    d_angle = np.concatenate([[0.0], np.abs(np.diff(angle))])
    tilts = controller.get("tilts_rsw")
    at_limit = None if tilts is None else np.linalg.norm(np.asarray(tilts), axis=-1) > 0.95 * np.sin(np.radians(5.0))
    out = []
    for lo, hi in WINDOWS:
        part = slice(max(lo, 1), min(hi, peaks.size))
        fires = fired[part] > 0
        out.append({"cycles": [lo, hi], "lines_moved_median_deg": float(np.median(moved[part][fires])),
                    "lines_moved_p90_deg": float(np.percentile(moved[part][fires], 90)),
                    "angle_mean_deg": float(angle[part].mean()), "angle_change_median_deg": float(np.median(d_angle[part])),
                    "tilt_at_limit_fraction": None if at_limit is None else float(at_limit[part][fires].mean()),
                    "peak_nms": float(peaks[part].max())})
    over = np.flatnonzero(peaks > capacity)
    return {"first_cycle_over_capacity": int(over[0]) if over.size else None, "windows": out}


def fly(base: str, variants: dict, args) -> tuple[dict, float]:
    common = {"duration.days": args.days, **capacity_study.ERRORS, **capacity_study.OPERATOR,
              capacity_study.OFFSET: args.offset, capacity_study.CAPACITY: args.capacity}
    scenarios = [scenario.load(base, {**common, **overrides}) for overrides in variants.values()]
    begun = time.perf_counter()
    result = simulate_batch(scenarios, seeds=[0] * len(scenarios))
    wall_s = time.perf_counter() - begun
    peaks = np.asarray(result.records.cycles.states["wheels"].max_abs_nms).max(-1)  # [run, cycle]
    out = {}
    for k, name in enumerate(variants):
        controller = {key: np.asarray(v)[k] for key, v in result.records.cycles.controller.items()
                      if key in ("directions_rsw", "fired_s", "start_s", "tilts_rsw")}
        out[name] = {"status": STATUS_MEANINGS[int(result.status[k])],
                     "max_wheel_momentum_nms": float(result.metrics["max_wheel_momentum_nms"][k]),
                     "dv_per_year_mps": float(result.metrics["dv_per_year_mps"][k]),
                     **diagnose(controller, peaks[k], args.capacity)}
    return out, wall_s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--days", type=float, default=365.25)
    ap.add_argument("--offset", type=float, default=0.3)
    ap.add_argument("--capacity", type=float, default=50.0)
    ap.add_argument("--out", type=Path, default=HERE / "results")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    runs, wall = fly("li2022-momentum-mpc", VARIANTS, args)
    law, law_wall = fly("li2022-momentum", {LAW: {"controller.kind": "mpc"}}, args)
    runs.update(law)
    lines = ["# Why the momentum MPC saturated at the autumn equinox, and what holds it", "",
             f"`python studies/momentum/mpc_equinox.py --days {args.days:g} --offset {args.offset:g} --capacity "
             f"{args.capacity:g}` (geojax {geojax.__version__}); the 3000 kg satellite at 19.2° E (`mpc_capacity.py`'s "
             "`OPERATOR`), Li's nominal errors, seed 0, the offset along the solar array's axis.", "",
             "| the program | status | peak (N m s) | first cycle past the capacity | ΔV (m/s/yr) |", "|---|---|---|---|---|"]
    for name, r in runs.items():
        first = r["first_cycle_over_capacity"]
        lines.append(f"| {name} | {r['status']} | {r['max_wheel_momentum_nms']:.1f} | "
                     f"{'never' if first is None else first} | {r['dv_per_year_mps']:.2f} |")
    lines += ["", "Per window of cycles: the lines' move from one cycle to the next (median, 90th percentile; what "
              "one solve plans on), the angle between a cycle's two lines in inertial space (mean) and its move a "
              "cycle (median), the share of burns tilted to the cone's limit (the planned tilt's sine above 0.95 "
              "sin 5°), the peak (N m s). Cycles 245 to 330: the autumn equinox.", ""]
    for name, r in runs.items():
        lines += [f"## {name}", "", "| cycles | lines' move (°) | angle (°) | angle's move (°) | tilts at the limit | peak |",
                  "|---|---|---|---|---|---|"]
        for w in r["windows"]:
            share = "" if w["tilt_at_limit_fraction"] is None else f"{w['tilt_at_limit_fraction']:.2f}"
            lines.append(f"| {w['cycles'][0]}-{w['cycles'][1]} | {w['lines_moved_median_deg']:.2f}, "
                         f"{w['lines_moved_p90_deg']:.2f} | {w['angle_mean_deg']:.2f} | "
                         f"{w['angle_change_median_deg']:.2f} | {share} | {w['peak_nms']:.1f} |")
        lines.append("")
    lines += [f"Wall time (2 CPU cores, shared, compilation included): the momentum MPC's {len(VARIANTS)} runs "
              f"{wall:.0f} s, the law {law_wall:.0f} s.", ""]
    (args.out / "mpc_equinox.json").write_text(json.dumps({"runs": runs, "variants": VARIANTS}, indent=1))
    (args.out / "mpc_equinox.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
