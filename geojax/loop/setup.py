"""From scenarios to what ``simulate`` reads: the controller, the ``Params`` of each sample, the shared arrays.

A batch is a list of scenarios (a sweep's grid points, or one scenario) that
differ only in array leaves: ``prepare`` checks that what sets the compiled
loop's structure (epoch, step, duration, dynamics, controller kind and its
static settings) is the same for all of them, builds each scenario's
``Params`` and stacks them, and computes what the batch shares once: the
environment grid (Sun, Moon, Earth angle at every RK4 stage) and, for a
controller that reads it, the uncontrolled reference (the same loop with the
null controller, ``reference``).  When the scenarios differ in what the
reference depends on (initial state, mass, force model), each sample runs its
own reference inside the batch (``Batch.reference_per_sample``).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.physics.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S
from geojax.control import REGISTRY, none
from geojax.control.base import Controller
from geojax.control.predictor import Reference
from geojax.physics.dynamics import SpacecraftState
from geojax.physics.elements import cartesian_to_mee, mee_to_cartesian, wrap_angle
from geojax.physics.frames import ecef_to_eci
from geojax.loop.simulate import Shared, simulate
from geojax.params import LEAF_TABLES, Params, static_settings, table_leaves
from geojax.physics.propagate import DYNAMICS, Dynamics, environment_grid, steps_per_cycle
from geojax.scenario import SCHEMA, Scenario, controller_fields


class Batch(NamedTuple):
    """Everything the rollouts of a batch of scenarios need (``params`` leaves: [n_scenarios, ...])."""

    controller: Controller
    params: Params
    shared: Shared
    step_s: float  # the step actually used: a whole number of steps per sidereal day
    dynamics: Dynamics
    n_cycles: int
    reference_env: object  # Environment of the reference run ([n_cycles + reference_cycles - 1] cycles), or None
    reference_per_sample: bool  # each sample runs its own reference (its initial state or forces differ)


def cycle_count(days: float) -> int:
    """Control cycles (sidereal days) of a closed-loop run of ``days`` solar days."""
    return max(1, round(days * SECONDS_PER_DAY / SIDEREAL_DAY_S))


def params_of(sc: Scenario, controller: Controller) -> Params:
    """The ``Params`` of one scenario: every leaf declared by a ``Field.si`` of its tables, SI units."""
    cfg = sc.config
    dynamics = DYNAMICS[sc.dynamics]
    fm = jax.tree_util.tree_map(jnp.asarray, sc.force_model)
    orbit = dynamics.from_mee(jnp.asarray(sc.initial_mee), fm.mu_m3_s2)
    initial = SpacecraftState(orbit, jnp.asarray(sc.mass_kg), jnp.asarray(0.0))
    fields = {t: SCHEMA[t] for t in LEAF_TABLES if t != "controller"}
    fields["controller"] = controller.fields
    leaves = {t: table_leaves(cfg[t], fields[t]) for t in LEAF_TABLES}
    return Params(initial, fm, **leaves)


def controller_of(scenarios: list[Scenario]) -> Controller:
    """The registered controller of ``controller.kind``, built for every scenario's ``[controller]`` table."""
    kinds = {sc.controller for sc in scenarios}
    if len(kinds) > 1:
        raise ValueError(f"controller.kind: one per batch, got {sorted(kinds)}")
    return REGISTRY[kinds.pop()].make([sc.config["controller"] for sc in scenarios])


def prepare(scenarios: list[Scenario], controller: Controller | None = None, reference_pad: int = 0) -> Batch:
    """The ``Batch`` of ``scenarios`` (``controller``: a user's, else the registered one of their kind).

    ``reference_pad`` extra reference cycles (a caller that reads the reference beyond the run).
    """
    controller = controller_of(scenarios) if controller is None else controller
    first = scenarios[0]
    _check_static(scenarios, controller)
    n_steps = steps_per_cycle(first.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    n_cycles = cycle_count(first.days)
    dynamics = DYNAMICS[first.dynamics]
    params = [params_of(sc, controller) for sc in scenarios]
    stacked = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *params)
    width = controller.reference_cycles
    n_env = n_cycles + max(width - 1, 0) + reference_pad
    env = environment_grid(first.epoch_tt_s, first.epoch_tt_s, first.tt_minus_ut1_s, step_s, n_env, n_steps,
                           first.config["forces"]["ephemeris"])
    cycles_env = jax.tree_util.tree_map(lambda x: x[:n_cycles], env)
    per_sample = width > 0 and not all(_same((p.initial, p.forces), (params[0].initial, params[0].forces))
                                       for p in params[1:])
    ref = None
    if width and not per_sample:
        ref = _reference_jit(params[0], env, step_s=step_s, dynamics=dynamics)
    return Batch(controller, stacked, Shared(cycles_env, ref), step_s, dynamics, n_cycles,
                 env if width else None, per_sample)


def _same(a, b) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)))


# What fixes the compiled loop's shapes and code, named by the key a user would sweep.
STATIC_KEYS = {"integration.step_s": lambda sc: steps_per_cycle(sc.step_s), "duration.days": lambda sc: cycle_count(sc.days),
               "integration.dynamics": lambda sc: sc.dynamics, "epoch.utc": lambda sc: sc.epoch_tt_s,
               "epoch.ut1_minus_utc_s": lambda sc: sc.tt_minus_ut1_s,
               "forces.gravity_degree": lambda sc: (sc.config["forces"]["gravity_degree"],
                                                    sc.config["forces"]["gravity_order"]),
               "forces.moon_shadow": lambda sc: sc.config["forces"]["moon_shadow"],
               "forces.ephemeris": lambda sc: sc.config["forces"]["ephemeris"]}


def _check_static(scenarios: list[Scenario], controller: Controller) -> None:
    for key, value in STATIC_KEYS.items():
        values = {value(sc) for sc in scenarios}
        if len(values) > 1:
            raise ValueError(f"{key}: sets the shape of the compiled loop; one value per batch (run one sweep per value)")
    fields = controller.fields or controller_fields(scenarios[0].config["controller"])
    settings = [static_settings(sc.config["controller"], fields) for sc in scenarios]
    for key in settings[0]:
        if len({repr(s[key]) for s in settings}) > 1:
            raise ValueError(f"controller.{key}: sets the compiled controller; one value per batch")


def reference(params: Params, env, step_s: float, dynamics: Dynamics) -> Reference:
    """The uncontrolled reference (Li 2022 eqs. (24)-(27)) of one sample over the cycles of ``env``:
    the closed loop with the null controller; elements at each cycle boundary but the last."""
    _, records = simulate(none.CONTROLLER, params, Shared(env, None), jax.random.key(0), step_s=step_s,
                          dynamics=dynamics)
    m = records.cycles.means
    mid = jnp.stack([m.lon_rad, m.drift_rad_s, m.a_m, m.ex, m.ey, m.ix, m.iy], axis=-1)
    mid = mid.at[:, 0].set(jnp.unwrap(mid[:, 0]))
    # Boundary means: the average of the two cycle means around a boundary (extrapolated at the first).
    first = 1.5 * mid[0] - 0.5 * mid[1]
    boundary = jnp.concatenate([first[None], 0.5 * (mid[:-1] + mid[1:])], 0)
    return Reference(records.cycles.boundary, boundary.at[:, 0].set(wrap_angle(boundary[:, 0])))


_reference_jit = jax.jit(reference, static_argnames=("step_s", "dynamics"))


def disperse(params: Params, key, sigma_mee, sigma_offset_ecef_m, earth_angle_rad, dynamics: Dynamics) -> Params:
    """``params`` with its initial orbit dispersed (Monte Carlo): Gaussian errors of 1-sigma ``sigma_mee`` [6]
    on the MEE elements (p m, f, g, h, k, L rad) and ``sigma_offset_ecef_m`` [3] on the ECEF position."""
    mu = params.forces.mu_m3_s2
    noise = jax.random.normal(key, (9,))
    mee = dynamics.to_mee(params.initial.orbit, mu) + sigma_mee * noise[:6]
    r, v = mee_to_cartesian(mee, mu)
    r = r + ecef_to_eci(sigma_offset_ecef_m * noise[6:], earth_angle_rad)
    orbit = dynamics.from_mee(cartesian_to_mee(r, v, mu), mu)
    return params._replace(initial=params.initial._replace(orbit=orbit))


def unstack(params: Params, index: int) -> Params:
    return jax.tree_util.tree_map(lambda x: x[index], params)

