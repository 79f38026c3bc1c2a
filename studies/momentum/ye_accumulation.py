"""Ye 2022's "up to 100 N m s a day" and its t_dump = 3207 s, from the physics of the SRP torque and the tilt.

    python studies/momentum/ye_accumulation.py [--days 2] [--dump-days 30] [--out studies/momentum/results]

Ye 2022 (Sec. 1) cites asymmetric GEO satellites (a single solar wing) storing up to 100 N m s a day, and sets
the least daily firing time the manipulator needs to unload it, t_dump = 3207 s (Sec. 4), without the
asymmetry or the dumping geometry behind either number.  Two questions, on Ye's satellite (ye2022-ex1: 2800 kg,
reflectivity 0.3, one 80 mN thruster on the manipulator):

1. **Which asymmetry stores 100 N m s a day.**  The wheels' momentum (``geojax.states.momentum``, no dumping)
   over ``--days`` for a grid of SRP areas (the wing) and centre-of-pressure offsets along the array's axis (the
   single wing's lever), each a scenario of its own in one batch; beside each, the closed form d P (1 + eta) A
   (1 AU / r)^2 cos(delta) per second (the force's part across the orbit normal, the Sun at declination delta
   from the orbit plane, no eclipse in January).  The accumulation is linear in d A, so the offset that stores
   100 N m s a day at each area follows.
2. **The t_dump the physics asks.**  A tilt of the thrust line by delta about a nozzle L from the centre of mass
   makes at most L F sin(delta) of torque, so a day's momentum H needs t_dump = H / (L F sin(delta)) of firing.
   Ye's 3207 s at 100 N m s and F = 80 mN is a line of action H / (F t_dump) = 0.39 m off the centre of mass;
   with the default 2.5 m nozzle distance, a tilt of 9.0 deg.  Flown: ye2022-ex1 with
   the wheels (200 N m s each, twice a day's momentum), the asymmetry of 1. at Ye's 40 m^2, and dumping within
   several tilt limits for ``--dump-days``: the firing the zone NSSK gives each day against the t_dump each limit
   asks, and whether the wheels hold, with Ye's constant least firing time (``controller.t_dump_from_momentum =
   false``) and with the zone NSSK's least firing time raised to what the measured momentum asks
   (``geojax.control.zone_nssk.dump_time_s``).

Writes ``ye_accumulation.md`` and ``ye_accumulation.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import jax.numpy as jnp
import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch
from geojax.physics import constants as c
from geojax.physics.ephemeris import sun_position_eci_m

HERE = Path(__file__).resolve().parent
AREAS_M2 = (20.0, 40.0, 80.0, 160.0)
OFFSETS_M = (0.25, 0.5, 1.0, 2.0)
YE_AREA_M2 = 40.0
YE_H_PER_DAY_NMS = 100.0
YE_T_DUMP_S = 3207.0  # Ye 2022, Sec. 4 (the zone NSSK's default, geojax.control.zone_nssk.T_DUMP_S)
TILTS_DEG = (5.0, 9.0, 15.0)
CAPACITY_NMS = 200.0


def wheels(days: float, area_m2: float, offset_m: float, **more) -> scenario.Scenario:
    """ye2022-ex1 (its zone NSSK) with the wheels and the wing's centre of pressure ``offset_m`` off along the
    array's axis; no dumping unless ``more`` asks for it."""
    return scenario.load("ye2022-ex1", {"duration.days": days, "spacecraft.srp_area_m2": area_m2,
                                        "attitude.wheels": True, "attitude.srp_offset_array_m[0]": offset_m,
                                        **more})


def closed_form_per_day_nms(sc: scenario.Scenario, area_m2: float, offset_m: float, days: float) -> float:
    """d P (1 + eta) A (1 AU / r)^2 cos(delta) x 86400, averaged over the run (the Sun from geojax's ephemeris at
    hourly points; the orbit normal along ECI z, Ye's i = 0.08 deg)."""
    t = sc.epoch_tt_s + np.arange(0.0, days * c.SECONDS_PER_DAY + 1.0, 3600.0)
    sun = np.asarray(sun_position_eci_m(jnp.asarray(t), sc.epoch_tt_s))
    r = np.linalg.norm(sun, axis=-1)
    across = np.linalg.norm(sun[:, :2], axis=-1) / r  # cos(delta)
    craft = sc.config["spacecraft"]
    force = sc.config["forces"]["srp_pressure_n_m2"] * (1 + craft["reflectivity"]) * area_m2 * (c.AU_M / r) ** 2
    return float(offset_m * np.mean(force * across) * c.SECONDS_PER_DAY)


def accumulation(days: float) -> dict:
    grid = [(a, d) for a in AREAS_M2 for d in OFFSETS_M]
    scenarios = [wheels(days, a, d) for a, d in grid]
    result = simulate_batch(scenarios)
    # the net change of the wheels' momentum from the first cycle start to the last cycle end, per day: over 30
    # days without dumping the external torques' secular rate (the Sun turns 30 deg)
    wheels_ = result.records.cycles.states["wheels"]
    net = np.linalg.norm(np.asarray(wheels_.end_nms)[:, -1] - np.asarray(wheels_.start_nms)[:, 0], axis=-1)
    per_day = net * c.SECONDS_PER_DAY / (np.asarray(wheels_.end_nms).shape[1] * c.SIDEREAL_DAY_S)
    rows = [{"area_m2": a, "offset_m": d, "per_day_nms": float(per_day[k]),
             "closed_form_per_day_nms": closed_form_per_day_nms(scenarios[k], a, d, days)}
            for k, (a, d) in enumerate(grid)]
    coefficient = float(np.mean([r["per_day_nms"] / (r["area_m2"] * r["offset_m"]) for r in rows]))
    return {"rows": rows, "per_day_per_m3_nms": coefficient,
            "offset_for_100_m": {str(a): YE_H_PER_DAY_NMS / (coefficient * a) for a in AREAS_M2},
            "largest_relative_difference": max(abs(r["per_day_nms"] / r["closed_form_per_day_nms"] - 1) for r in rows)}


def dumping(days: float, offset_m: float) -> dict:
    base = scenario.load("ye2022-ex1")
    force_n, arm_m = base.config["thrusters"]["thrust_n"], scenario.load(
        "li2022-momentum").config["attitude"]["thrust_arm_m"]
    grid = [(tilt, from_momentum) for from_momentum in (False, True) for tilt in TILTS_DEG]
    scenarios = [wheels(days, YE_AREA_M2, offset_m, **{"attitude.dump_angle_max_deg": tilt,
                                                       "attitude.wheel_capacity_nms": CAPACITY_NMS,
                                                       "controller.t_dump_from_momentum": from_momentum})
                 for tilt, from_momentum in grid]
    result = simulate_batch(scenarios)
    burn_s_per_day = np.asarray(result.metrics["dv_per_year_mps"]) / 365.25 * base.config["spacecraft"][
        "mass_kg"] / force_n  # the firing a day at the start's mass (the mass changes by 1e-3 over the run)
    rows = [{"tilt_deg": tilt, "t_dump_from_momentum": from_momentum,
             "t_dump_s": YE_H_PER_DAY_NMS / (arm_m * force_n * np.sin(np.radians(tilt))),
             "firing_s_per_day": float(burn_s_per_day[k]),
             "max_wheel_momentum_nms": float(result.metrics["max_wheel_momentum_nms"][k]),
             "status": STATUS_MEANINGS[int(result.status[k])]} for k, (tilt, from_momentum) in enumerate(grid)]
    line_offset_m = YE_H_PER_DAY_NMS / (force_n * YE_T_DUMP_S)
    return {"rows": rows, "thrust_n": force_n, "thrust_arm_m": arm_m, "ye_line_offset_m": line_offset_m,
            "ye_tilt_deg": float(np.degrees(np.arcsin(line_offset_m / arm_m))), "capacity_nms": CAPACITY_NMS}


def table(acc: dict, dump: dict, days: float, dump_days: float) -> str:
    areas = list(AREAS_M2)
    lines = ["# Ye 2022's 100 N m s a day and its t_dump, from the physics", "",
             f"`python studies/momentum/ye_accumulation.py --days {days:g} --dump-days {dump_days:g}` (geojax "
             f"{geojax.__version__}); ye2022-ex1's satellite (reflectivity 0.3), the wheels' momentum with no "
             f"dumping over {days:g} days from 2020-01-01, the centre of pressure off along the array's axis.", "",
             "## 1. The daily accumulation (N m s a day; the closed form in brackets)", "",
             "| offset (m) | " + " | ".join(f"A = {a:g} m²" for a in areas) + " |",
             "|---|" + "---|" * len(areas)]
    for d in OFFSETS_M:
        cells = [next(r for r in acc["rows"] if r["area_m2"] == a and r["offset_m"] == d) for a in areas]
        lines.append(f"| {d:g} | " + " | ".join(f"{r['per_day_nms']:.2f} ({r['closed_form_per_day_nms']:.2f})"
                                                 for r in cells) + " |")
    lines += ["", f"Linear in d A: {acc['per_day_per_m3_nms']:.4f} N m s a day per m of offset and m² of area "
                  f"(largest difference from the closed form {100 * acc['largest_relative_difference']:.2f} %). "
                  "100 N m s a day needs an offset of " + ", ".join(
                      f"{acc['offset_for_100_m'][str(a)]:.2f} m at {a:g} m²" for a in areas)
              + f": at Ye's {YE_AREA_M2:g} m², a single wing's centre of pressure "
                f"{acc['offset_for_100_m'][str(YE_AREA_M2)]:.2f} m off the centre of mass along its axis.", "",
              "## 2. The t_dump the physics asks (100 N m s a day)", "",
              f"Ye's t_dump = {YE_T_DUMP_S:g} s with one {1000 * dump['thrust_n']:g} mN thruster is a line of action "
              f"{dump['ye_line_offset_m']:.2f} m off the centre of mass; at {dump['thrust_arm_m']:g} m from the "
              f"nozzle, a tilt of {dump['ye_tilt_deg']:.1f}°. Flown for {dump_days:g} days (ye2022-ex1, zone NSSK, "
              f"{dump['capacity_nms']:g} N m s wheels, the offset of 1. at {YE_AREA_M2:g} m²):", "",
              "| tilt limit (°) | zone NSSK's least firing | t_dump asked (s) | firing per day (s) | "
              "largest wheel momentum (N m s) | status |",
              "|---|---|---|---|---|---|"]
    lines += [f"| {r['tilt_deg']:g} | {'from the momentum' if r['t_dump_from_momentum'] else 'Ye t_min'} | "
              f"{r['t_dump_s']:.0f} | {r['firing_s_per_day']:.0f} | {r['max_wheel_momentum_nms']:.1f} | "
              f"{r['status']} |" for r in dump["rows"]]
    return "\n".join(lines + [""])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--days", type=float, default=2.0)
    ap.add_argument("--dump-days", type=float, default=30.0)
    ap.add_argument("--out", type=Path, default=HERE / "results")
    args = ap.parse_args(argv)
    acc = accumulation(args.days)
    dump = dumping(args.dump_days, acc["offset_for_100_m"][str(YE_AREA_M2)])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "ye_accumulation.json").write_text(json.dumps({"accumulation": acc, "dumping": dump}, indent=1))
    (args.out / "ye_accumulation.md").write_text(table(acc, dump, args.days, args.dump_days))
    print((args.out / "ye_accumulation.md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
