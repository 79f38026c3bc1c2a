"""Summary metrics of a closed-loop rollout, in JAX so a sweep computes them inside its batch.

Units are in the names (DESIGN.md "Contracts").  The first cycle is
acquisition and is left out of the accuracy metrics when there is more than one.
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S
from geojax.elements import wrap_angle

CYCLE_NAMES = ("lon_deg", "ex", "ey", "ix", "iy", "dv_mps", "ns_fraction")
NAMES = ("dv_per_year_mps", "burns_total", "burns_per_thruster_per_orbit", "max_abs_dlon_deg", "max_abs_dlat_deg",
         "max_abs_de", "max_abs_di", "mean_beta_deg", "cycles_without_solution")


def closed_loop_metrics(records, final, target, n_cycles: int) -> dict:
    """``records`` (simulate.CycleRecord, leading cycle axis), final state, target [6] -> {name: scalar}."""
    m = records.means
    first = 1 if n_cycles > 1 else 0
    fired = records.burn_s > 0
    v = jnp.where(fired, records.burns.v_mps, 0.0)
    dv_ns = jnp.sum(jnp.where(fired, jnp.abs(records.burns.dv_rsw_mps[..., 2]), 0.0), axis=1)
    v_sum = jnp.sum(v, axis=1)
    with_burns = v_sum > 0
    # Li 2022, eq. (46), averaged over the cycles that burn.
    beta = jnp.degrees(jnp.arcsin(jnp.clip(dv_ns / jnp.where(with_burns, v_sum, 1.0), 0.0, 1.0)))
    mean_beta = jnp.sum(jnp.where(with_burns, beta, 0.0)) / jnp.maximum(jnp.sum(with_burns), 1)
    return {
        "dv_per_year_mps": final.dv_mps * 365.25 * SECONDS_PER_DAY / (n_cycles * SIDEREAL_DAY_S),
        "burns_total": jnp.sum(fired).astype(float),
        "burns_per_thruster_per_orbit": jnp.sum(fired) / (2 * n_cycles),
        "max_abs_dlon_deg": jnp.max(jnp.abs(jnp.degrees(wrap_angle(m.lon_rad[first:] - target[0])))),
        "max_abs_dlat_deg": jnp.max(jnp.degrees(m.max_abs_lat_rad[first:])),
        "max_abs_de": jnp.max(jnp.hypot(m.ex[first:] - target[2], m.ey[first:] - target[3])),
        "max_abs_di": jnp.max(jnp.hypot(m.ix[first:] - target[4], m.iy[first:] - target[5])),
        "mean_beta_deg": mean_beta,
        "cycles_without_solution": jnp.sum(~records.burns.feasible).astype(float),
    }


def cycle_series(records) -> dict:
    """Per-cycle records a sweep may keep (``cycles = true``): mean longitude (deg), e and i vectors
    (MEE f, g, h, k), the Delta-V planned and fired in the cycle (m/s) and the north-south fraction."""
    m = records.means
    fired = records.burn_s > 0
    return {
        "lon_deg": jnp.degrees(m.lon_rad), "ex": m.ex, "ey": m.ey, "ix": m.ix, "iy": m.iy,
        "dv_mps": jnp.sum(jnp.where(fired, records.burns.v_mps, 0.0), axis=1),
        "ns_fraction": records.fraction,
    }
