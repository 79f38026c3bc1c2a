"""Propagation over control cycles with one-cycle mean GEO elements.

``propagate_cycles`` is the building block of every rollout: an outer
``lax.scan`` over cycles (one sidereal day each) around an inner scan over
integration steps, returning the one-cycle mean elements (Li 2022, eqs. (8)-(9))
of each cycle.  It is pure and vmappable over the initial state and the force
model; the environment grid is shared by the batch.
"""

from __future__ import annotations

from functools import partial
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp

from geojax.constants import SIDEREAL_DAY_S
from geojax.dynamics import SpacecraftState, cartesian_rhs, mee_rhs
from geojax.elements import cartesian_to_mee, cycle_mean, mee_to_cartesian, semi_major_axis_m, subsatellite_point_rad, wrap_angle
from geojax.ephemeris import moon_position_eci_m, sun_position_eci_m
from geojax.forces import Environment, ForceModel
from geojax.frames import earth_rotation_angle_rad
from geojax.integrate import propagate_steps


class Dynamics(NamedTuple):
    """An orbit representation: its equations of motion and conversions to and from MEE."""

    rhs: Callable
    to_mee: Callable  # (orbit [6], mu) -> MEE [6]
    from_mee: Callable  # (MEE [6], mu) -> orbit [6]


MEE = Dynamics(mee_rhs, lambda orbit, mu: orbit, lambda mee, mu: mee)
CARTESIAN = Dynamics(
    cartesian_rhs,
    lambda orbit, mu: cartesian_to_mee(orbit[..., :3], orbit[..., 3:], mu),
    lambda mee, mu: jnp.concatenate(mee_to_cartesian(mee, mu), axis=-1),
)
DYNAMICS = {"mee": MEE, "cartesian": CARTESIAN}


class CycleMeans(NamedTuple):
    """One-cycle mean elements (Li 2022, eq. (8)), SI units, leading axis = cycle."""

    t_s: jnp.ndarray  # mid-cycle time since the start of the propagation
    lon_rad: jnp.ndarray  # mean sub-satellite longitude, wrapped to [-pi, pi)
    drift_rad_s: jnp.ndarray  # longitude change over the cycle / cycle length
    ex: jnp.ndarray
    ey: jnp.ndarray
    ix: jnp.ndarray
    iy: jnp.ndarray
    a_m: jnp.ndarray
    max_abs_lat_rad: jnp.ndarray  # largest |sub-satellite latitude| sampled in the cycle (not a mean)


def steps_per_cycle(step_s: float) -> int:
    """Number of integration steps per sidereal day for a requested step (rounded to the nearest)."""
    if not step_s > 0:
        raise ValueError(f"integration.step_s: must be > 0 s, got {step_s}")
    return max(1, round(SIDEREAL_DAY_S / step_s))


def environment_at(t_tt_s, frame_epoch_tt_s, tt_minus_ut1_s) -> Environment:
    """Sun, Moon and Earth angle at TT times of any shape (leaves [..., 3] and [...])."""
    return Environment(
        sun_position_eci_m(t_tt_s, frame_epoch_tt_s),
        moon_position_eci_m(t_tt_s, frame_epoch_tt_s),
        earth_rotation_angle_rad(t_tt_s, frame_epoch_tt_s, tt_minus_ut1_s),
    )


@partial(jax.jit, static_argnums=(4, 5))
def environment_grid(start_tt_s, frame_epoch_tt_s, tt_minus_ut1_s, step_s, n_cycles: int, n_steps: int) -> Environment:
    """Environment at the RK4 stage times of every step from ``start_tt_s``: leaves [n_cycles, n_steps, 3, ...].

    Evaluated once per scenario (and per step size), shared by every sample of a batch.
    """
    half_steps = jnp.arange(2 * n_cycles * n_steps + 1)
    env = environment_at(start_tt_s + half_steps * (step_s / 2), frame_epoch_tt_s, tt_minus_ut1_s)
    index = 2 * jnp.arange(n_cycles * n_steps)[:, None] + jnp.arange(3)[None, :]
    return jax.tree_util.tree_map(lambda x: x[index].reshape((n_cycles, n_steps, 3) + x.shape[1:]), env)


def cycle_means(mee_samples, earth_angle_rad, mu, cycle_s, t_mid_s) -> CycleMeans:
    """Mean elements from [n + 1] MEE samples equally spaced over one cycle, both ends included."""
    lon, lat = subsatellite_point_rad(mee_samples, earth_angle_rad, mu)
    dlon = wrap_angle(lon - lon[0])
    # Unwrap relative to the first sample; the longitude moves < pi per cycle.
    dlon = jnp.concatenate([jnp.zeros(1), jnp.cumsum(wrap_angle(jnp.diff(dlon)))])
    mean = cycle_mean(mee_samples)
    return CycleMeans(
        t_s=t_mid_s,
        lon_rad=wrap_angle(lon[0] + cycle_mean(dlon)),
        drift_rad_s=dlon[-1] / cycle_s,
        ex=mean[1],
        ey=mean[2],
        ix=mean[3],
        iy=mean[4],
        a_m=cycle_mean(semi_major_axis_m(mee_samples)),
        max_abs_lat_rad=jnp.max(jnp.abs(lat)),
    )


def propagate_cycles(
    dynamics: Dynamics,
    state: SpacecraftState,
    env_grid: Environment,
    fm: ForceModel,
    step_s,
    thrust_fn=None,
):
    """Propagate over all cycles of ``env_grid``; returns (final state, CycleMeans [n_cycles]).

    ``thrust_fn(step_start_s, step_s) -> Thrust`` is evaluated per step with
    the time since the start of the propagation (none if omitted).
    """
    n_steps = env_grid.earth_angle_rad.shape[1]
    cycle_s = n_steps * step_s

    def one_cycle(carry, xs):
        cycle_index, env_steps = xs
        t0 = cycle_index * cycle_s
        final, starts = propagate_steps(dynamics.rhs, carry, env_steps, fm, step_s, t0, thrust_fn)
        orbits = jnp.concatenate([starts.orbit, final.orbit[None]], axis=0)
        angles = jnp.concatenate([env_steps.earth_angle_rad[:, 0], env_steps.earth_angle_rad[-1:, 2]])
        means = cycle_means(dynamics.to_mee(orbits, fm.mu_m3_s2), angles, fm.mu_m3_s2, cycle_s, t0 + cycle_s / 2)
        return final, means

    n_cycles = env_grid.earth_angle_rad.shape[0]
    return jax.lax.scan(one_cycle, state, (jnp.arange(n_cycles), env_grid))
