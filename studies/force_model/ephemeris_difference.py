"""Meeus against JPL DE421 over one year, on the environment grid, and what the difference does.

    python studies/force_model/ephemeris_difference.py

For each epoch: the Sun and Moon of both ephemerides at every half step of the 897.5 s grid over 365.25 days
(``physics.propagate.environment_grid``): largest angle between the two directions (arcsec), largest distance
differences, the largest difference of the Sun + Moon third-body acceleration at the GEO station at 0 deg E;
then the uncontrolled `geo` scenario (EGM2008 8x8) over the year with each ephemeris: the inclination change
and the mean-longitude drift; and, with DE421 and moon_shadow = true, the steps at the station that the Moon's
shadow touches.  Results: ``results/ephemeris_difference.json`` and ``.md``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import jax.numpy as jnp
import numpy as np

import geojax  # noqa: F401  (x64)
from geojax import scenario
from geojax.physics import constants as c
from geojax.physics.constants import SIDEREAL_DAY_S
from geojax.physics.forces import ForceModel, sunlit_fraction_xyz, third_body
from geojax.physics.propagate import environment_grid, steps_per_cycle
from geojax.uncontrolled import drift_summary, propagate_scenario

HERE = Path(__file__).resolve().parent
EPOCHS = ("2020-01-01T12:00:00", "2027-01-01T00:00:00")


def angle_arcsec(a, b):
    cos = np.sum(a * b, -1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1, 1))) * 3600


def compare(utc: str) -> dict:
    sc = scenario.load("geo", {"epoch.utc": utc, "duration.days": 365.25})
    n = steps_per_cycle(sc.step_s)
    cycles = round(365.25 * 86400 / SIDEREAL_DAY_S)
    grids = {kind: environment_grid(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s, SIDEREAL_DAY_S / n, cycles, n, kind)
             for kind in ("meeus", "de421")}
    m, d = grids["meeus"], grids["de421"]
    flat = lambda x: np.asarray(x).reshape(-1, 3)  # noqa: E731
    sun_m, sun_d, moon_m, moon_d = flat(m.r_sun_eci_m), flat(d.r_sun_eci_m), flat(m.r_moon_eci_m), flat(d.r_moon_eci_m)
    # The station at 0 deg E (ECI at each stage time) and the third-body accelerations there.
    angle = np.asarray(m.earth_angle_rad).reshape(-1)
    station = 42164.16e3 * np.stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)], -1)
    accel = lambda sun, moon: np.asarray(third_body(jnp.asarray(station), jnp.asarray(sun), c.MU_SUN_M3_S2)  # noqa: E731
                                         + third_body(jnp.asarray(station), jnp.asarray(moon), c.MU_MOON_M3_S2))
    a_m, a_d = accel(sun_m, moon_m), accel(sun_d, moon_d)
    fm = ForceModel(shadow_on=0.0, moon_radius_m=c.R_MOON_M)
    lit = np.asarray(sunlit_fraction_xyz(*(jnp.asarray(station[:, j]) for j in range(3)),
                                         d._replace(r_sun_eci_m=jnp.asarray(sun_d), r_moon_eci_m=jnp.asarray(moon_d)), fm))
    out = {"epoch_utc": utc, "grid_points": len(sun_m),
           "sun_max_angle_arcsec": float(angle_arcsec(sun_m, sun_d).max()),
           "sun_max_distance_relative": float(np.max(np.abs(np.linalg.norm(sun_m, axis=-1) / np.linalg.norm(sun_d, axis=-1) - 1))),
           "moon_max_angle_arcsec": float(angle_arcsec(moon_m, moon_d).max()),
           "moon_max_distance_km": float(np.max(np.abs(np.linalg.norm(moon_m, axis=-1) - np.linalg.norm(moon_d, axis=-1))) / 1e3),
           "third_body_max_difference_mps2": float(np.max(np.linalg.norm(a_m - a_d, axis=-1))),
           "third_body_max_mps2": float(np.max(np.linalg.norm(a_d, axis=-1))),
           "moon_shadow_stage_points_at_0E": int(np.sum(lit < 1.0)), "moon_shadow_min_sunlit": float(lit.min())}
    for kind in ("meeus", "de421"):
        run = propagate_scenario(scenario.load("geo", {"epoch.utc": utc, "duration.days": 365.25,
                                                       "forces.ephemeris": kind}), progress=False)
        summary = drift_summary(run.cycles, 365.25)
        out[f"uncontrolled_{kind}"] = {"di_deg": summary.di_deg, "dlon_deg": summary.dlon_deg, "de_max": summary.de_max}
    return out


def main():
    results = {"command": "python studies/force_model/ephemeris_difference.py " + " ".join(sys.argv[1:]),
               "epochs": [compare(utc) for utc in EPOCHS]}
    lines = ["# Meeus against JPL DE421 over one year", "", f"`{results['command']}`: every half step of the "
             "897.5 s environment grid over 365.25 days; third-body acceleration at the GEO station at 0 deg E; "
             "the uncontrolled `geo` scenario (EGM2008 8x8, 0 deg E) over the year with each ephemeris.", "",
             "| epoch | Sun angle (\") | Sun distance (rel.) | Moon angle (\") | Moon distance (km) | "
             "third-body accel. diff. (m/s^2, of max) | i change Meeus / DE421 (deg) | lon drift Meeus / DE421 (deg) | "
             "Moon-shadow points at 0 E (min. sunlit) |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for e in results["epochs"]:
        um, ud = e["uncontrolled_meeus"], e["uncontrolled_de421"]
        lines.append(f"| {e['epoch_utc']} | {e['sun_max_angle_arcsec']:.1f} | {e['sun_max_distance_relative']:.1e} | "
                     f"{e['moon_max_angle_arcsec']:.1f} | {e['moon_max_distance_km']:.1f} | "
                     f"{e['third_body_max_difference_mps2']:.2e} ({e['third_body_max_mps2']:.2e}) | "
                     f"{um['di_deg']:.5f} / {ud['di_deg']:.5f} | {um['dlon_deg']:+.4f} / {ud['dlon_deg']:+.4f} | "
                     f"{e['moon_shadow_stage_points_at_0E']} ({e['moon_shadow_min_sunlit']:.3f}) |")
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "ephemeris_difference.json").write_text(json.dumps(results, indent=1))
    (HERE / "results" / "ephemeris_difference.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
