"""Several satellites in one slot, in one loop: the closed loop's cycle vmapped over a cluster's satellites
inside the scan over cycles, and the distance between every pair from their true positions.

Each satellite is a full sample (its own parameters, random key, controller state and parts) flying the same
compiled cycle as a lone one (``loop.simulate.cycle_body``); the cluster shares the cycle grid and the
environment.  Per cycle the satellites' true positions and velocities at every step start and at the cycle's end
give each pair's closest approach within every step (``physics.relative.closest_in_step``); a cycle's record keeps
each pair's least distance, when, the time below the alert distance, and the separation the operator sees at the
cycle start (from what the controllers were told: the fixes, or a filter's estimates) beside the true one.
Nothing per step is kept beyond what a lone loop keeps.  A controller with ``plan_cluster`` (the coordinated
MPC, ``control.mpc_cluster``) plans every satellite in one program: each satellite's cycle start (its estimate)
and its flight stay vmapped (``loop.simulate.cycle_phases``), the plan between them is the cluster's.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control.base import Controller
from geojax.loop.simulate import Records, Shared, _scan_first, cycle_body, cycle_inputs, cycle_phases, initial_carry
from geojax.params import Params
from geojax.physics.constants import SECONDS_PER_DAY
from geojax.physics.propagate import MEE, Dynamics
from geojax.physics.relative import closest_in_step
from geojax.states.base import StateModel


class SeparationRecord(NamedTuple):
    """Per cycle and pair (leaves [cycle, pair]; pairs in ``pairs(n)``'s order)."""

    min_m: jnp.ndarray  # the least true distance within the cycle
    at_s: jnp.ndarray  # when, s since the cycle's start
    below_alert_s: jnp.ndarray  # time closer than the alert distance
    start_m: jnp.ndarray  # the true distance at the cycle's start
    estimated_start_m: jnp.ndarray  # the distance between the positions the controllers were told there


def pairs(n_satellites: int) -> tuple[tuple[int, int], ...]:
    """The cluster's pairs (i, j), i < j, in the order of every per-pair record."""
    return tuple(itertools.combinations(range(n_satellites), 2))


def simulate_cluster(controller: Controller, params: Params, shared: Shared, keys, *, step_s: float,
                     alert_m, dynamics: Dynamics = MEE, keep_steps: bool = False,
                     states: tuple[StateModel, ...] = (), min_separation_m=None):
    """The closed loop of a cluster (``params`` and ``keys``: a leading satellite axis; ``shared.reference``
    per satellite where given with one) over the cycles of ``shared.env``: (final states, ``Records`` of every
    satellite, leading axis satellite, ``SeparationRecord``).  ``alert_m`` [] is the alert distance;
    ``min_separation_m`` [] the distance a coordinated plan keeps (with a controller's ``plan_cluster``, which
    then plans the cluster once per cycle; None: each satellite plans alone).  Pure and vmappable over clusters;
    the static arguments are ``simulate``'s."""
    n = jax.tree_util.tree_leaves(params)[0].shape[0]
    if n < 2:
        raise ValueError(f"a cluster needs at least two satellites, got {n}")
    index_i, index_j = (jnp.array(side) for side in zip(*pairs(n)))
    xs = cycle_inputs(controller, shared)
    per_satellite_reference = controller.reference_cycles > 0 and xs[3].ndim == 4
    ref_axis = 0 if per_satellite_reference else None

    options = dict(step_s=step_s, dynamics=dynamics, keep_steps=keep_steps, states=states, positions=True)
    axes = (0, 0, 0, ref_axis, ref_axis, None, None)

    def one(p, key, carry, osc_ref, window, k, env_steps):
        return cycle_body(controller, p, key, **options)(carry, (k, env_steps, osc_ref, window))

    def begin(p, key, carry, osc_ref, window, k, env_steps):
        return cycle_phases(controller, p, key, **options)[0](carry, (k, env_steps, osc_ref, window))

    def fly(p, key, carry, osc_ref, window, k, env_steps, start, plan, controller_state):
        return cycle_phases(controller, p, key, **options)[1](carry, (k, env_steps, osc_ref, window), start, plan,
                                                              controller_state)

    def coordinated(carry, xs):  # every satellite's estimate, the cluster's plan, every satellite's flight
        start = jax.vmap(begin, in_axes=axes)(params, keys, carry, *xs[2:], *xs[:2])
        plan, controller_state = controller.plan_cluster(params, carry[1], start.estimate, start.context, start.key,
                                                         min_separation_m)
        return jax.vmap(fly, in_axes=(*axes, 0, 0, 0))(params, keys, carry, *xs[2:], *xs[:2], start, plan,
                                                       controller_state)

    def cycle(carry, xs):
        k, env_steps, osc_ref, window = xs
        if controller.plan_cluster is None or min_separation_m is None:
            carry, (record, steps, told) = jax.vmap(one, in_axes=axes)(params, keys, carry, osc_ref, window, k,
                                                                       env_steps)
        else:
            carry, (record, steps, told) = coordinated(carry, xs)
        rv = jnp.concatenate([told.steps_rv, told.end_rv[:, None]], axis=1)  # [satellite, n_steps + 1, 6]
        rel = rv[index_i] - rv[index_j]  # [pair, n_steps + 1, 6]
        distance, at_s, below_s = closest_in_step(rel[:, :-1, :3], rel[:, :-1, 3:], rel[:, 1:, :3], rel[:, 1:, 3:],
                                                  step_s, alert_m)
        step = jnp.argmin(distance, axis=1)
        separation = SeparationRecord(
            jnp.min(distance, axis=1), jnp.take_along_axis(at_s, step[:, None], axis=1)[:, 0] + step * step_s,
            jnp.sum(below_s, axis=1), jnp.linalg.norm(rel[:, 0, :3], axis=-1),
            jnp.linalg.norm(told.estimated_r[index_i] - told.estimated_r[index_j], axis=-1))
        return carry, (record, steps, separation)

    carry = jax.vmap(lambda p, w: initial_carry(controller, p, shared.env, w, dynamics, step_s, states),
                     in_axes=(0, ref_axis))(params, xs[3][0])
    body = jax.checkpoint(cycle)
    if shared.n_active is None:
        (final, _, _), (cycles, steps, separation) = jax.lax.scan(body, carry, xs)
    else:
        (final, _, _), (cycles, steps, separation) = _scan_first(body, carry, xs, shared.n_active)
    to_satellite_first = lambda tree: jax.tree_util.tree_map(lambda x: jnp.swapaxes(x, 0, 1), tree)  # noqa: E731
    records = Records(to_satellite_first(cycles), None if steps is None else to_satellite_first(steps))
    return final, records, separation


def separation_metrics(separation: SeparationRecord, cycle_s: float) -> dict:
    """The cluster's separation metrics over a run (``separation``'s leaves [cycle, pair]; units in the names):
    the least distance over every cycle and pair, when (days from the start) and which pair (its index in
    ``pairs``), each pair's least distance and time below the alert [pair], and the separation the operator sees
    at the cycle starts (from what the controllers were told): its least value and its largest error against
    the truth."""
    flat = jnp.argmin(separation.min_m)
    cycle, pair = jnp.unravel_index(flat, separation.min_m.shape)
    error = jnp.abs(separation.estimated_start_m - separation.start_m)
    return {
        "min_separation_km": jnp.min(separation.min_m) / 1e3,
        "min_separation_day": (cycle * cycle_s + separation.at_s[cycle, pair]) / SECONDS_PER_DAY,
        "min_separation_pair": pair,
        "pair_min_separation_km": jnp.min(separation.min_m, axis=0) / 1e3,
        "below_alert_h": jnp.sum(separation.below_alert_s) / 3600.0,
        "pair_below_alert_h": jnp.sum(separation.below_alert_s, axis=0) / 3600.0,
        "min_estimated_separation_km": jnp.min(separation.estimated_start_m) / 1e3,
        "max_separation_error_km": jnp.max(error) / 1e3,
    }
