"""What a planner's burns say of a run (``Controller.metrics`` of the planners that fly ``control.burns``): how many
burns, the duty, the mean pitch of Li 2022 eq. (46), and the Delta-V budget by axis.  Where a part of the loop
changes what is flown (a burn missed, a thruster out or degraded: ``states.faults``) it reports the firing time
and the Delta-V delivered in its cycle records, ``flown_s`` [n_cycles, thrusters] and ``flown_dv_abs_rsw``
[n_cycles, thrusters, 3]; the duty and the budget are then counted as flown, not as planned."""

from __future__ import annotations

import jax.numpy as jnp

from geojax.physics.constants import SECONDS_PER_YEAR
from geojax.reductions import sum_in_order, sum_over_cycles

# The per-axis components of a planner's Delta-V (``dv_components_per_year``), in RSW (= RTN) order.
DV_COMPONENTS = ("dv_radial_per_year_mps", "dv_ew_per_year_mps", "dv_ns_per_year_mps")


def metrics(params, cycles, run_s: float, own) -> dict:
    """{name: scalar} of a planner's records over a run of ``run_s`` (``cycles``: the loop's ``CycleRecord``
    stacked over cycles; ``own`` [n_cycles] bool: the cycles it flew itself, not the re-acquisition law's)."""
    rec = cycles.controller
    flown = _flown(cycles.states)
    if flown is None:
        out = {"duty_fraction": sum_over_cycles(jnp.sum(rec["fired_s"], axis=1)) / run_s}
    else:  # the firing time delivered, not the planned, over the planner's own cycles
        out = {"duty_fraction": sum_over_cycles(jnp.where(own, sum_in_order(flown.flown_s), 0.0)) / run_s}
    out.update(burn_counts(rec, rec["fired_s"].shape[0]))
    out.update(dv_components_per_year(rec, cycles.dv_mps, run_s) if flown is None
               else flown_dv_components_per_year(flown, own, run_s))
    return out


def _flown(states: dict):
    """The cycle records of the part that reports what was flown (``flown_s`` and ``flown_dv_abs_rsw``), or None."""
    reporting = [rec for rec in states.values() if hasattr(rec, "flown_s") and hasattr(rec, "flown_dv_abs_rsw")]
    if len(reporting) > 1:
        raise ValueError("two parts of the loop report the thrust flown (flown_s); at most one may change it")
    return reporting[0] if reporting else None


def burn_counts(rec: dict, n_cycles: int) -> dict:
    """Li 2022: burns fired, per thruster per orbit, and the mean pitch of eq. (46) over the cycles that burn."""
    fired = rec["fired_s"] > 0
    burns = rec["burns"]
    v_sum = jnp.sum(jnp.where(fired, burns.v_mps, 0.0), axis=1)
    dv_ns = ns_delta_v_mps(rec)
    with_burns = v_sum > 0
    beta = jnp.degrees(jnp.arcsin(jnp.clip(dv_ns / jnp.where(with_burns, v_sum, 1.0), 0.0, 1.0)))
    return {
        "burns_total": jnp.sum(fired).astype(float),
        "burns_per_thruster_per_orbit": jnp.sum(fired) / (2 * n_cycles),
        "mean_beta_deg": sum_over_cycles(jnp.where(with_burns, beta, 0.0)) / jnp.maximum(jnp.sum(with_burns), 1),
    }


def dv_components_per_year(rec: dict, dv_mps, run_s: float) -> dict:
    """The radial, along-track and cross-track components of a planner's Delta-V, per 365.25 days, a planner's
    budget by axis: ``dv_radial_per_year_mps`` (RSW R; with the robotic arms, the geometry's cosine loss: thrust
    lines aimed through the centre of mass from anti-nadir arms),
    ``dv_ew_per_year_mps`` (S, along-track: east-west control, drift and eccentricity) and
    ``dv_ns_per_year_mps`` (W, cross-track: north-south control, inclination).  Each cycle's delivered Delta-V
    (``dv_mps`` [n_cycles]) is split by the directions its burns flew (``directions_rsw`` [n_cycles, 2, 3],
    attitude errors included), weighted by each burn's firing time (one thrust F/m for both burns of a cycle:
    the mass changes by parts in 1e5 within a cycle): a burn of v along the unit direction d counts v |d_R|,
    v |d_S| and v |d_W|.  Components, not a partition: the three add up to more than ``dv_per_year_mps``
    wherever a burn is not along one axis (their root sum of squares per burn is its Delta-V)."""
    d = rec["directions_rsw"]
    weight = rec["fired_s"] / jnp.maximum(jnp.sum(rec["fired_s"], axis=1, keepdims=True), 1e-300)
    # the weighted parts stored before they are added (``geojax.reductions``: fused, the last bit depended on
    # the lane width, 1-2 of 40 QFFC samples an ulp apart at 64 and 1024 lanes)
    return {name: sum_over_cycles(dv_mps * sum_in_order(weight * jnp.abs(d[..., axis]))) * SECONDS_PER_YEAR / run_s
            for axis, name in enumerate(DV_COMPONENTS)}


def flown_dv_components_per_year(faults, own, run_s: float) -> dict:
    """``dv_components_per_year`` as flown, where a part reports it (``states.faults``): each cycle's Delta-V
    delivered per thruster and RSW axis, summed step by step as |component| (``flown_dv_abs_rsw``
    [n_cycles, 4, 3]: a burn missed counts 0, a degraded one its delivered thrust, a stuck arm's its frozen
    direction), over the cycles of the controller's own burns (``own`` [n_cycles]), per 365.25 days."""
    per_cycle = jnp.where(own[:, None], jnp.sum(faults.flown_dv_abs_rsw, axis=1), 0.0)  # [n_cycles, 3]
    return {name: sum_over_cycles(per_cycle[:, axis]) * SECONDS_PER_YEAR / run_s
            for axis, name in enumerate(DV_COMPONENTS)}


def ns_delta_v_mps(rec: dict):
    """North-south Delta-V of each cycle's fired burns (Li 2022, eq. (45)), [n_cycles]."""
    fired = rec["fired_s"] > 0
    return jnp.sum(jnp.where(fired, jnp.abs(rec["burns"].dv_rsw_mps[..., 2]), 0.0), axis=1)
