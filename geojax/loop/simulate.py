"""One closed loop for every controller (docs/design.md: the engine).

``simulate`` is an outer ``lax.scan`` over control cycles (one sidereal day
each, ``jax.checkpoint``ed, so reverse-mode memory grows with cycles, not
steps) around an inner ``lax.scan`` over RK4 steps (each checkpointed too).
Every closed loop runs through it, and so do uncontrolled propagation and the
predictor's reference run (the null controller, ``control.none``).

Per cycle, at its start:

1. the orbit-determination fix: Li 2022's Gaussian fix (``navigation.fix``, drawn from ``key_k = fold_in(key,
   k)``) unless a part navigates (``StateModel.navigates``: the navigation filter);
2. the estimate: the fix, and for a controller that asks for the shared
   reference (``reference_cycles > 0``) the mean elements of Li 2022 eqs.
   (24)-(27) (``control.predictor``);
3. ``controller.plan`` with ``key_k`` (a controller draws its own noise from it:
   ``control.burns`` takes row 1 for attitude errors, the FOMPC ``fold_in(key_k, 1)``).

Then per step ``controller.thrust`` gives the thrust held over the step, and
the loop records, from the true state at each step start, the osculating
sub-satellite point relative to the station and the delivered acceleration.
A cycle's record (``CycleRecord``) holds the one-cycle mean elements (Li 2022
eq. (9)), the boundary elements the reference needs, the Delta-V delivered,
the extremes of the step records (so box checks cover every step without
keeping the steps) and the controller's own records.  Per-step records are
kept only on request (``keep_steps``).

Beyond the orbit and the mass the loop carries the spacecraft's further states (``geojax.states``: the wheels'
momentum, the navigation filter), one extension point: ``states`` is a static tuple of ``StateModel`` s whose states
ride in the carry (a dict by name), updated after each orbit step (``StateModel.step``) and at each cycle start
(``StateModel.cycle``), and which may change the thrust flown over a step (``StateModel.thrust``: the wheels'
dumping tilt) or what the controller is told at a cycle start (``StateModel.estimate``: the measured wheel momentum,
the navigation filter's estimate in place of the fix), with records in ``CycleRecord.states`` and
``StepRecord.states``. With none, every dict is empty: no leaf, the same program and numbers.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control.base import Controller, Estimate
from geojax.control.predictor import Reference, boundary_elements, estimate_mean
from geojax.navigation.fix import fix_mee
from geojax.physics.dynamics import SpacecraftState
from geojax.physics.elements import mee_to_cartesian, semi_major_axis_m, wrap_angle
from geojax.physics.forces import Environment, ForceModel
from geojax.physics.frames import latitude_rad, rsw_to_eci_xyz, subsatellite_lon_tan_lat_xyz
from geojax.physics.fusion import materialized
from geojax.physics.integrate import rk4_step
from geojax.params import Params
from geojax.physics.propagate import MEE, CycleMeans, Dynamics, cycle_means
from geojax.states.base import CycleStart, StateModel, StepContext, ThrustContext, check_streams, stream_id

# A component of the delivered acceleration counts as firing when it exceeds this fraction of the
# acceleration's norm: the RSW -> ECEF rotations leave ~1e-16 of it on an axis a law did not fire.
FIRING_COMPONENT_RTOL = 1e-9


class CycleContext(NamedTuple):
    """What the loop tells a controller about the cycle it plans (shared by the batch but ``force_model``)."""

    index: jnp.ndarray  # [] int, cycle number from 0
    t_s: jnp.ndarray  # [] cycle start, s since the start of the run
    cycle_s: float  # cycle length (n_steps x step_s)
    step_s: float
    env: Environment  # the cycle's environment at every RK4 stage, leaves [n_steps, 3, ...]
    reference: jnp.ndarray  # [reference_cycles, 7] uncontrolled mean (lon, drift, a, f, g, h, k) at boundaries k, k+1, ...
    force_model: ForceModel


class StepEnvironment(NamedTuple):
    """What the loop tells ``thrust`` about a step."""

    env: Environment  # at the step's three RK4 stage times (start, middle, end)
    step_s: float
    index: jnp.ndarray  # [] int, step number within the cycle
    r_eci_m: jnp.ndarray  # [3] true position at the step start
    v_eci_mps: jnp.ndarray  # [3] true velocity at the step start


class CycleRecord(NamedTuple):
    """Per cycle (leading axis: cycle)."""

    means: CycleMeans  # one-cycle mean elements
    boundary: jnp.ndarray  # [6] true (lon, a, f, g, h, k) at the cycle start (``predictor.boundary_elements``)
    dv_mps: jnp.ndarray  # [] Delta-V delivered in the cycle
    dlon_min_rad: jnp.ndarray  # extremes over the cycle's step starts of the osculating sub-satellite
    dlon_max_rad: jnp.ndarray  # longitude less the station's, wrapped
    dlon_sum_rad: jnp.ndarray
    lat_min_rad: jnp.ndarray  # and of the geocentric latitude
    lat_max_rad: jnp.ndarray
    firing_steps: jnp.ndarray  # [3] steps whose delivered acceleration has an ECEF x, y, z component
    controller: dict  # ``controller.record(plan)``
    states: dict  # {name: ``StateModel.summary``} of each further state the loop carries (``geojax.states``)


class StepRecord(NamedTuple):
    """Per step (leading axes [cycle, step]): at the step start, and the acceleration held over the step."""

    lon_rad: jnp.ndarray  # geocentric sub-satellite longitude
    lat_rad: jnp.ndarray  # geocentric sub-satellite latitude
    accel_ecef_mps2: jnp.ndarray  # [..., 3] delivered thrust acceleration, ECEF axes
    states: dict  # {name: step record} of each further state the loop carries


class Records(NamedTuple):
    cycles: CycleRecord
    steps: StepRecord | None


class Shared(NamedTuple):
    """Arrays every sample of a batch shares (computed once per scenario)."""

    env: Environment  # leaves [n_cycles, n_steps, 3, ...]
    reference: Reference | None  # for n_cycles or more, reference_cycles boundaries or more; None if unused
    # [] int: run the first n_active cycles of ``env`` only (the loop compiled for more, ``runner.setup.cycle_slots``,
    # so that other durations reuse it); None: all of them
    n_active: jnp.ndarray | None = None


class Positions(NamedTuple):
    """A cycle's true positions and velocities (ECI, m and m/s), what a cluster's separations are computed from
    (``loop.cluster``), and the position the controller was told at the cycle start."""

    steps_rv: jnp.ndarray  # [n_steps, 6] at every step start
    end_rv: jnp.ndarray  # [6] at the cycle's end
    estimated_r: jnp.ndarray  # [3] the estimate's position at the cycle start (the fix, or a filter's)


def simulate(controller: Controller, params: Params, shared: Shared, key, *, step_s: float,
             dynamics: Dynamics = MEE, keep_steps: bool = False, states: tuple[StateModel, ...] = ()):
    """Closed loop over the cycles of ``shared.env``; returns (final ``SpacecraftState``, ``Records``).

    Pure: vmap it over ``params`` and ``key`` for a batch, differentiate it with respect to ``params``.
    ``controller``, ``step_s``, ``dynamics``, ``keep_steps`` and ``states`` (the further states carried,
    ``geojax.states``) are static.
    """
    xs = cycle_inputs(controller, shared)
    body = jax.checkpoint(cycle_body(controller, params, key, step_s=step_s, dynamics=dynamics,
                                     keep_steps=keep_steps, states=states))
    carry = initial_carry(controller, params, shared.env, xs[3][0], dynamics, step_s, states)
    if shared.n_active is None:
        (final, _, _), (cycles, steps) = jax.lax.scan(body, carry, xs)
    else:
        (final, _, _), (cycles, steps) = _scan_first(body, carry, xs, shared.n_active)
    return final, Records(cycles, steps)


def cycle_inputs(controller: Controller, shared: Shared):
    """What the cycle scan runs over: (cycle index, environment, the reference's osculating elements and
    window), leading axis cycle (a reference with a leading satellite axis keeps it after the cycle's)."""
    env = shared.env
    n_cycles = env.earth_angle_rad.shape[0]
    width = controller.reference_cycles
    if not width:
        return jnp.arange(n_cycles), env, jnp.zeros((n_cycles, 6)), jnp.zeros((n_cycles, 0, 7))
    window = None if shared.reference is None else shared.reference.window
    have = (0, 0) if window is None else window.shape[-3:-1]
    if have[0] < n_cycles or have[1] < width:
        raise ValueError(f"reference: the controller reads {width} boundaries per cycle for {n_cycles} cycles, "
                         f"got {have[1]} for {have[0]}")
    if window.ndim == 4:  # [satellite, cycle, ...] -> [cycle, satellite, ...]
        return (jnp.arange(n_cycles), env, jnp.swapaxes(shared.reference.osc[:, :n_cycles], 0, 1),
                jnp.swapaxes(window[:, :n_cycles, :width], 0, 1))
    return jnp.arange(n_cycles), env, shared.reference.osc[:n_cycles], window[:n_cycles, :width]


def initial_carry(controller: Controller, params: Params, env: Environment, window, dynamics: Dynamics,
                  step_s: float, states: tuple[StateModel, ...] = ()):
    """The loop's carry at the run's start: (spacecraft state, controller state, {part: state})."""
    check_streams(states)
    n_steps = env.earth_angle_rad.shape[1]
    fm = params.forces
    first_env = jax.tree_util.tree_map(lambda x: x[0], env)
    cycle_s = n_steps * step_s
    initial_state = controller.init(params, CycleContext(jnp.asarray(0), jnp.asarray(0) * cycle_s, cycle_s, step_s,
                                                         first_env, window, fm))
    # A controller's state that starts as constants (the FOMPC's warm start) becomes per sample in the loop: under
    # vmap it starts as per-sample zeros added (x + 0 = x), so that vmap batches the cycle once, not once to find
    # that and again (the FOMPC's 32-lane loop traced in 7.1-7.5 s instead of 8.7; see the step sums' zero below).
    anchor = 0.0 * params.initial.orbit[0]
    initial_state = jax.tree_util.tree_map(
        lambda x: x + anchor.astype(x.dtype) if jnp.issubdtype(x.dtype, jnp.floating) else x, initial_state)
    r0, v0 = position_velocity(dynamics, params.initial.orbit, fm.mu_m3_s2) if states else (None, None)
    env0 = jax.tree_util.tree_map(lambda x: x[0, 0, 0], env) if states else None  # the run's first instant
    return params.initial, initial_state, {m.name: m.init(params, r0, v0, env0, fm) for m in states}


class Planning(NamedTuple):
    """What a cycle's start gives its plan (``cycle_phases``): the estimate, the context, the cycle's key and the
    further states after their cycle-start hooks."""

    estimate: Estimate
    context: CycleContext
    key: jax.Array
    extra: dict


def cycle_body(controller: Controller, params: Params, key, *, step_s: float, dynamics: Dynamics = MEE,
               keep_steps: bool = False, states: tuple[StateModel, ...] = (), positions: bool = False):
    """One sample's control cycle, ``(carry, xs) -> (carry, (CycleRecord, StepRecord | None))`` over the
    inputs of ``cycle_inputs`` (one cycle's); with ``positions`` the outputs also hold the cycle's
    ``Positions`` (a cluster's separations, ``loop.cluster``)."""
    begin, fly = cycle_phases(controller, params, key, step_s=step_s, dynamics=dynamics, keep_steps=keep_steps,
                              states=states, positions=positions)

    def one_cycle(carry, xs):
        start = begin(carry, xs)
        plan, controller_state = controller.plan(params, carry[1], start.estimate, start.context, start.key)
        return fly(carry, xs, start, plan, controller_state)

    return one_cycle


def cycle_phases(controller: Controller, params: Params, key, *, step_s: float, dynamics: Dynamics = MEE,
                 keep_steps: bool = False, states: tuple[StateModel, ...] = (), positions: bool = False):
    """``cycle_body``'s cycle in two parts around its plan, so that a cluster can plan its satellites together
    (``loop.cluster``): ``begin(carry, xs) -> Planning``, and ``fly(carry, xs, start, plan, controller_state)
    -> (carry, outputs)``, ``cycle_body``'s."""
    fm = params.forces
    mu = fm.mu_m3_s2
    width = controller.reference_cycles
    station_lon = params.station["lon_rad"]

    def begin(carry, xs):
        state, _, extra = carry
        k, env_steps, osc_ref_k, window = xs
        n_steps = env_steps.earth_angle_rad.shape[0]
        cycle_s = n_steps * step_s
        cycle_key = jax.random.fold_in(key, k)
        ctx = CycleContext(k, k * cycle_s, cycle_s, step_s, env_steps, window, fm)
        extra = _cycle_start(states, params, extra, dynamics, state, k, ctx.t_s, cycle_key, mu)
        fix = dynamics.to_mee(state.orbit, mu)
        if not any(m.navigates for m in states):  # the navigation part's Gaussian fix, the loop's to draw
            fix = fix_mee(fix, *position_velocity(dynamics, state.orbit, mu), jax.random.normal(cycle_key, (2, 6))[0],
                          params.errors, mu)
        estimate = _estimate_hooks(states, params, extra, Estimate(fix, jnp.zeros(6), state.mass_kg, ctx.t_s))
        if width:
            estimate = estimate._replace(mean=estimate_mean(
                boundary_elements(estimate.fix_mee, env_steps.earth_angle_rad[0, 0]), osc_ref_k, window[0], mu))
        return Planning(estimate, ctx, cycle_key, extra)

    def fly(carry, xs, start: Planning, plan, controller_state):
        state = carry[0]
        estimate, ctx, extra = start.estimate, start.context, start.extra
        env_steps = xs[1]
        n_steps = env_steps.earth_angle_rad.shape[0]
        cycle_s = n_steps * step_s

        def step(carry, xs):
            state, (fghk_sum, a_sum), extra = carry
            j, env3 = xs
            r, v = dynamics.rv_xyz(state.orbit, mu)  # components: no [3] vectors in the step's kernels
            thrust = controller.thrust(params, plan, ctx.t_s + j * step_s, state,
                                       StepEnvironment(env3, step_s, j, jnp.stack(r), jnp.stack(v)))
            has_propellant = state.mass_kg > params.spacecraft["dry_mass_kg"]  # else the thrusters stop
            thrust = thrust._replace(on_fraction=jnp.where(has_propellant, thrust.on_fraction, 0.0))
            extra, thrust = _thrust_hooks(states, params, extra, thrust,
                                          ThrustContext(ctx.t_s + j * step_s, step_s, jnp.stack(r), jnp.stack(v),
                                                        state.mass_kg))
            east = _to_ecef(env3.cos_earth_angle[0], env3.sin_earth_angle[0])
            lon, tan_lat = subsatellite_lon_tan_lat_xyz(*east(r))  # latitudes once per cycle, from extremes
            accel = thrust.on_fraction * thrust.thrust_n / state.mass_kg
            d = thrust.direction_rsw
            accel_ecef = jnp.stack(east(rsw_to_eci_xyz((accel * d[0], accel * d[1], accel * d[2]), r, v)))
            mee = dynamics.to_mee(state.orbit, mu)
            sums = (fghk_sum + mee[1:5], a_sum + semi_major_axis_m(mee))  # for the cycle means, summed as it goes
            new = rk4_step(dynamics.rhs, state, env3, fm, thrust, step_s, dynamics.rk4_stages_in_loop)
            extra, extra_steps = _steps(states, params, extra, dynamics, state, new, r, v, thrust, env3,
                                        ctx.t_s + j * step_s, step_s, mu)
            rv = jnp.stack([*r, *v]) if positions else None
            return (new, sums, extra), (lon, tan_lat, accel_ecef, extra_steps, rv)

        # The orbit is carried as one array [6] and the mean elements' sums as the loop steps (docs/speed.md,
        # "Cycle means").  The sums start at a zero computed from the orbit (0 x p = +0 for MEE, +-0 for a
        # Cartesian x: the same sums): under vmap a zero that carries the sample axis, so that vmap batches the
        # step once, not once to find that the sums become batched and again.
        zero = 0.0 * state.orbit[0]
        (final, (fghk_sum, a_sum), extra_end), (lon, tan_lat, accel, extra_steps, steps_rv) = jax.lax.scan(
            jax.checkpoint(step), (state, (jnp.zeros(4, state.orbit.dtype) + zero, zero), extra),
            (jnp.arange(n_steps), env_steps))
        # the cycle's mean elements from the step starts' records and the end state, whose longitude and
        # latitude are stored once (``materialized``: else XLA's CPU fusion evaluates them again for each of the
        # n samples of every kernel that appends them)
        end = _to_ecef(env_steps.cos_earth_angle[-1, 2], env_steps.sin_earth_angle[-1, 2])
        lon_end, tan_lat_end = materialized(
            lambda orbit: subsatellite_lon_tan_lat_xyz(*end(dynamics.rv_xyz(orbit, mu)[0])),
            final.orbit, anchor=env_steps.earth_angle_rad[-1, 2])
        # trapezoid rule: the step starts' sum, less half the first sample, plus half the end state
        mee_start, mee_end = dynamics.to_mee(state.orbit, mu), dynamics.to_mee(final.orbit, mu)
        fghk_mean = (fghk_sum + 0.5 * (mee_end[1:5] - mee_start[1:5])) / n_steps
        a_mean = (a_sum + 0.5 * (semi_major_axis_m(mee_end) - semi_major_axis_m(mee_start))) / n_steps
        means = cycle_means(fghk_mean, a_mean, jnp.append(lon, lon_end), jnp.append(tan_lat, tan_lat_end), cycle_s,
                            ctx.t_s + cycle_s / 2)
        dlon = wrap_angle(lon - station_lon)
        norm = jnp.linalg.norm(accel, axis=-1, keepdims=True)
        firing = jnp.sum(jnp.abs(accel) > FIRING_COMPONENT_RTOL * norm, axis=0)
        record = CycleRecord(
            means, boundary_elements(dynamics.to_mee(state.orbit, mu), env_steps.earth_angle_rad[0, 0]),
            final.dv_mps - state.dv_mps, jnp.min(dlon), jnp.max(dlon), jnp.sum(dlon), latitude_rad(jnp.min(tan_lat)),
            latitude_rad(jnp.max(tan_lat)),
            firing, {} if controller.record is None else controller.record(plan),
            {m.name: m.summary(params, extra[m.name], extra_end[m.name], extra_steps[m.name]) for m in states})
        steps = StepRecord(lon, latitude_rad(tan_lat), accel, extra_steps) if keep_steps else None
        if not positions:
            return (final, controller_state, extra_end), (record, steps)
        told = Positions(steps_rv, jnp.concatenate(position_velocity(dynamics, final.orbit, mu)),
                         mee_to_cartesian(estimate.fix_mee, mu)[0])
        return (final, controller_state, extra_end), (record, steps, told)

    return begin, fly


def _cycle_start(states, params, extra: dict, dynamics, state, k, t_s, cycle_key, mu) -> dict:
    """The further states after their ``cycle`` hooks at a cycle start (unchanged without hooks)."""
    hooked = [m for m in states if m.cycle is not None]
    if not hooked:
        return extra
    r, v = position_velocity(dynamics, state.orbit, mu)
    extra = dict(extra)
    for m in hooked:
        start = CycleStart(k, t_s, r, v, state.mass_kg, jax.random.fold_in(cycle_key, stream_id(m)))
        extra[m.name] = m.cycle(params, extra[m.name], start)
    return extra


def _estimate_hooks(states, params, extra: dict, estimate: Estimate) -> Estimate:
    """The controller's ``Estimate`` after the further states' ``estimate`` hooks, in the tuple's order (the fix
    they leave is the one the mean elements are estimated from; unchanged without hooks)."""
    for m in states:
        if m.estimate is not None:
            estimate = m.estimate(params, extra[m.name], estimate)
    return estimate


def _thrust_hooks(states, params, extra: dict, thrust, context: ThrustContext):
    """The further states and the thrust after their ``thrust`` hooks, in the tuple's order (unchanged without
    hooks)."""
    for m in states:
        if m.thrust is not None:
            extra = dict(extra)
            extra[m.name], thrust = m.thrust(params, extra[m.name], thrust, context)
    return extra, thrust


def _steps(states, params, extra: dict, dynamics, state, new, r, v, thrust, env3, t_s, step_s, mu):
    """The further states after one orbit step from ``state`` to ``new`` (``r``, ``v``: the start's
    components), and their step records: ({name: state}, {name: record}); ({}, {}) without states."""
    if not states:
        return {}, {}
    r_end, v_end = position_velocity(dynamics, new.orbit, mu)
    ctx = StepContext(t_s, step_s, env3, jnp.stack(r), jnp.stack(v), r_end, v_end, state.mass_kg, thrust,
                      params.forces)
    stepped = {m.name: m.step(params, extra[m.name], ctx) for m in states}
    return {name: s for name, (s, _) in stepped.items()}, {name: rec for name, (_, rec) in stepped.items()}


def _scan_first(body, carry, xs, n_active):
    """``lax.scan(body, carry, xs)`` over the first ``n_active`` elements of ``xs`` only (a traced count: one
    compiled loop serves every duration within the slots of ``xs``); the outputs beyond are zeros.

    The loop is the ``while`` that ``lax.scan`` lowers to, with a traced trip count, so a cycle computes what it
    computes in a scan, bit for bit (a ``lax.cond`` around the cycle moved the last bit).  ``n_active`` is shared
    by a batch, so under ``vmap`` the loop stays a loop.  Not reverse-differentiable (a ``while``): tuning runs
    the plain scan.  ``body`` is traced once (``jax.closure_convert``), not again for the shapes of its outputs.
    """
    first = jax.tree_util.tree_map(lambda x: x[0], xs)
    fn, consts = jax.closure_convert(body, carry, first)
    shapes = jax.eval_shape(fn, carry, first, *consts)[1]
    n_slots = jax.tree_util.tree_leaves(xs)[0].shape[0]
    outputs = jax.tree_util.tree_map(lambda s: jnp.zeros((n_slots, *s.shape), s.dtype), shapes)

    def one(k, state):
        carry, outputs = state
        x = jax.tree_util.tree_map(lambda a: jax.lax.dynamic_index_in_dim(a, k, keepdims=False), xs)
        carry, y = fn(carry, x, *consts)
        return carry, jax.tree_util.tree_map(lambda o, v: jax.lax.dynamic_update_index_in_dim(o, v, k, 0), outputs, y)

    return jax.lax.fori_loop(0, n_active, one, (carry, outputs))


def _to_ecef(cos_angle, sin_angle):
    """ECI components (x, y, z) -> ECEF components, for an Earth angle shared by the batch (its cosine and
    sine from the environment grid)."""
    return lambda u: (cos_angle * u[0] + sin_angle * u[1], -sin_angle * u[0] + cos_angle * u[1], u[2])


def position_velocity(dynamics: Dynamics, orbit, mu):
    """ECI position and velocity [3] of an orbit state of ``dynamics`` (Cartesian or MEE)."""
    rv = dynamics.to_cartesian(orbit, mu)
    return rv[:3], rv[3:]


def propagate(dynamics: Dynamics, state: SpacecraftState, env: Environment, force_model: ForceModel, step_s: float,
              thrust_fn=None):
    """Open-loop propagation through the same loop: ``thrust_fn(step_start_s, step_s) -> Thrust`` per step
    (none if omitted).  Returns (final state, ``CycleMeans`` [n_cycles])."""
    from geojax.control import none
    from geojax.control.base import no_plan, stateless_init

    controller = none.CONTROLLER if thrust_fn is None else Controller(
        stateless_init, no_plan, lambda params, plan, t, state, environment: thrust_fn(t, environment.step_s))
    zero = jnp.asarray(0.0)
    params = Params(state, force_model, {"dry_mass_kg": zero}, {}, {"lon_rad": zero}, {"sigma3_r_m": zero, "sigma3_v_mps": zero}, {})
    final, records = simulate(controller, params, Shared(env, None), jax.random.key(0), step_s=step_s,
                              dynamics=dynamics)
    return final, records.cycles.means
