"""The protocol of the loop's further states (docs/design.md: the engine): data plus pure functions, as controllers are.

Beyond the orbit and the mass, the closed loop (``geojax.loop.simulate``) carries further states of the spacecraft
-- the wheels' momentum (``states.momentum``), the navigation filter's estimate and covariance
(``states.navigation``) -- through one extension point: a tuple of ``StateModel`` s, static (chosen from the
scenario, ``states.of_config``), whose states ride in the loop's carry and whose records in ``CycleRecord.states``
and ``StepRecord.states``, dicts keyed by the model's ``name``. A model is pure functions in the optax manner:

* ``init(params, r_eci_m, v_eci_mps, env, force_model) -> state``: once, from the true initial position and
  velocity and the environment at that instant (``Environment``, one instant);
* ``cycle(params, state, start) -> state`` (optional): at each cycle's start, before the controller plans
  (``CycleStart``: the true state, the cycle's key);
* ``step(params, state, context) -> (state, step_record)``: once per integration step, after the orbit's step
  (``StepContext``: the true state at the step's start and end, the thrust held over it, the environment);
* ``thrust(params, state, thrust, context) -> (state, thrust)`` (optional): before each orbit step, on the
  thrust the controller commands (``physics.dynamics.Thrust``, stopped without propellant): the model may change
  what is flown (the wheels' dumping tilt) and note in its state what it did, for its ``step``; the orbit then
  flies the returned thrust (``ThrustContext``: the true state at the step's start, the step);
* ``estimate(params, state, estimate) -> Estimate`` (optional): at each cycle start, after ``cycle``, on what
  the controller will be told (``control.base.Estimate``): the model may add what it measures to
  ``estimate.states[name]`` (the wheels: their measured momentum) or replace the fix (a navigation filter: its
  state); the mean elements are then estimated from the fix it leaves;
* ``summary(params, state_at_start, state_at_end, step_records) -> cycle_record``: the cycle's record from the
  step records ([n_steps, ...]), kept always (extremes, so a check covers every step without keeping them);
* ``metrics(params, cycle_records, n_steps_total, run_s) -> ({name: []}, failed)``: its scalar metrics (units in
  the names) and whether the sample failed in its way; ``status`` is then the meaning of the status code that
  ``failed`` sets (one of ``loop.metrics.STATUS_MEANINGS``; None: never fails);
* ``box_metrics(params, cycle_records, out_of_box, cycle_s) -> {name: []}`` (optional): metrics of its own
  that read the loop's box check per cycle (``out_of_box`` [n_cycles] bool: some step start of the cycle outside
  the box, ``loop.metrics.box_exits``; ``cycle_s`` the cycle's length), the time out of the box after a fault;
* ``columns(cycle_records) -> {name: numpy array}`` (optional): its per-cycle series in edge units (``/cycles``).

With no model (every scenario that asks for none) the carry and the records hold empty dicts: no leaf, the same
program, every number as without the extension point (``tests/test_reference_numbers.py`` holds them).
"""

from __future__ import annotations

import zlib
from typing import Callable, NamedTuple

import jax.numpy as jnp

from geojax.physics.dynamics import Thrust
from geojax.physics.forces import Environment, ForceModel


class CycleStart(NamedTuple):
    """What the loop tells ``StateModel.cycle`` at a cycle's start."""

    index: jnp.ndarray  # [] int, cycle number from 0
    t_s: jnp.ndarray  # [] s since the start of the run
    r_eci_m: jnp.ndarray  # [3] true position
    v_eci_mps: jnp.ndarray  # [3] true velocity
    mass_kg: jnp.ndarray  # []
    key: jnp.ndarray  # the model's own key this cycle: fold_in(the cycle's key, stream_id(model))


# The streams the loop and the controllers draw from the cycle's key: rows of normal(key_k), fold_in(key_k, 1)
# (the FOMPC's search) and fold_in(key_k, physics.execution.MAGNITUDE_KEY).  A part's stream is never one of them.
# What a part tells the controller at a cycle start, each under its ``Estimate.states`` key: a quantity, not a part,
# so that a controller names no part to read it and any part that knows the quantity serves it.  A part declares
# which it tells (``Part.tells``); a controller which it plans with (``control.base.Spec.needs``), checked at load.
THRUSTER_LEVELS = "thruster_levels"  # [4] each thruster's delivered fraction of its thrust, 0 out (states.faults)
WHEEL_MOMENTUM = "wheel_momentum_nms"  # [3] the wheels' measured momentum, N m s, body axes (states.momentum)
# {"thrust_arm_m", "dump_angle_max_rad", "wheel_capacity_nms"}: the nozzle's distance from the centre of mass, how
# far a burn's line may tilt about it, and the wheels' capacity it unloads (states.momentum)
DUMPING = "dumping"
STATION_PASSES = "station_passes"  # navigation.schedule.Schedule [n_stations]: the tracking passes (states.navigation)
QUANTITIES = {THRUSTER_LEVELS: "each thruster's level", WHEEL_MOMENTUM: "the wheels' measured momentum",
              DUMPING: "a thrust line that tilts to unload the wheels", STATION_PASSES: "the tracking stations' passes"}

RESERVED_STREAMS = frozenset({0, 1, 2})
# The navigation filter's stream: the value it drew from when it was the only part (the first of the tuple,
# 1 << 16 + its place), kept so that every scenario with the filter keeps its numbers bit for bit.
NAVIGATION_STREAM = 1 << 16


def stream_id(model) -> int:
    """The id a part's key is folded with at each cycle start: its declared ``stream``, else a stable hash of its
    name (CRC-32), never its place in the tuple, so that adding or removing a part changes no other part's draws
    (common random numbers between runs with and without it)."""
    if model.stream is not None:
        return int(model.stream)
    return zlib.crc32(model.name.encode()) | (1 << 31)  # the top bit set: apart from every small constant


def check_streams(models) -> None:
    """``ValueError`` where two parts share a name or a stream, or a part takes one of the loop's own streams."""
    seen = {}
    for m in models:
        sid = stream_id(m)
        if sid in RESERVED_STREAMS:
            raise ValueError(f"state {m.name!r}: stream {sid} is the loop's own (reserved: {sorted(RESERVED_STREAMS)})")
        if m.name in (other.name for other in seen.values()):
            raise ValueError(f"state {m.name!r}: two parts of one name")
        if sid in seen:
            raise ValueError(f"state {m.name!r}: stream {sid} is also state {seen[sid].name!r}'s; give it another")
        seen[sid] = m


class StepContext(NamedTuple):
    """What the loop tells ``StateModel.step`` about an integration step."""

    t_s: jnp.ndarray  # [] step start, s since the start of the run
    step_s: float
    env: Environment  # at the step's three RK4 stage times (start, middle, end), leaves [3, ...]
    r_eci_m: jnp.ndarray  # [3] true position at the step start
    v_eci_mps: jnp.ndarray  # [3] true velocity at the step start
    r_end_eci_m: jnp.ndarray  # [3] true position at the step end
    v_end_eci_mps: jnp.ndarray  # [3] true velocity at the step end
    mass_kg: jnp.ndarray  # [] at the step start
    thrust: Thrust  # held over the step (as flown: stopped without propellant)
    force_model: ForceModel


class ThrustContext(NamedTuple):
    """What the loop tells ``StateModel.thrust`` about the step the thrust is held over."""

    t_s: jnp.ndarray  # [] step start, s since the start of the run
    step_s: float
    r_eci_m: jnp.ndarray  # [3] true position at the step start
    v_eci_mps: jnp.ndarray  # [3] true velocity at the step start
    mass_kg: jnp.ndarray  # [] at the step start


class StateModel(NamedTuple):
    """A further state of the spacecraft that the loop carries (the protocol above).  Its functions are
    module-level, so a model is the same hashable object every time (a static argument of the compiled loop)."""

    name: str  # its key in the loop's carry and records, and its table's name in ``states.REGISTRY``
    init: Callable
    step: Callable
    summary: Callable
    metrics: Callable
    cycle: Callable | None = None
    status: str | None = None
    columns: Callable | None = None
    thrust: Callable | None = None
    estimate: Callable | None = None
    box_metrics: Callable | None = None
    # For the lanes' memory model (``geojax.lanes``): the values per cycle its ``columns`` add to a sweep's kept
    # records (``tests/test_lanes.py`` checks it against the columns); its records' bytes come from jax.eval_shape
    columns_per_cycle: int = 0
    stream: int | None = None  # its random stream's id (``stream_id``); None: a stable hash of its name
    # The navigation slot: True where its ``estimate`` tells the controller the orbit (a filter), so the loop draws
    # no Gaussian fix (``navigation.fix``) and hands the hook the true elements to keep its longitude continuous.
    navigates: bool = False


class Constraint(NamedTuple):
    """A constraint a tuning keeps: ``value(params, metrics) <= 0`` inside (normalised like the box's,
    (excursion / limit)^2 - 1), and the status meaning of a sample that breaks it."""

    name: str
    value: Callable
    status: str


BURN_STATUSES = ("flown", "missed", "cut", "degraded")  # a burn as flown, where a part says (``FlownBurns``)


class FlownBurns(NamedTuple):
    """A run's planned burns [cycles, burns] as a part let them fly (``Part.flown_burns``)."""

    fired_s: object  # the firing time delivered, s
    directions_rsw: object  # [..., 3] unit, the direction flown
    level: object  # the fraction of the full thrust delivered
    status: object  # one of ``BURN_STATUSES``
    commanded_s: object  # the firing time the controller commanded, s


class Part(NamedTuple):
    """What a state of the loop declares besides its protocol, every entry optional but its name: its scenario
    table and keys, the model a table selects, its ``Params`` leaves (``params.states[name]``), its validation,
    the meanings of the status codes it sets, its metric and column descriptions, its tuning constraints and its
    figures.  ``geojax.states.REGISTRY`` lists the shipped parts, one line each; a user's own ``StateModel`` is
    a part of defaults (no table, no leaves) unless it comes as a ``Part``."""

    name: str  # the model's name: its key in the loop's carry, records and ``params.states``
    table: str | None = None  # its scenario table ("attitude"); None: no keys
    fields: dict = {}  # {key: params.Field} of its table
    select: Callable | None = None  # validated table -> its StateModel, or None where the table turns it off
    # the true/false key of its table that turns it on: where it is false, every other key of the table must keep
    # its default (a key that would not be read is refused at load, naming it)
    switch: str | None = None
    leaves: Callable | None = None  # validated table -> {leaf: array} (default: the fields' SI leaves)
    validate: Callable | None = None  # (validated config) -> its table completed (or None: unchanged), at load
    statuses: tuple = ()  # meanings of the failure codes its model sets (``StateModel.status`` among them)
    descriptions: dict = {}  # {metric or column name: one line} for results files, summaries and docs
    constraints: tuple = ()  # ``Constraint`` s a tuning keeps (``geojax.tune``)
    # (result, folder) -> [paths of the figures it drew], or its import path ("geojax.plots.parts:wheel_figures"),
    # resolved by the runner when a run's figures are drawn: a part's module need not import the figures' code
    figures: Callable | str | None = None
    # (run, fired_s, directions_rsw, thrusters) -> ``FlownBurns``: the planner's burns [cycles, burns] as this part
    # let them fly (host side, numpy), for the burns file and the CCSDS maneuvers (``export.trajectory.run_burns``)
    flown_burns: Callable | None = None
    # validated table -> the quantities (``QUANTITIES``) its ``estimate`` hook tells the controller under it, and
    # {quantity: what a scenario sets for it to tell it}, for the error where a controller needs one none tells
    tells: Callable | None = None
    tells_how: dict = {}
    # the model where it does not depend on the table (a user's own), or the one whose metrics and columns serve
    # every table (a registered part's)
    model: StateModel | None = None


def part_of(entry) -> Part:
    """A ``Part`` of a ``StateModel`` (the defaults: no table, no leaves) or the ``Part`` itself."""
    if isinstance(entry, Part):
        return entry
    if isinstance(entry, StateModel):
        return Part(entry.name, statuses=(entry.status,) if entry.status else (), model=entry)
    raise TypeError(f"states: a StateModel or a Part, got {type(entry).__name__}")
