"""The coordinated MPC: one linear program for a whole cluster, its satellites' minimum-fuel programs
(``control.mpc``) side by side and coupled by a least separation between every pair over the horizon.

Each satellite's program is the MPC's (its burns, its windows about its own targets, its capacities); the
cluster's stacks their decisions and their mean-element states (``mpc.operator`` on the stacked state: the
Riccati recursion then couples them), and adds for every pair (i, j), every boundary 1..N of the horizon and
``ANGLES`` sidereal angles L of the day after it one half-space row

    n(L) . (r_i - r_j)(L) >= d_min,   r_i - r_j = a M(L) (x_i - x_j)  (``physics.relative.linear_relative_rtn``),

with n(L) the unit vector of the relative position that the satellites' free drift (the program's own zero:
each satellite's predicted mean elements without burns) gives at L, and M(L) carrying beside the e/i terms the
drift's: the along-track a d(lambda_dot) tau (tau: the time from the boundary to L) and the radial
-2/3 a d(lambda_dot) / omega of the semi-major axis that goes with it.  By Cauchy-Schwarz each row implies
|r_i - r_j|(L) >= d_min in the linearised relative motion, whatever the burns turn the relative position to,
so the rows are a convex inner approximation of the separation.  Rows are soft with the MPC's
exact penalty (``penalty_mps`` per d_min violated), so the program stays feasible; ``min_separation_m`` = 0
leaves them out, and the program is then the satellites' own programs together (the same plans to the
solver's tolerance).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control import lp, mpc
from geojax.control.base import Controller
from geojax.control.effects import R_SYNC_M
from geojax.params import station_target
from geojax.physics.constants import OMEGA_EARTH_RAD_S
from geojax.physics.elements import wrap_angle
from geojax.physics.propulsion import arm_limits
from geojax.physics.relative import linear_relative_rtn

ANGLES = 24  # sidereal angles per day at which each pair's separation is held (15 deg apart)


class Coordinated(NamedTuple):
    """A satellite's plan in a coordinated cluster: the MPC's, and the least separation to the other satellites
    that the program predicts over the day after the next boundary (linearised relative motion; inf alone)."""

    plan: mpc.Plan
    separation_m: jnp.ndarray  # []


def relative_rtn_matrix(angles_rad, tau_s):
    """[K, 6, 3] d(relative RTN position, m) / d(relative mean elements (lon, drift, e_x, e_y, i_x, i_y) at a
    boundary) at the sidereal angles ``angles_rad`` [K], ``tau_s`` [K] after the boundary: the e/i terms of
    ``linear_relative_rtn`` (linear in the differences) and the drift's, along-track a tau and radial
    -2/3 a / omega (the semi-major axis of the drift, lambda_dot = -3/2 omega da / a)."""
    basis = jnp.eye(6)
    m = jax.vmap(lambda angle: linear_relative_rtn(R_SYNC_M, basis[:, 0], basis[:, 2], basis[:, 3],
                                                   basis[:, 4], basis[:, 5], angle))(angles_rad)
    drift = jnp.stack([jnp.full_like(tau_s, -2 / 3 * R_SYNC_M / OMEGA_EARTH_RAD_S), R_SYNC_M * tau_s,
                       jnp.zeros_like(tau_s)], -1)
    return m.at[:, 1].set(drift)


def separation_rows(free, horizon, min_separation_m, n_max: int, l_start_rad=0.0):
    """The pairs' half-space rows: (rows [n_max, P K, 6 S] on the stacked change of the mean elements at
    boundaries 1..n_max, lower [n_max, P K] (upper: none), the free drift's relative positions [P, n_max, K, 3]
    m at the ``ANGLES`` angles and their matrix [K, 6, 3] (``relative_rtn_matrix``)), from every satellite's
    free drift ``free`` [S, n_max + 1, 6] (absolute mean elements), horizon [S] and the sidereal angle at the
    boundaries ``l_start_rad`` (the cycle's start: cycles are sidereal days); scaled to d_min (1 m where it is
    0)."""
    n_sat = free.shape[0]
    index_i, index_j = (jnp.array(side) for side in zip(*itertools.combinations(range(n_sat), 2)))
    relative = free[index_i, 1:] - free[index_j, 1:]  # [P, n_max, 6]
    relative = relative.at[..., 0].set(wrap_angle(relative[..., 0]))
    angles = 2 * jnp.pi * jnp.arange(ANGLES) / ANGLES
    m = relative_rtn_matrix(angles, jnp.mod(angles - l_start_rad, 2 * jnp.pi) / OMEGA_EARTH_RAD_S)  # [K, 6, 3]
    r = jnp.einsum("pjc,kcr->pjkr", relative, m)
    distance = jnp.linalg.norm(r, axis=-1)  # [P, n_max, K]
    unit = r / jnp.where(distance > 0, distance, 1.0)[..., None]
    u = jnp.einsum("pjkr,kcr->pjkc", unit, m)  # [P, n_max, K, 6]: n(L) . M(L)
    on = jax.nn.one_hot(index_i, n_sat) - jax.nn.one_hot(index_j, n_sat)  # [P, S]
    scale = jnp.where(min_separation_m > 0, min_separation_m, 1.0)
    rows = jnp.einsum("ps,pjkc->jpksc", on, u).reshape(n_max, -1, 6 * n_sat) / scale
    active = (min_separation_m > 0) & (jnp.arange(1, n_max + 1)[None, :, None]
                                       <= jnp.minimum(horizon[index_i], horizon[index_j])[:, None, None])
    lower = jnp.where(active, (min_separation_m - distance) / scale, -jnp.inf)  # [P, n_max, K]
    return rows, jnp.swapaxes(lower, 0, 1).reshape(n_max, -1), r, m


def stacked(models: mpc.Model, rows, lower) -> mpc.Model:
    """The cluster's ``mpc.Model`` from its satellites' (leaves [S, ...]) and the pairs' rows: states and burns
    side by side ([n_max, 6 S, 2G S], ordered satellite, burn, direction within a cycle), each satellite's rows
    on its own state then the pairs' (``separation_rows``)."""
    n_sat, n_max = models.rows.shape[:2]
    eye = jnp.eye(n_sat)
    effect = jnp.einsum("st,sj,sab->jsatb", eye, models.mask, models.effect)
    own = jnp.einsum("st,sjra->jsrta", eye, models.rows).reshape(n_max, -1, 6 * n_sat)
    width = effect.shape[-1] * n_sat
    per_cycle = lambda x: jnp.swapaxes(x, 0, 1).reshape(n_max, -1)  # noqa: E731  [S, n_max, ...] -> [n_max, S ...]
    return mpc.Model(effect.reshape(n_max, 6 * n_sat, width), models.directions, models.l_rad,
                     jnp.concatenate([own, rows], 1), jnp.concatenate([per_cycle(models.lower), lower], 1),
                     jnp.concatenate([per_cycle(models.upper), jnp.full_like(lower, jnp.inf)], 1),
                     jnp.repeat(models.cap_scale, 2), jnp.ones(n_max), models.cycle_s[0])


def stacked_program(models: mpc.Model, leaves: dict, pair_lower, pair_penalty, shape: mpc.Shape):
    """(c, lower, upper, penalty) of the cluster's program on ``stacked``'s rows: each satellite's
    (``mpc.program``) interleaved per cycle, then the pairs' rows (``pair_lower``, ``pair_penalty`` [n_max,
    P K]; no upper bound)."""
    n_sat, n_max, g = models.rows.shape[0], shape.n_max, shape.generators
    c, lower, upper, penalty = jax.vmap(lambda m, l_: mpc.program(m, l_, shape))(models, leaves)
    n, caps = n_max * 2 * g, 2 * n_max

    def interleave(v, pairs):  # [S, n + caps + n_max R] -> the stacked order, ``pairs`` [n_max, P K] appended
        per_cycle = lambda x: jnp.swapaxes(x.reshape(n_sat, n_max, -1), 0, 1).reshape(-1)  # noqa: E731
        rows = jnp.swapaxes(v[:, n + caps:].reshape(n_sat, n_max, -1), 0, 1).reshape(n_max, -1)
        return jnp.concatenate([per_cycle(v[:, :n]), per_cycle(v[:, n:n + caps]),
                                jnp.concatenate([rows, pairs], 1).reshape(-1)])

    c = jnp.swapaxes(c.reshape(n_sat, n_max, -1), 0, 1).reshape(-1)
    return (c, interleave(lower, pair_lower), interleave(upper, jnp.full_like(pair_lower, jnp.inf)),
            interleave(penalty, pair_penalty))


def plan_cluster(params, estimate, context, min_separation_m, shape: mpc.Shape):
    """The cluster's program solved (every argument with a leading satellite axis but ``min_separation_m`` []):
    (each satellite's first-cycle ``BurnPair``, the ``lp.Solution``, each satellite's rows' largest violation
    in half-widths [S] (its pairs' included, in d_min), the predicted least separation [S] m)."""
    limits = jax.vmap(arm_limits)(params.thrusters)
    target = jax.vmap(station_target)(params.station)
    accel = params.thrusters["thrust_n"] / estimate.mass_kg
    models = jax.vmap(lambda x, t, ref, l0, lim, acc, cyc, leaves, station: mpc.build(
        x, t, ref, l0, lim, acc, cyc, leaves, station, shape))(
        estimate.mean, target, context.reference, estimate.fix_mee[:, 5], limits, accel, context.cycle_s,
        params.controller, params.station)
    free = jax.vmap(mpc.natural_deviations)(estimate.mean, target, context.reference, context.cycle_s) \
        + target[:, None]
    horizon = jnp.clip(params.controller["horizon"], 1, shape.n_max)
    rows, lower, r, m = separation_rows(free, horizon, min_separation_m, shape.n_max, estimate.fix_mee[0, 5])
    n_sat, (n_pairs, n_max) = free.shape[0], r.shape[:2]
    index_i, index_j = (jnp.array(side) for side in zip(*itertools.combinations(range(n_sat), 2)))
    penalty = jnp.maximum(params.controller["penalty_mps"][index_i], params.controller["penalty_mps"][index_j])
    pair_penalty = jnp.broadcast_to(penalty[None, :, None], (n_max, n_pairs, ANGLES)).reshape(n_max, -1)
    model = stacked(models, rows, lower)
    c, low, up, pen = stacked_program(models, params.controller, lower, pair_penalty, shape)
    solution = lp.solve(c, mpc.operator(model, shape), low, up, pen,
                        tolerance=jnp.min(params.controller["tolerance"]),
                        settings=lp.Settings(iterations=shape.iterations))
    x = solution.x.reshape(n_max, n_sat, 2, shape.generators)
    w = jnp.where(jnp.all(jnp.isfinite(x[0])), jnp.maximum(x[0], 0.0), 0.0)  # never fly a failed solve
    burns = jax.vmap(mpc.first_burns)(models, w, limits)
    values = solution.ax[-model.lower.size:].reshape(n_max, -1)
    own = jnp.swapaxes(values[:, :-rows.shape[1]].reshape(n_max, n_sat, -1), 0, 1).reshape(n_sat, -1)
    violation = jax.vmap(mpc.row_violation)(models, own)
    pair_short = jnp.max(jnp.maximum(lower - values[:, -rows.shape[1]:], 0.0).reshape(n_max, n_pairs, -1), (0, 2))
    on = jax.nn.one_hot(index_i, n_sat) + jax.nn.one_hot(index_j, n_sat)  # [P, S]
    violation = jnp.maximum(violation, jnp.max(on * pair_short[:, None], 0))
    # the linearised distance over the day after boundary 1, with the first cycle's burns
    change = jnp.einsum("sab,sb->sa", models.mask[:, 0, None, None] * models.effect, w.reshape(n_sat, -1))
    moved = r[:, 0] + jnp.einsum("kcr,pc->pkr", m, change[index_i] - change[index_j])  # [P, K, 3]
    nearest = jnp.where(on > 0, jnp.min(jnp.linalg.norm(moved, axis=-1), 1)[:, None], jnp.inf)
    return burns, solution, violation, jnp.min(nearest, 0)


def coordinated_controller(shape: mpc.Shape = mpc.Shape()) -> Controller:
    """The MPC of ``shape`` with the cluster's plan (``Controller.plan_cluster``); alone, it is the MPC."""
    return _coordinated(mpc.controller(shape), shape)


@functools.lru_cache(maxsize=None)
def _coordinated(alone: Controller, shape: mpc.Shape) -> Controller:
    def plan(params, controller_state, estimate, context, key):
        own, controller_state = alone.plan(params, controller_state, estimate, context, key)
        return Coordinated(own, jnp.asarray(jnp.inf)), controller_state

    def plan_together(params, controller_state, estimate, context, key, min_separation_m):
        burns, solution, violation, separation = plan_cluster(params, estimate, context, min_separation_m, shape)
        target = jax.vmap(station_target)(params.station)
        axes = lp.Solution(0, None, None, None, None, None, None, None)
        x = jnp.swapaxes(solution.x.reshape(shape.n_max, target.shape[0], -1), 0, 1)
        own = jax.vmap(mpc.flown_plan, in_axes=(0, 0, 0, axes, 0, 0, 0, 0))(
            params, target, burns, solution._replace(x=x), violation, estimate, context, key)
        return Coordinated(own, separation), controller_state

    def thrust(params, plan_: Coordinated, t, state, environment):
        return alone.thrust(params, plan_.plan, t, state, environment)

    def record(plan_: Coordinated) -> dict:
        return {**alone.record(plan_.plan), "planned_separation_km": plan_.separation_m / 1e3}

    return dataclasses.replace(alone, plan=plan, thrust=thrust, record=record, plan_cluster=plan_together)
