"""The drift atlas: the longitude acceleration of a geostationary satellite around the whole ring from the
Earth's field alone (EGM2008 to degree 2, 3, 4, 8 and 20), and its equilibrium longitudes against the
published ones (stable 75.1 deg E and 105.3 deg W, unstable 11.5 deg W and 161.9 deg E).

    python studies/force_model/drift_atlas.py

The published values are quoted from the literature as issue 33 gives them (Soop, *Handbook of Geostationary
Orbits*, 1994, Sec. 3.4, discusses the equilibria: near 75 E and 105 W stable), not computed here.
Results: ``results/drift_atlas.json`` and ``.md``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import geojax  # noqa: F401  (x64)
from geojax.physics import constants as c
from geojax.papers import SOOP1994_EQUILIBRIA_DEG
from geojax.physics.geopotential import egm2008, longitude_acceleration_rad_s2

HERE = Path(__file__).resolve().parent
GEO_RADIUS_M = 42164.16e3
PUBLISHED_DEG = SOOP1994_EQUILIBRIA_DEG
DEGREES = (2, 3, 4, 8, 20)


def equilibria(degree: int, samples: int = 36000):
    """(stable, unstable) longitudes in deg E, (-180, 180], by sign changes on a 0.01 deg ring refined by
    bisection, and the acceleration on the ring (deg/day^2)."""
    field = jax.tree_util.tree_map(jnp.asarray, egm2008(degree))
    accel = jax.jit(lambda lon: longitude_acceleration_rad_s2(lon, GEO_RADIUS_M, c.MU_EARTH_M3_S2, c.R_EARTH_M, field))
    lon = np.linspace(-np.pi, np.pi, samples, endpoint=False)
    values = np.asarray(accel(jnp.asarray(lon)))
    stable, unstable = [], []
    for i in np.nonzero(np.sign(values) != np.sign(np.roll(values, -1)))[0]:
        lo, hi = lon[i], lon[i] + 2 * np.pi / samples
        f_lo = values[i]
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            f_mid = float(accel(jnp.asarray(mid)))
            lo, hi, f_lo = (mid, hi, f_mid) if np.sign(f_mid) == np.sign(f_lo) else (lo, mid, f_lo)
        root = float(np.degrees(np.angle(np.exp(1j * 0.5 * (lo + hi)))))
        (stable if values[i] > 0 else unstable).append(root)  # decreasing through zero: restoring
    return sorted(stable), sorted(unstable), np.degrees(values) * 86400.0**2


def main():
    results = {"command": "python studies/force_model/drift_atlas.py " + " ".join(sys.argv[1:]),
               "radius_km": GEO_RADIUS_M / 1e3, "published_deg": PUBLISHED_DEG, "degrees": {}}
    for degree in DEGREES:
        stable, unstable, values = equilibria(degree)
        results["degrees"][str(degree)] = {"stable_deg": stable, "unstable_deg": unstable,
                                           "max_abs_accel_deg_per_day2": float(np.max(np.abs(values)))}
        print(degree, stable, unstable, flush=True)
    lines = ["# Drift atlas: equilibrium longitudes of the geostationary ring from the Earth's field", "",
             f"`{results['command']}`; circular equatorial orbit of radius {GEO_RADIUS_M / 1e3:.2f} km, EGM2008 "
             "(tide-free) to degree and order N, field alone (no Sun, Moon, SRP).  Longitudes in deg E.  Published: "
             "stable {:g} and {:g}, unstable {:g} and {:g}.".format(*PUBLISHED_DEG["stable"], *PUBLISHED_DEG["unstable"]), "",
             "| N | stable | unstable | largest |longitude acceleration| (deg/day^2) |", "|---:|---|---|---:|"]
    for degree, row in results["degrees"].items():
        lines.append(f"| {degree} | {', '.join(f'{x:.2f}' for x in row['stable_deg'])} | "
                     f"{', '.join(f'{x:.2f}' for x in row['unstable_deg'])} | "
                     f"{row['max_abs_accel_deg_per_day2']:.2e} |")
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "drift_atlas.json").write_text(json.dumps(results, indent=1))
    (HERE / "results" / "drift_atlas.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
