"""From scenarios to what ``simulate`` reads: the controller, the ``Params`` of each sample, the shared arrays.

A batch is a list of scenarios (a sweep's grid points, or one scenario) that
differ only in array leaves: ``prepare`` checks that what sets the compiled
loop's structure (epoch, step, duration, dynamics, controller kind and its
static settings) is the same for all of them, builds each scenario's
``Params`` and stacks them, and computes what the batch shares once: the
environment grid (Sun, Moon, Earth angle at every RK4 stage) and, for a
controller that reads it, the uncontrolled reference (the same loop with the
null controller, ``reference``), in segments re-started from the station
every ``REFERENCE_SEGMENT_CYCLES`` cycles (``control.predictor`` says why).
When the scenarios differ in what the reference depends on (initial state,
mass, force model), each sample runs its own reference inside the batch
(``Batch.reference_per_sample``).
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax import compilation, nominal_errors, traced
from geojax.physics.constants import SIDEREAL_DAY_S
from geojax.control import lookup, recovery, none
from geojax.control.base import Controller
from geojax.control.predictor import Reference, station_mee
from geojax.physics.dynamics import SpacecraftState
from geojax.physics.elements import cartesian_to_mee, mee_to_cartesian, wrap_angle
from geojax.physics.forces import Environment
from geojax.physics.frames import ecef_to_eci
from geojax.loop.simulate import Shared, simulate
from geojax.params import LEAF_TABLES, Params, static_settings, table_leaves
from geojax.physics.propagate import (DYNAMICS, Dynamics, cycle_count, environment_grid, environment_shape,
                                      for_one_sample, steps_per_cycle)
from geojax.scenario import SCHEMA, Scenario, controller_fields
from geojax import states as parts


# Cycles between re-starts of the predictor's reference from the station's nominal state (``control.predictor``).
# Measured (studies/longrun/results/predictor_reference.md, segment_length.md): never re-started, the third year
# of a QFFC run from 2020 costs 6.8 % more than the same year flown fresh (FOMPC 7.9 %); re-started every 30
# cycles, within 0.1 %, and the reference's inclination stays within 0.1 deg of the station's.  Every 10 cycles
# gives the same within 0.6 %; every 91 or 366 leaves some of the within-year drift (2022 flown fresh costs 3 %
# more at 366).
REFERENCE_SEGMENT_CYCLES = 30


class Segments(NamedTuple):
    """Where the uncontrolled reference runs (leading axis = segment), and where each control cycle reads it."""

    env: Environment  # leaves [n_segments, segment_cycles + width - 1, n_steps, 3, ...]: each segment's cycles
    segment: jnp.ndarray  # [n_cycles] int, the segment cycle k reads
    offset: jnp.ndarray  # [n_cycles] int, cycle k's start boundary within that segment


def cycle_slots(n_cycles: int) -> int:
    """The cycles a loop of ``n_cycles`` is compiled for: the least of 32, 48, 64, 96, 128, 192, ... (a power of
    two or one and a half times one) that holds them.  The cycles beyond ``n_cycles`` are skipped at run time
    (``Shared.n_active``), so every duration within a slot count runs one compiled program (10 and 30 days: 32
    slots; a year, 366 cycles: 384), at most a third more slots than cycles from 32 cycles up."""
    slots = 32
    while slots < n_cycles:
        slots = slots * 3 // 2 if slots & (slots - 1) == 0 else slots * 4 // 3
    return slots


class Batch(NamedTuple):
    """Everything the rollouts of a batch of scenarios need (``params`` leaves: [n_scenarios, ...])."""

    controller: Controller
    params: Params
    shared: Shared
    step_s: float  # the step actually used: a whole number of steps per sidereal day
    dynamics: Dynamics
    n_cycles: int  # the run's cycles; ``shared.env`` may hold more (``cycle_slots``), skipped at run time
    reference_env: Segments | None  # where the reference runs; None for a controller that reads none
    reference_per_sample: bool  # each sample runs its own reference (its initial state or forces differ)
    states: tuple = ()  # the further states the loop carries (``geojax.states.of_config``), static
    # With ``prepare(own_references=True)`` and references that differ: each sample's reference [n, ...], computed
    # before the loop by the program a batch of one reference shares (``distinct_references``); else None
    references: Reference | None = None


def params_of(sc: Scenario, controller: Controller, extra: tuple = ()) -> Params:
    """The ``Params`` of one scenario: every leaf declared by a ``Field.si`` of its tables, SI units, and the
    leaves of each part it carries (``extra``: a user's own parts beside the scenario's)."""
    cfg = sc.config
    dynamics = DYNAMICS[sc.dynamics]
    fm = jax.tree_util.tree_map(jnp.asarray, sc.force_model)
    orbit = dynamics.from_mee(jnp.asarray(sc.initial_mee), fm.mu_m3_s2)
    initial = SpacecraftState(orbit, jnp.asarray(sc.mass_kg), jnp.asarray(0.0))
    fields = {t: SCHEMA[t] for t in LEAF_TABLES if t != "controller"}
    fields["controller"] = controller.fields
    leaves = {t: table_leaves(cfg[t], fields[t]) for t in LEAF_TABLES}
    leaves["errors"].update(nominal_errors.leaves(cfg["errors"]))  # each error's size, its preset converted
    return Params(initial, fm, **leaves, states=parts.leaves_of(cfg, extra))


def controller_of(scenarios: list[Scenario]) -> Controller:
    """The registered controller of ``controller.kind``, built for every scenario's ``[controller]`` table."""
    kinds = {sc.controller for sc in scenarios}
    if len(kinds) > 1:
        raise ValueError(f"controller.kind: one per batch, got {sorted(kinds)}")
    tables = [sc.config["controller"] for sc in scenarios]
    if len({table.get("recovery", False) for table in tables}) > 1:
        raise ValueError("controller.recovery: sets the compiled controller; one value per batch")
    controller = lookup(kinds.pop()).make(tables)
    return recovery.with_recovery(controller) if tables[0].get("recovery", False) else controller


def prepare(scenarios: list[Scenario], controller: Controller | None = None,
            segment_cycles: int = REFERENCE_SEGMENT_CYCLES, pad: bool = False, on_shapes=None,
            one_sample: bool = False, states: tuple = (), slots=None, shapes_only: bool = False,
            own_references: bool = False) -> Batch:
    """The ``Batch`` of ``scenarios`` (``controller``: a user's, else the registered one of their kind).

    ``segment_cycles``: cycles between re-starts of the predictor's reference (``REFERENCE_SEGMENT_CYCLES``).
    ``pad``: compile the loop for ``cycle_slots(n_cycles)`` cycles and run ``n_cycles`` of them
    (``Shared.n_active``), so that other durations reuse the compiled programs; the records then hold the
    slots (zero beyond ``n_cycles``), the numbers of the run's cycles bit-for-bit those of a loop compiled for
    exactly ``n_cycles``.

    ``on_shapes(batch)``: called before the environment grid and the reference are computed (a few seconds of
    their own compilation) with the ``Batch`` whose ``shared`` and ``reference_env`` leaves are their shapes
    (``jax.ShapeDtypeStruct``), the rest as returned: enough to compile the closed loop meanwhile
    (``rollout.simulate_batch`` does, in a thread: XLA compiles one program on one core).  What ``on_shapes``
    returns, if not None, is called before the reference is traced: tracing is Python, one thread at a time, and
    the closed loop's tracing comes first (its compilation is the longest wait; the reference compiles meanwhile).
    ``states``: a user's own parts (``StateModel`` s or ``Part`` s) carried beside the scenario's.
    ``one_sample``: the batch is one sample's (``simulate``), whose reference is compiled for start-up rather than
    run speed (``reference(sequential=True)`` with ``compilation.ONE_SAMPLE_OPTIONS``).
    ``shapes_only``: return that ``Batch`` of shapes at once (what ``runner.rollout.record_bytes_per_cycle``
    traces), computing nothing.
    ``own_references``: where the samples' references differ, compute each distinct one (at most
    ``DISTINCT_REFERENCES``) before the loop with the program that computes a batch's shared reference, so that a
    sample's numbers do not depend on the batch it flies in (``Batch.references``); else the loop computes them.
    ``slots(layout, n_slots)``, with ``pad``: the slot count to compile for instead of ``n_slots``
    (``cycle_slots(n_cycles)``), given ``layout(count)``, the ``Batch`` of shapes (as ``on_shapes`` gets it) for a
    loop of ``count`` slots: a larger one already compiled serves the run as well (``rollout.simulate_batch``).
    """
    controller = controller_of(scenarios) if controller is None else controller
    first = scenarios[0]
    _check_static(scenarios, controller)
    n_steps = steps_per_cycle(first.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    n_cycles = cycle_count(first.days)
    n_slots = cycle_slots(n_cycles) if pad else n_cycles
    dynamics = DYNAMICS[first.dynamics]
    params = [params_of(sc, controller, states) for sc in scenarios]
    stacked = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *params)
    width = controller.reference_cycles
    segment_cycles = min(segment_cycles, n_cycles)
    n_env = environment_cycles(n_cycles, width, segment_cycles)
    grid = (first.epoch_tt_s, first.epoch_tt_s, first.tt_minus_ut1_s, step_s, n_env, n_steps)
    per_sample = width > 0 and _references_differ(params)
    distinct = _distinct_references(params) if per_sample and own_references else None
    on_segments = functools.partial(reference_segments, n_cycles=n_cycles, width=width, segment_cycles=segment_cycles)
    batch = functools.partial(Batch, controller, stacked, step_s=step_s, dynamics=dynamics, n_cycles=n_cycles,
                              reference_per_sample=per_sample, states=parts.of_config(first.config, states))

    @functools.cache
    def layout(count: int | None) -> Batch:  # the batch's shapes for a loop of ``count`` slots
        env = environment_shape(*grid)
        ref = reference_shape(n_cycles, width, env.earth_angle_rad.dtype) if width and not per_sample else None
        shared = jax.eval_shape(functools.partial(_shared, n_cycles=n_cycles, n_slots=count), env, ref)
        own = None
        if distinct is not None:  # each sample's, as the shared one's program pads it
            one = jax.eval_shape(functools.partial(_shared, n_cycles=n_cycles, n_slots=count), env,
                                 reference_shape(n_cycles, width, env.earth_angle_rad.dtype)).reference
            own = jax.tree_util.tree_map(lambda x: jax.ShapeDtypeStruct((len(scenarios), *x.shape), x.dtype), one)
        return batch(shared, reference_env=jax.eval_shape(on_segments, env) if width else None, references=own)

    if pad and slots is not None:
        n_slots = slots(layout, n_slots)
    sharing = functools.partial(_shared, n_cycles=n_cycles, n_slots=n_slots if pad else None)
    if shapes_only:
        return layout(n_slots if pad else None)
    before_reference = None
    if on_shapes is not None:
        before_reference = on_shapes(layout(n_slots if pad else None))
    env = environment_grid(*grid, first.config["forces"]["ephemeris"])
    segments = on_segments(env) if width else None
    def shared_reference(p: Params) -> Reference:  # the reference a batch of samples like ``p`` shares
        identity = program_identity(first, "reference", step_s, width, one_sample)
        return traced.call(_REFERENCE_JIT[one_sample], "reference", identity, p, segments,
                           compiler_options=compilation.ONE_SAMPLE_OPTIONS if one_sample else None, step_s=step_s,
                           dynamics=for_one_sample(dynamics) if one_sample else dynamics, width=width)

    ref = own = None
    if width and (not per_sample or distinct is not None) and before_reference is not None:
        before_reference()
    if width and not per_sample:
        ref = shared_reference(params[0])
    if distinct is not None:
        computed = [sharing(env, shared_reference(params[k])).reference for k in sorted(set(distinct))]
        by_first = dict(zip(sorted(set(distinct)), computed))
        own = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *(by_first[k] for k in distinct))
    return batch(sharing(env, ref), reference_env=segments, references=own)


def environment_cycles(n_cycles: int, width: int, segment_cycles: int = REFERENCE_SEGMENT_CYCLES) -> int:
    """The cycles of the environment grid ``prepare`` computes for a run of ``n_cycles``: the run's, and for a
    controller that reads ``width`` reference boundaries the last reference segment's (``reference_segments``)."""
    segment_cycles = min(segment_cycles, n_cycles)
    n_segments = -(-n_cycles // segment_cycles)
    return max(n_cycles, n_segments * segment_cycles + width - 1) if width else n_cycles


@functools.partial(jax.jit, static_argnames=("n_cycles", "n_slots"))  # one small program, not ~10 eager ones
def _shared(env, ref, n_cycles: int, n_slots: int | None) -> Shared:
    """What the samples share: the environment of the run's ``n_cycles`` and the reference (with ``n_slots``:
    repeated into the slots the loop skips, and ``Shared.n_active``)."""
    cycles_env = jax.tree_util.tree_map(lambda x: x[:n_cycles], env)
    if n_slots is None:
        return Shared(cycles_env, ref)
    # The environment and the reference are computed for the run's cycles (small programs;
    # their values at other lengths differ in the last bit, XLA's vector and scalar loops), then repeated into
    # the slots the loop skips.
    return Shared(*padded((cycles_env, ref), n_slots), jnp.asarray(n_cycles, jnp.int32))


def reference_shape(n_cycles: int, width: int, dtype) -> Reference:
    """The shapes ``reference`` returns for a run of ``n_cycles`` (known without tracing it, ~2 s on a CPU)."""
    return Reference(jax.ShapeDtypeStruct((n_cycles, 6), dtype), jax.ShapeDtypeStruct((n_cycles, width, 7), dtype))


def padded(tree, n_slots: int):
    """``tree``'s leaves [n, ...] with their last row repeated to [n_slots, ...]."""
    return jax.tree_util.tree_map(
        lambda x: jnp.concatenate([x, jnp.repeat(x[-1:], n_slots - x.shape[0], axis=0)]), tree)


@functools.partial(jax.jit, static_argnames=("n_cycles", "width", "segment_cycles"))
def reference_segments(env, n_cycles: int, width: int, segment_cycles: int) -> Segments:
    """The reference's segments over an environment grid ``env`` (leaves [n_env, ...], n_env at least
    ceil(n_cycles / segment_cycles) x segment_cycles + width - 1): segment s starts at cycle s x segment_cycles
    and runs segment_cycles + width - 1 cycles, so that its last cycle's controller reads ``width`` boundaries
    of it."""
    cycle = np.arange(n_cycles)
    starts = np.arange(0, n_cycles, segment_cycles)
    index = starts[:, None] + np.arange(segment_cycles + width - 1)[None, :]
    return Segments(jax.tree_util.tree_map(lambda x: x[index], env), jnp.asarray(cycle // segment_cycles),
                    jnp.asarray(cycle % segment_cycles))


def reference_per_sample(scenarios: list[Scenario], controller: Controller) -> bool:
    """Whether a batch of ``scenarios`` runs one predictor reference per sample (``Batch.reference_per_sample``),
    without preparing it."""
    return controller.reference_cycles > 0 and _references_differ([params_of(sc, controller) for sc in scenarios])


# The most distinct references a batch computes before its loop (``prepare(own_references=True)``); a batch with
# more (a Monte Carlo of dispersed initial states: every sample its own) computes them inside the loop.
DISTINCT_REFERENCES = 64


def _distinct_references(params: list[Params]) -> list[int] | None:
    """For each sample the index of the first sample whose reference inputs it shares; None where there are more
    than ``DISTINCT_REFERENCES`` distinct ones."""
    firsts: list[int] = []
    out = []
    for p in params:
        match = next((k for k in firsts if _same(_reference_inputs(p), _reference_inputs(params[k]))), None)
        if match is None:
            if len(firsts) == DISTINCT_REFERENCES:
                return None
            firsts.append(len(out))
            match = len(out)
        out.append(match)
    return out


def _references_differ(params: list[Params]) -> bool:
    return not all(_same(_reference_inputs(p), _reference_inputs(params[0])) for p in params[1:])


def _reference_inputs(params: Params):
    """What the reference depends on: the initial state, the forces, the station's nominal orbit."""
    return params.initial, params.forces, [params.station[k] for k in ("lon_rad", "ex", "ey", "ix", "iy")]


def _same(a, b) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)))


def static_keys(schema: dict) -> dict:
    """{dotted key: the scenario's identity of it} of every static ``Field`` of ``schema``'s tables but the
    controller's (whose static keys its own fields declare, ``_check_static``): what fixes the compiled loop's
    shapes and code, declared on the fields alone."""
    return {f"{table}.{key}" if table else key:
            (lambda sc, table=table, key=key, field=field:
             field.identity_of((sc.config[table] if table else sc.config)[key]))
            for table, fields in schema.items() if table != "controller"
            for key, field in fields.items() if field.static}


STATIC_KEYS = static_keys(SCHEMA)


def program_identity(sc: Scenario, *settings) -> tuple:
    """What, beside the arguments' shapes, fixes a traced program of ``sc`` (``geojax.traced``): the keys of
    ``STATIC_KEYS`` but the duration and the epoch, whose values reach the programs as arguments (the environment
    grid, the cycle count, shapes of their own), and the caller's ``settings`` (controller, lanes, ...)."""
    return (*settings, *(value(sc) for key, value in STATIC_KEYS.items()
                         if key not in ("duration.days", "epoch.utc", "epoch.ut1_minus_utc_s")))


def _check_static(scenarios: list[Scenario], controller: Controller, skip: tuple[str, ...] = ()) -> None:
    """``ValueError`` naming the first key of ``STATIC_KEYS`` (but ``skip``) or of the controller's static
    settings whose value differs between ``scenarios``."""
    for key, value in STATIC_KEYS.items():
        if key in skip:
            continue
        values = {value(sc) for sc in scenarios}
        if len(values) > 1:
            raise ValueError(f"{key}: sets the shape of the compiled loop; one value per batch (run one sweep per value)")
    fields = controller.fields or controller_fields(scenarios[0].config["controller"])
    settings = [static_settings(sc.config["controller"], fields) for sc in scenarios]
    for key in settings[0]:
        if len({repr(s[key]) for s in settings}) > 1:
            raise ValueError(f"controller.{key}: sets the compiled controller; one value per batch")


def reference(params: Params, segments: Segments, step_s: float, dynamics: Dynamics, width: int,
              sequential: bool = False) -> Reference:
    """The predictor's reference (Li 2022 eqs. (24)-(27)) of one sample: what each cycle reads of the
    uncontrolled ``segments``, the first started from the sample's initial state, each later one from the
    station's nominal state at its start (``predictor.station_mee``, the initial state's semi-latus rectum).

    The segments run side by side (``vmap``), or with ``sequential`` one after another (``lax.map``: a program
    that traces and compiles in half the time and runs 2-3x longer; the same numbers to rounding)."""
    mu = params.forces.mu_m3_s2
    p_m = dynamics.to_mee(params.initial.orbit, mu)[0]
    start_angle_rad = segments.env.earth_angle_rad[:, 0, 0, 0]
    anchors = jax.vmap(lambda angle: dynamics.from_mee(station_mee(params.station, p_m, angle), mu))(start_angle_rad)
    orbits = anchors.at[0].set(params.initial.orbit)
    def segment(orbit, env):
        return uncontrolled_boundaries(params._replace(initial=params.initial._replace(orbit=orbit)), env, step_s,
                                       dynamics)

    if sequential:
        osc, mean = jax.lax.map(lambda xs: segment(*xs), (orbits, segments.env))
    else:
        osc, mean = jax.vmap(segment)(orbits, segments.env)
    s, j = segments.segment, segments.offset
    return Reference(osc[s, j], mean[s[:, None], j[:, None] + jnp.arange(width)[None, :]])


def uncontrolled_boundaries(params: Params, env, step_s: float, dynamics: Dynamics):
    """One uncontrolled run of a sample over the cycles of ``env`` (the closed loop with the null controller):
    at each cycle boundary but the last, the osculating (lon, a, f, g, h, k) [n, 6]
    (``predictor.boundary_elements``) and the mean (lon, drift, a, f, g, h, k) [n, 7]."""
    _, records = simulate(none.CONTROLLER, params, Shared(env, None), jax.random.key(0), step_s=step_s,
                          dynamics=dynamics)
    m = records.cycles.means
    mid = jnp.stack([m.lon_rad, m.drift_rad_s, m.a_m, m.ex, m.ey, m.ix, m.iy], axis=-1)
    mid = mid.at[:, 0].set(jnp.unwrap(mid[:, 0]))
    # Boundary means: the average of the two cycle means around a boundary (extrapolated at the first).
    first = 1.5 * mid[0] - 0.5 * mid[1]
    boundary = jnp.concatenate([first[None], 0.5 * (mid[:-1] + mid[1:])], 0)
    return records.cycles.boundary, boundary.at[:, 0].set(wrap_angle(boundary[:, 0]))


# {one_sample: the reference's jitted program} (``prepare``)
_REFERENCE_STATIC = ("step_s", "dynamics", "width")
_REFERENCE_JIT = {False: jax.jit(reference, static_argnames=_REFERENCE_STATIC),
                  True: jax.jit(functools.partial(reference, sequential=True), static_argnames=_REFERENCE_STATIC,
                                compiler_options=compilation.ONE_SAMPLE_OPTIONS)}


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

