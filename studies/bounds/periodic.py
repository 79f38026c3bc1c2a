"""The fuel bound with a periodic end (the default of ``geojax bound``) beside the free end.

    python studies/bounds/periodic.py [--scenario li2022] [--days 365.25] [--start-utc UTC] [--name periodic]
                                      [--out studies/bounds/results]

Gazzino 2016's Problem 3 ends where it starts, x(T) = x(0); a free end lets a plan finish the horizon at the
box's edge and keep the difference, which no run of several years can do every year.  For the scenario (li2022:
normal limits, 2020, one year) this runs ``geojax bound`` both ways and writes ``periodic.md`` / ``.json``
(``--name``) with each bound, its re-simulated plan and the north-south floor of a periodic plan by the README's arithmetic:
the uncontrolled year's inclination change (``li2022/uncontrolled_year.py``: 0.8788 deg) must be flown back,
2 V |Delta(h, k)| of out-of-plane Delta-V, divided by sin(beta_max) at the arms' pitch cap.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.bound import bound
from geojax.bound.run import _uncontrolled
from geojax.control.effects import V_SYNC_MPS
from geojax.loop.metrics import SECONDS_PER_YEAR
from geojax.physics.constants import SIDEREAL_DAY_S

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="li2022")
    ap.add_argument("--days", type=float, default=365.25)
    ap.add_argument("--start-utc", help="start then instead of the scenario's epoch, the same orbit relative to "
                    "the Earth (``scenario.started_at``): the bound of a later year")
    ap.add_argument("--name", default="periodic")
    ap.add_argument("--out", type=Path, default=HERE / "results")
    args = ap.parse_args(argv)
    overrides = {"duration.days": args.days}
    sc = (scenario.started_at(args.scenario, args.start_utc, overrides) if args.start_utc
          else geojax.load_scenario(args.scenario, overrides))
    rows = {}
    for name, free_end in (("periodic", False), ("free end", True)):
        begun = time.perf_counter()
        r = bound(sc, free_end=free_end, say=print)
        rows[name] = {"bound_per_year_mps": r.bound_per_year_mps, "plan_per_year_mps": r.plan_per_year_mps,
                      "resim_dv_per_year_mps": r.resim["dv_per_year_mps"], "status": r.resim_status,
                      "max_abs_dlon_deg": r.resim["max_abs_dlon_deg"], "max_abs_dlat_deg": r.resim["max_abs_dlat_deg"],
                      "wall_s": time.perf_counter() - begun}
    uncontrolled = geojax.simulate(_uncontrolled(sc))
    dhk = np.asarray(uncontrolled.final.orbit[3:5]) - np.asarray(uncontrolled.params.initial.orbit[3:5])
    beta_max = float(sc.config["thrusters"]["beta_max_deg"])
    floor_mps = 2 * V_SYNC_MPS * float(np.hypot(*dhk)) / np.sin(np.radians(beta_max))
    di_deg = float(np.degrees(2 * np.arctan(np.hypot(*dhk))))
    floor_per_year_mps = floor_mps * SECONDS_PER_YEAR / (len(uncontrolled.records.cycles.dv_mps) * SIDEREAL_DAY_S)
    side = lambda r: "above" if r["bound_per_year_mps"] >= floor_per_year_mps else "below"  # noqa: E731
    args.out.mkdir(parents=True, exist_ok=True)
    start = f" --start-utc {args.start_utc} --name {args.name}" if args.start_utc else ""
    lines = [f"# The fuel bound of {sc.name}, periodic and free end, {args.days:g} days from {sc.config['epoch']['utc']}",
             "", f"`python studies/bounds/periodic.py --scenario {args.scenario} --days {args.days:g}{start}`. Periodic: "
             "Gazzino 2016's x(T) = x(0), the default of `geojax bound`; free end: `geojax bound --free-end`. "
             "No navigation or attitude errors; the plan re-simulated in the closed loop.", "",
             "| end condition | bound (m/s/yr) | plan flown (m/s/yr) | status | max abs dλ (°) | max abs φ (°) | wall (s) |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for name, r in rows.items():
        lines.append(f"| {name} | {r['bound_per_year_mps']:.2f} | {r['resim_dv_per_year_mps']:.2f} | {r['status']} | "
                     f"{r['max_abs_dlon_deg']:.4f} | {r['max_abs_dlat_deg']:.4f} | {r['wall_s']:.0f} |")
    lines += ["", f"The uncontrolled run's osculating inclination vector moves by {di_deg:.4f}° over the horizon; a "
              f"periodic plan flies it back: at least 2 V |Δ(h, k)| / sin {beta_max:g}° = {floor_mps:.2f} m/s over the "
              f"horizon, {floor_per_year_mps:.2f} m/s/yr (each out-of-plane m/s moves (h, k) by at most 1 / (2 V)); the periodic bound is "
              f"{side(rows['periodic'])} it, the free end's {side(rows['free end'])} it."]
    (args.out / f"{args.name}.md").write_text("\n".join(lines) + "\n")
    (args.out / f"{args.name}.json").write_text(json.dumps({**rows, "ns_floor_mps": floor_mps, "ns_floor_per_year_mps": floor_per_year_mps, "di_deg": di_deg}, indent=1) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
