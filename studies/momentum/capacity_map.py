"""The capacity map: the largest SRP asymmetry each controller holds for a year with given wheels, dumping on and off.

    python studies/momentum/capacity_map.py [--days 365.25] [--out studies/momentum/results]

Runs ``capacity_map.toml`` (li2022-momentum, the QFFC and the FOMPC with the dumping law, a grid of
centre-of-pressure offsets along the array's axis, of wheel capacities and of tilt limits, 8 draws of Li's nominal
errors each;
resumable, ``geojax.sweep``) and, for the map without dumping, the same satellite with ``dump_angle_max_deg = 0``
at the grid's smallest offset: without dumping the stored momentum is the torque's integral, linear in the offset,
so the largest offset a capacity C holds for the run is d C / max|h| (checked at a second offset).

A grid point is held when every draw ends with status 0 (box kept, no wheel above its capacity).  Writes
``capacity_map.md`` and ``capacity_map.json`` into ``--out``; the sweeps' HDF5 files stay there (not in git).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import geojax
from geojax import sweep

HERE = Path(__file__).resolve().parent
SWEEP_FILE = HERE / "capacity_map.toml"
OFFSET = "attitude.srp_offset_array_m[0]"
CAPACITY = "attitude.wheel_capacity_nms"
TILT = "attitude.dump_angle_max_deg"


def run(out: Path, days: float, changes: dict, name: str):
    spec = sweep.load(SWEEP_FILE, changes={**changes, "set": {"duration.days": days, **changes.get("set", {})}})
    return geojax.open_results(sweep.run_sweep(spec, out / f"{name}.h5", resume=True, progress=True))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--days", type=float, default=365.25)
    ap.add_argument("--out", type=Path, default=HERE / "results")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    on = run(args.out, args.days, {}, "capacity_map")
    offsets = [float(x) for x in on[OFFSET].values]
    off = run(args.out, args.days, {"grid": {OFFSET: offsets[:2], CAPACITY: [1.0e5], TILT: [0.0]}},
              "capacity_map_no_dumping")
    result = {"days": args.days, "offsets_m": offsets, "capacities_nms": [float(x) for x in on[CAPACITY].values],
              "tilts_deg": [float(x) for x in on[TILT].values], "controllers": {}}
    for controller in [str(c) for c in on["controller"].values]:
        status = on["status"].sel(controller=controller).values  # [offset, capacity, tilt, repetition]
        peak = on["max_wheel_momentum_nms"].sel(controller=controller).values
        dv = on["dv_per_year_mps"].sel(controller=controller).values
        free_peak = off["max_wheel_momentum_nms"].sel(controller=controller).values[:, 0, 0, :]  # [offset, rep]
        per_metre = np.max(free_peak, axis=1) / np.asarray(offsets[:2])
        result["controllers"][controller] = {
            "held": (status == 0).all(axis=-1).tolist(),
            "max_wheel_momentum_nms": peak.max(axis=-1).tolist(),
            "dv_per_year_mps_mean": dv.mean(axis=-1).tolist(),
            "no_dumping_peak_per_m_nms": per_metre.tolist(),
            "no_dumping_largest_offset_m": {str(cap): float(cap / per_metre[0]) for cap in result["capacities_nms"]},
        }
    (args.out / "capacity_map.json").write_text(json.dumps(result, indent=1))
    (args.out / "capacity_map.md").write_text(table(result))
    print((args.out / "capacity_map.md").read_text())
    return 0


def table(r: dict) -> str:
    caps, tilts = r["capacities_nms"], r["tilts_deg"]
    lines = ["# The capacity map: the largest SRP asymmetry held for a year", "",
             f"`python studies/momentum/capacity_map.py --days {r['days']:g}` (geojax {geojax.__version__}); "
             "li2022-momentum (`capacity_map.toml`): 8 draws of Li's nominal errors per point; a point is held when "
             "every draw keeps the box and its wheels. Cells: the largest wheel momentum over the draws (N m s), "
             "✓ held, ✗ not.", ""]
    for controller, c in r["controllers"].items():
        lines += [f"## {controller.upper()}", "",
                  "| offset (m) | tilt limit (°) | " + " | ".join(f"{cap:g} N m s wheels" for cap in caps)
                  + " | ΔV, mean over capacities (m/s/yr) |", "|---|---|" + "---|" * (len(caps) + 1)]
        for i, d in enumerate(r["offsets_m"]):
            for k, tilt in enumerate(tilts):
                cells = [f"{c['max_wheel_momentum_nms'][i][j][k]:.1f} {'✓' if c['held'][i][j][k] else '✗'}"
                         for j in range(len(caps))]
                dv = np.mean([c["dv_per_year_mps_mean"][i][j][k] for j in range(len(caps))])
                lines.append(f"| {d:g} | {tilt:g} | " + " | ".join(cells) + f" | {dv:.2f} |")
        for k, tilt in enumerate(tilts):
            largest = [max((d for i, d in enumerate(r["offsets_m"]) if c["held"][i][j][k]), default=None)
                       for j in range(len(caps))]
            lines += ["", f"Largest offset of the grid held with a {tilt:g}° tilt: " + ", ".join(
                f"{'none' if d is None else f'{d:g} m'} with {cap:g} N m s" for d, cap in zip(largest, caps)) + "."]
        lines += ["", "Without dumping (the stored momentum is linear in the offset: "
                  + f"{c['no_dumping_peak_per_m_nms'][0]:.0f} and {c['no_dumping_peak_per_m_nms'][1]:.0f} N m s per "
                    "m at the two smallest offsets): " + ", ".join(
                      f"{c['no_dumping_largest_offset_m'][str(cap)]:.4f} m with {cap:g} N m s" for cap in caps) + ".",
                  ""]
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
