"""Uncontrolled propagation at EGM2008 8x8: geojax (MEE, RK4, 897.5 s step) against an independent DOP853
integration (``reference.py``: Cartesian, rtol 1e-12, the field by a different method, same Sun, Moon, SRP
and shadow), 200 days from a drifting start (at the slot with the slot's inertial velocity).

    python studies/force_model/propagation_check.py [--days 200] [--cases 0:2027 -75:2029 96:2020]

Both trajectories are sampled at geojax's step grid and reduced by the same one-cycle means (trapezoid over
each sidereal day): mean sub-satellite longitude, inclination vector, eccentricity vector.  Reported: the
largest difference of the mean longitude, the inclination change and the eccentricity excursion of each, and
their relative differences.  Results: ``results/propagation_check.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import geojax  # noqa: F401  (x64)
from geojax import scenario
from geojax.physics.constants import SIDEREAL_DAY_S
from geojax.physics.dynamics import SpacecraftState, mee_rhs
from geojax.physics.elements import cartesian_to_mee, mee_to_cartesian
from geojax.physics.integrate import propagate_steps
from geojax.physics.propagate import environment_at, environment_grid, steps_per_cycle
from geojax.uncontrolled import inclination_vector_deg

HERE = Path(__file__).resolve().parent
import importlib.util  # noqa: E402

_spec = importlib.util.spec_from_file_location("force_model_reference", HERE / "reference.py")
reference = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(reference)


def case_scenario(lon_deg: float, year: int, days: float, degree: int = 8):
    return scenario.load("geo", {"station.lon_deg": lon_deg, "epoch.utc": f"{year}-01-01T00:00:00",
                                 "duration.days": days, "forces.gravity_degree": degree,
                                 "forces.gravity_order": degree})


def geojax_states(sc, n_cycles: int):
    """MEE [n_cycles * n + 1, 6] at every step start of geojax's RK4 (and the end), n steps per sidereal day."""
    n = steps_per_cycle(sc.step_s)
    step_s = SIDEREAL_DAY_S / n
    env = environment_grid(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s, step_s, n_cycles, n)
    env = jax.tree_util.tree_map(lambda x: x.reshape((n_cycles * n,) + x.shape[2:]), env)
    fm = jax.tree_util.tree_map(jnp.asarray, sc.force_model)
    state = SpacecraftState(jnp.asarray(sc.initial_mee), jnp.asarray(sc.mass_kg), jnp.asarray(0.0))
    run = jax.jit(lambda s: propagate_steps(mee_rhs, s, env, fm, step_s, 0.0))
    final, starts = run(state)
    return np.concatenate([np.asarray(starts.orbit), np.asarray(final.orbit)[None]]), step_s, n


def reference_states(sc, times_s):
    """MEE at ``times_s`` from the DOP853 reference with the same force model."""
    fm = sc.force_model
    forces = {"mu": fm.mu_m3_s2, "r_earth_m": fm.r_earth_m, "c_nm": np.asarray(fm.gravity.c_nm),
              "s_nm": np.asarray(fm.gravity.s_nm), "degree": fm.gravity.degree, "order": fm.gravity.order,
              "mu_sun": fm.mu_sun_m3_s2 * fm.sun_on, "mu_moon": fm.mu_moon_m3_s2 * fm.moon_on,
              "srp": fm.srp_on * fm.srp_pressure_1au_n_m2 * (1 + fm.reflectivity) * fm.srp_area_m2,
              "shadow": bool(fm.shadow_on)}
    ephemeris = reference.Ephemeris(sc.epoch_tt_s, sc.tt_minus_ut1_s, float(times_s[-1]))
    r, v = mee_to_cartesian(jnp.asarray(sc.initial_mee), fm.mu_m3_s2)
    rv = reference.integrate(reference.cartesian_rhs(forces, ephemeris, sc.mass_kg),
                             np.concatenate([np.asarray(r), np.asarray(v)]), times_s)
    return np.asarray(cartesian_to_mee(jnp.asarray(rv[:, :3]), jnp.asarray(rv[:, 3:]), fm.mu_m3_s2))


def cycle_means(sc, mee, times_s, n):
    """One-cycle means (trapezoid over the n + 1 samples of each sidereal day): lon (deg), i vector (deg), e vector."""
    r, _ = mee_to_cartesian(jnp.asarray(mee), sc.force_model.mu_m3_s2)
    angle = np.asarray(environment_at(sc.epoch_tt_s + times_s, sc.epoch_tt_s, sc.tt_minus_ut1_s).earth_angle_rad)
    lon = np.unwrap(np.arctan2(np.asarray(r)[:, 1], np.asarray(r)[:, 0]) - angle)
    weights = np.ones(n + 1) / n
    weights[[0, -1]] /= 2
    cycles = (len(times_s) - 1) // n
    mean = lambda q: np.array([weights @ q[c * n:(c + 1) * n + 1] for c in range(cycles)])  # noqa: E731
    return np.degrees(mean(lon)), inclination_vector_deg(mean(mee[:, 3]), mean(mee[:, 4])), \
        np.stack([mean(mee[:, 1]), mean(mee[:, 2])], -1)


def compare(lon_deg: float, year: int, days: float, degree: int = 8) -> dict:
    sc = case_scenario(lon_deg, year, days, degree)
    n_cycles = round(days * 86400.0 / SIDEREAL_DAY_S)
    start = time.perf_counter()
    mee_g, step_s, n = geojax_states(sc, n_cycles)
    geojax_s = time.perf_counter() - start
    times = np.arange(n_cycles * n + 1) * step_s
    start = time.perf_counter()
    mee_r = reference_states(sc, times)
    reference_s = time.perf_counter() - start
    (lon_g, i_g, e_g), (lon_r, i_r, e_r) = cycle_means(sc, mee_g, times, n), cycle_means(sc, mee_r, times, n)
    di = lambda i: float(np.linalg.norm(i[-1] - i[0]))  # noqa: E731
    de = lambda e: float(np.max(np.linalg.norm(e - e[0], axis=-1)))  # noqa: E731
    return {"lon_deg": lon_deg, "year": year, "days": days, "degree": degree, "cycles": n_cycles, "step_s": step_s,
            "drift_deg": float(lon_g[-1] - lon_g[0]),
            "max_mean_lon_difference_deg": float(np.max(np.abs(lon_g - lon_r))),
            "inclination_change_deg": {"geojax": di(i_g), "reference": di(i_r)},
            "inclination_change_relative_difference": abs(di(i_g) - di(i_r)) / di(i_r),
            "eccentricity_excursion": {"geojax": de(e_g), "reference": de(e_r)},
            "eccentricity_excursion_relative_difference": abs(de(e_g) - de(e_r)) / de(e_r),
            "wall_s": {"geojax": geojax_s, "reference": reference_s}}


def markdown(results: dict) -> str:
    lines = ["# Uncontrolled propagation at EGM2008 8x8: geojax against DOP853", "",
             f"`{results['command']}`.  geojax: MEE, RK4, {results['cases'][0]['step_s']:.2f} s step.  Reference: "
             "Cartesian DOP853, rtol 1e-12, the field by a spherical-gradient evaluation (studies/force_model/"
             "reference.py), same Meeus Sun and Moon (hourly cubic splines), SRP and conical shadow.  "
             "Start at the slot with the slot's inertial velocity (`geo` scenario, 3000 kg, 30 m^2).", "",
             "| slot | epoch | days | drift (deg) | max diff. of one-cycle mean lon (deg) | inclination change "
             "(deg), geojax / reference (rel. diff.) | e excursion, geojax / reference (rel. diff.) |",
             "|---:|---:|---:|---:|---:|---:|---:|"]
    for c in results["cases"]:
        ic, ee = c["inclination_change_deg"], c["eccentricity_excursion"]
        lines.append(f"| {c['lon_deg']:g} | {c['year']} | {c['days']:g} | {c['drift_deg']:+.3f} | "
                     f"{c['max_mean_lon_difference_deg']:.2e} | {ic['geojax']:.5f} / {ic['reference']:.5f} "
                     f"({c['inclination_change_relative_difference']:.1e}) | {ee['geojax']:.3e} / "
                     f"{ee['reference']:.3e} ({c['eccentricity_excursion_relative_difference']:.1e}) |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=200.0)
    parser.add_argument("--cases", nargs="+", default=["0:2027", "-75:2029", "96:2020"],
                        help="slot:year, slot in deg E")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    import sys
    results = {"command": "python studies/force_model/propagation_check.py " + " ".join(sys.argv[1:]), "cases": []}
    for case in args.cases:
        lon, year = case.split(":")
        results["cases"].append(compare(float(lon), int(year), args.days))
        print(json.dumps(results["cases"][-1]), flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "propagation_check.json").write_text(json.dumps(results, indent=1))
    (args.out / "propagation_check.md").write_text(markdown(results))
    print(markdown(results))


if __name__ == "__main__":
    main()
