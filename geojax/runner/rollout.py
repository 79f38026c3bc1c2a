"""Rollouts of scenarios: one (``simulate``) or a batch (``simulate_batch``), compiled once and reused.

``rollout_fn(batch)`` is the pure per-sample function that ``sweep`` and
``tune`` vmap: ``(params, key) -> (final state, records, metrics)``.
``simulate`` and ``simulate_batch`` wrap it for a scenario, with results as
numpy arrays.
"""

from __future__ import annotations

import functools
import math
import threading
import time
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.control import REGISTRY
from geojax.control.base import Controller, keeps_steps
from geojax.control.predictor import Reference
from geojax.physics.dynamics import SpacecraftState
from geojax.loop.metrics import cycle_table, summarize
from geojax.export import maneuvers, recorder, trajectory
from geojax.runner import report
from geojax import compilation, traced
from geojax import states as parts
from geojax.lanes import RecordBytes
from geojax.parallel import Background
from geojax.runner.setup import (Batch, controller_of, cycle_slots, padded, prepare, program_identity, reference,
                                 reference_shape, unstack)
from geojax.params import static_settings
from geojax.loop.simulate import Records, Shared, simulate as closed_loop
from geojax.params import Params
from geojax.physics.propagate import Dynamics, for_lanes, for_one_sample
from geojax.scenario import Scenario


class Result(NamedTuple):
    """A rollout's results (numpy leaves; a batch has a leading sample axis on every leaf).

    ``metrics`` maps the names of ``loop.metrics.summarize`` (units in the names) to values,
    ``status`` is the status code (``loop.metrics.STATUS_MEANINGS``), ``records`` the per-cycle (and, if
    kept, per-step) records, ``params`` the parameters the rollout ran with (SI).  A single rollout
    (``simulate``) also carries its ``scenario`` and ``seed``, what its file records (``save``); a batch's
    are None: plain references, so the vmapped result stays its arrays.
    """

    metrics: dict
    status: np.ndarray
    records: Records
    final: SpacecraftState
    params: Params
    step_s: float
    wall_s: float  # compilation included
    compile_s: float = float("nan")  # from the closed loop's compilation's start to its and its metrics' readiness
    run_s: float = float("nan")  # the compiled closed loop's and metrics' run alone
    scenario: Scenario | None = None  # a single rollout's
    seed: int | None = None  # a single rollout's, None where it was given a key
    states: tuple = ()  # the models of the parts the loop carried (``geojax.states``)
    parts: tuple = ()  # their ``Part`` s (a user's own as given): their figures and descriptions
    ephemeris: recorder.Ephemeris | None = None  # per step, where asked for (``simulate(..., ephemeris=True)``)

    @property
    def status_meanings(self) -> tuple[str, ...]:
        """The meaning of each status code of this result: the loop's, the shipped parts', then its own parts'."""
        return parts.status_meanings(self.states)

    def cycles(self) -> dict[str, np.ndarray]:
        """The per-cycle records in edge units (``/cycles``) of a single rollout."""
        return cycle_table(self.records, self.states)

    # What ``geojax simulate`` writes (``--out``), prints and draws (``--plots``): its report's functions.
    save, summary, plot = report.save, report.summary, report.plot
    save_oem = trajectory.save_oem  # CCSDS OEM of the truth or the estimate (and covariance), and the burns as CSV
    save_maneuvers = maneuvers.save_maneuvers  # CCSDS OPM with one maneuver block per burn flown


def rollout(params: Params, key, shared: Shared, reference_env=None, *, controller: Controller, step_s: float,
            dynamics: Dynamics, keep_steps: bool = False, states: tuple = ()):
    """One sample's closed loop and its metrics: ``(final state, records, metrics)``; pure, vmappable.

    ``reference_env`` (the reference's ``runner.setup.Segments``) makes the sample run its own uncontrolled
    reference (``runner.setup.reference``) instead of ``shared.reference``; ``controller``, ``step_s``,
    ``dynamics``, ``keep_steps`` and ``states`` (the further states carried, ``geojax.states``) are static.
    """
    final, records = loop(params, key, shared, reference_env, controller=controller, step_s=step_s,
                          dynamics=dynamics, keep_steps=keep_steps, states=states)
    return final, records, summarize(params, final, records, step_s, shared.env.earth_angle_rad.shape[1], states,
                                     controller.metrics)


def loop(params: Params, key, shared: Shared, reference_env=None, *, controller: Controller, step_s: float,
         dynamics: Dynamics, keep_steps: bool = False, states: tuple = ()):
    """``rollout`` without its metrics: ``(final state, records)``, the records over every cycle of
    ``shared.env`` (the run's first ``shared.n_active``, zeros beyond).  ``reference_env``: where this sample's
    own reference runs (``Segments``), or the reference itself, computed before (``Batch.references``)."""
    if isinstance(reference_env, Reference):
        shared = shared._replace(reference=reference_env)
    elif reference_env is not None:
        own = reference(params, reference_env, step_s, dynamics, controller.reference_cycles)
        slots = shared.env.earth_angle_rad.shape[0]  # the loop's cycle slots (``runner.setup.prepare(pad=True)``)
        if own.osc.shape[0] < slots:
            own = padded(own, slots)
        shared = shared._replace(reference=own)
    return closed_loop(controller, params, shared, key, step_s=step_s, dynamics=dynamics, keep_steps=keep_steps,
                       states=states)


def rollout_fn(batch: Batch, keep_steps: bool = False, controller: Controller | None = None, lanes: int = 1):
    """The pure rollout of one sample of ``batch``: ``(params, key) -> (final, records, metrics)``.

    ``controller`` replaces the batch's (a tuning differentiates through the surrogate); ``lanes`` is how many
    samples the caller vmaps per device (the step is compiled for it, ``physics.propagate.for_lanes``).
    """
    return functools.partial(rollout, shared=batch.shared,
                             reference_env=batch.reference_env if batch.reference_per_sample else None,
                             controller=batch.controller if controller is None else controller,
                             step_s=batch.step_s, dynamics=for_lanes(batch.dynamics, lanes), keep_steps=keep_steps,
                             states=batch.states)


def record_bytes_per_cycle(batch: Batch) -> RecordBytes:
    """What each cycle adds to one lane of ``batch`` (a ``Batch`` of shapes will do, ``prepare(shapes_only=True)``):
    the bytes of the loop's stacked cycle records, from ``jax.eval_shape`` of one lane's loop (a trace, no
    compilation: 1-3 s on a CPU), and of a reference run's, from its shapes."""
    params = jax.tree_util.tree_map(lambda x: jax.ShapeDtypeStruct(x.shape[1:], x.dtype), batch.params)
    key = jax.eval_shape(lambda: jax.random.key(0))
    one = functools.partial(loop, controller=batch.controller, step_s=batch.step_s, dynamics=batch.dynamics,
                            states=batch.states)
    own = _reference_env(batch)
    if isinstance(own, Reference):  # one lane's
        own = jax.tree_util.tree_map(lambda x: jax.ShapeDtypeStruct(x.shape[1:], x.dtype), own)
    _, records = jax.eval_shape(one, params, key, batch.shared, own)
    n_cycles = batch.shared.env.earth_angle_rad.shape[0]
    width = batch.controller.reference_cycles
    reference = reference_shape(n_cycles, width, jnp.float64) if width else ()
    return RecordBytes(_nbytes(records.cycles) // n_cycles, _nbytes(reference) // n_cycles)


def _nbytes(tree) -> int:
    return sum(math.prod(x.shape) * x.dtype.itemsize for x in jax.tree_util.tree_leaves(tree))


def _reference_env(batch: Batch):
    """What the loop gets of the samples' references: each sample's, computed before (``Batch.references``,
    [n, ...]), where each runs its own (``Segments``), or None (one shared in ``batch.shared``)."""
    if batch.references is not None:
        return batch.references
    return batch.reference_env if batch.reference_per_sample else None


@functools.partial(jax.jit, static_argnames=("controller", "step_s", "dynamics", "keep_steps", "states"))
def closed_loop_batch(params, keys, shared, reference_env, controller, step_s, dynamics, keep_steps, states=()):
    """``loop`` vmapped over (params, keys): the closed loop, compiled once per (lanes, cycle slots, controller,
    step, dynamics), whatever the duration within the slots and the epoch."""
    one = functools.partial(loop, controller=controller, step_s=step_s, dynamics=dynamics, keep_steps=keep_steps,
                            states=states)
    if isinstance(reference_env, Reference):  # each sample's own, computed before the loop: per lane
        return _over_lanes(lambda p, k, r, s: one(p, k, s, r), (params, keys, reference_env), (shared,))
    return _over_lanes(one, (params, keys), (shared, reference_env))


def _over_lanes(fn, per_lane: tuple, common: tuple):
    """``fn(*per_lane, *common)`` vmapped over the leading axis of ``per_lane``'s leaves; a single lane runs
    ``fn`` itself, its results given the lane axis back: without vmap's batching of the traced program (3.6 of a
    cold one-sample QFFC year's 6.2 s of tracing; the program compiles in 9.9 s instead of 12.3), the same numbers to
    rounding (``tests/test_compilation.py``)."""
    if jax.tree_util.tree_leaves(per_lane)[0].shape[0] == 1:
        first = jax.tree_util.tree_map(lambda x: x[0], per_lane)
        return jax.tree_util.tree_map(lambda x: x[None], fn(*first, *common))
    return jax.vmap(fn, in_axes=(0,) * len(per_lane) + (None,) * len(common))(*per_lane, *common)


@functools.partial(jax.jit, static_argnames=("n_cycles", "step_s", "steps_per_cycle", "states", "controller_metrics"))
def metrics_batch(params, final, records, n_cycles: int, step_s: float, steps_per_cycle: int, states: tuple = (),
                  controller_metrics=None):
    """``loop.metrics.summarize`` of every sample over the first ``n_cycles`` cycles of its records: a small
    program of its own, compiled per duration (the closed loop is compiled per slot count)."""
    records = records._replace(cycles=jax.tree_util.tree_map(lambda x: x[:, :n_cycles], records.cycles))
    return _over_lanes(lambda p, f, r: summarize(p, f, r, step_s, steps_per_cycle, states, controller_metrics),
                       (params, final, records),
                       ())


def simulate(scenario: Scenario, seed: int = 0, *, controller: Controller | None = None,
             keep_steps: bool | None = None, key=None, on_compiled=None, meanwhile=None, states: tuple = (),
             ephemeris: bool = False) -> Result:
    """One closed-loop rollout of ``scenario`` (its registered controller, or ``controller``), carrying the parts
    the scenario turns on and ``states`` (a user's own: ``StateModel`` s or ``Part`` s, ``geojax.states.base``).

    ``seed`` (or a ``jax.random`` ``key``) draws the orbit-determination and attitude errors
    and any randomness of the controller; same seed, same result.  ``keep_steps`` also returns
    the per-step records (``records.steps``, leaves [n_cycles, n_steps, ...]); by default as the controller says
    (``Spec.keeps_steps``: a feedback law's are kept, its figures are drawn per step; a planner's are not).
    ``ephemeris`` also returns the true state at every step start and, with a navigation filter, its estimate and
    covariance there (``Result.ephemeris``, ``export.recorder``; every other number as without it), what
    ``Result.save_oem`` writes at step resolution.
    """
    if keep_steps is None:
        keep_steps = keeps_steps(controller_of([scenario]) if controller is None else controller)
    result = simulate_batch([scenario], seeds=[seed], controller=controller, keep_steps=keep_steps,
                            keys=None if key is None else jnp.stack([key]), on_compiled=on_compiled,
                            meanwhile=meanwhile, states=states, ephemeris=ephemeris)
    first = lambda tree: jax.tree_util.tree_map(lambda x: x[0], tree)  # noqa: E731
    return result._replace(metrics=first(result.metrics), status=result.status[0], records=first(result.records),
                           final=first(result.final), params=first(result.params), scenario=scenario,
                           seed=None if key is not None else seed,
                           ephemeris=None if result.ephemeris is None else first(result.ephemeris))


def simulate_batch(scenarios: list[Scenario] | Scenario, params: Params | None = None, *, seeds=None, keys=None,
                   controller: Controller | None = None, keep_steps: bool = False, on_compiled=None,
                   meanwhile=None, states: tuple = (), ephemeris: bool = False) -> Result:
    """A batch of rollouts, vmapped in one compiled call.

    Either a list of scenarios (one sample each), or one scenario with ``params`` whose leaves carry a
    leading batch axis (e.g. 100 initial states: start from ``prepare_params(scenario, n)`` and replace
    ``params.initial``).  ``seeds`` [n] (default 0, 1, ...) or ``keys`` [n] draw each sample's errors.
    ``on_compiled(seconds)``: called when the closed loop and its metrics are compiled (or loaded from the
    cache), before they run, with the seconds since their compilation began (e.g. the command line's "closed
    loop ready in X s"); the result's ``compile_s`` is the same.  ``meanwhile()``: called once the environment grid
    and the reference are ready, while the closed loop may still compile (``geojax simulate`` computes its figures'
    uncontrolled run then, on a core that would otherwise wait).  ``ephemeris``: as for ``simulate``.

    The closed loop compiles in a thread of its own while the environment grid and the predictor's reference
    are computed (their programs compile meanwhile): XLA compiles a program on one core, so on two cores a
    cold one-year QFFC run waits for the longest of them rather than their sum.
    """
    start = time.perf_counter()
    scenarios = [scenarios] if isinstance(scenarios, Scenario) else list(scenarios)
    if params is not None and len(scenarios) != 1:
        raise ValueError("params: give one scenario with a batch of params, or a list of scenarios")
    own_states = bool(states) or bool(scenarios[0].config.get("states"))  # a user's code: not kept traced
    call = functools.partial(_loop_call, scenarios, params, seeds, keys, controller, keep_steps, own_states, ephemeris)
    compiling = {}

    def compile_meanwhile(layout: Batch):
        compiling["begun"] = time.perf_counter()
        lowered = threading.Event()
        compiling["programs"] = Background(functools.partial(_compiled_programs, *call(layout), lowered=lowered))
        return functools.partial(_wait, lowered)

    n = len(scenarios) if params is None else jax.tree_util.tree_leaves(params)[0].shape[0]
    batch = prepare(scenarios, controller, pad=True, on_shapes=compile_meanwhile, one_sample=n == 1, states=states,
                    own_references=True,
                    slots=functools.partial(slots_compiled, call))
    args, _, _, _, summarized, n = call(batch)
    if meanwhile is not None:
        meanwhile()
    loop_program, metrics_program = compiling["programs"].result()
    compile_s = time.perf_counter() - compiling["begun"]
    if on_compiled is not None:
        on_compiled(compile_s)
    begun = time.perf_counter()
    final, records = jax.block_until_ready(loop_program(*args))
    records, kept = recorder.split(records) if ephemeris else (records, None)
    metrics = jax.block_until_ready(metrics_program(args[0], final, records))
    run_s = time.perf_counter() - begun
    to_numpy = lambda tree: to_host(tree, n)  # noqa: E731
    metrics = to_numpy(metrics)
    status = metrics.pop("status")
    records = Records(to_host(records.cycles, n, batch.n_cycles),
                      None if records.steps is None else to_host(records.steps, n, batch.n_cycles))
    params = batch.params if params is None else params
    kept = None if kept is None else recorder.Ephemeris(*(None if x is None else to_host(x, n, batch.n_cycles)
                                                          for x in kept))
    return Result(metrics, status, records, to_numpy(final), jax.tree_util.tree_map(np.asarray, params),
                  batch.step_s, time.perf_counter() - start, compile_s, run_s, states=batch.states,
                  parts=parts.parts_of(batch.states, (*parts.named(scenarios[0].config), *states)), ephemeris=kept)


def _loop_call(scenarios, params, seeds, keys, controller, keep_steps, own_states: bool, ephemeris, batch: Batch):
    """What ``simulate_batch`` compiles and calls for ``batch`` (its ``shared`` arrays or their shapes):
    (the loop's arguments, its static ones, the traced programs' identities of the loop and of the metrics, the
    metrics' static ones, the sample count)."""
    params = batch.params if params is None else params
    n = jax.tree_util.tree_leaves(params)[0].shape[0]
    if keys is None:
        keys = keys_of(np.arange(n) if seeds is None else seeds)
    lanes = lane_slots(n)
    own = _reference_env(batch)
    args = (pad_lanes(params, lanes), pad_lanes(keys, lanes), batch.shared,
            pad_lanes(own, lanes) if isinstance(own, Reference) else own)
    dynamics = for_one_sample(batch.dynamics) if lanes == 1 else for_lanes(batch.dynamics, lanes)
    static = dict(controller=batch.controller, step_s=batch.step_s, dynamics=dynamics,
                  keep_steps=keep_steps, states=recorder.with_recording(batch.states) if ephemeris else batch.states)
    summarized = dict(n_cycles=batch.n_cycles, step_s=batch.step_s,
                      steps_per_cycle=batch.shared.env.earth_angle_rad.shape[1], states=batch.states,
                      controller_metrics=batch.controller.metrics)
    # A registered controller's programs are kept traced between runs (``geojax.traced``); a user's, or a loop
    # carrying a user's own part, are not.
    shipped = controller is None and scenarios[0].controller in REGISTRY and not own_states  # in traced's digest
    identity = None if not shipped else program_identity(
        scenarios[0], scenarios[0].controller, repr(sorted(static_settings(scenarios[0].config["controller"],
                                                                        batch.controller.fields).items())),
        lanes, keep_steps, batch.step_s, *(("ephemeris",) if ephemeris else ()))
    per_duration = None if identity is None else (*identity, batch.n_cycles)  # the metrics' static cycle count
    return args, static, identity, per_duration, summarized, n


# Slot counts a run may borrow: up to this many times its own (``slots_compiled``; 10 days in a year's 384 slots is
# 12 times their 32): the loop carries and zeroes every slot's records, so a far longer loop is left to compile anew.
REUSE_MAX_RATIO = 16
_LOOPS_COMPILED: set = set()  # ``_loop_key`` of every closed loop compiled (or loaded) in this process


def slots_compiled(call, layout, own: int) -> int:
    """The cycle slots ``simulate_batch`` compiles its closed loop for: the least count from ``own``
    (``runner.setup.cycle_slots``) up to ``REUSE_MAX_RATIO`` times it whose loop, otherwise the same, this process
    has compiled already or the cache folder keeps traced (``geojax.traced.kept``; its executable then comes from
    JAX's cache), else ``own``.  A shorter run after a longer one then runs the longer one's program, its first
    cycles only (``Shared.n_active``): the same numbers bit for bit (``tests/test_compilation.py``), nothing
    compiled (where JAX's cache has evicted the kept loop's executable, the longer loop compiles, in about the time
    of the run's own: the program is the cycle's body, whatever the trip count).  ``call(layout(count))`` is
    ``_loop_call``'s for a loop of ``count`` slots (only its shared arrays' shapes differ from count to count:
    ``call`` runs once)."""
    args, static, identity, *_ = call(layout(own))
    count = own
    while count <= REUSE_MAX_RATIO * own:
        args = (*args[:2], layout(count).shared, *args[3:])  # (params, keys, shared, reference_env)
        if _loop_key(args, static) in _LOOPS_COMPILED or traced.kept("closed_loop", identity, *args):
            return count
        count = cycle_slots(count + 1)
    return own


def _loop_key(args, static: dict) -> tuple:
    """What fixes a compiled ``closed_loop_batch``: its static arguments and its arguments' tree, shapes and dtypes."""
    leaves, tree = jax.tree_util.tree_flatten(args)
    return (tuple(static.items()), str(tree),
            tuple((tuple(x.shape), str(x.dtype), bool(getattr(x, "weak_type", False))) for x in leaves))


def _compiled_programs(args, static, identity, per_duration, summarized, n, lowered: threading.Event):
    """The closed loop and its metrics compiled (or loaded from the cache) for ``args`` (arrays or shapes), the
    metrics in a thread of their own once the loop's result shapes are known; ``lowered`` is set once the loop is
    traced and lowered (or that failed)."""
    lanes = jax.tree_util.tree_leaves(args[0])[0].shape[0]
    try:
        loop_program = traced.lowered(closed_loop_batch, "closed_loop", identity, *args, **static)
    finally:
        lowered.set()
    final, records = loop_program.out_info
    if recorder.NAME in records.cycles.states:  # the metrics never see the ephemeris (``recorder.split``)
        records = recorder.split(records)[0]
    metrics = Background(lambda: traced.lowered(metrics_batch, "metrics", per_duration, args[0], final, records,
                                                **summarized).compile(compiler_options(lanes)))
    loop_program = loop_program.compile(compiler_options(lanes, static["controller"]))
    _LOOPS_COMPILED.add(_loop_key(args, static))
    return loop_program, metrics.result()


def compiler_options(lanes: int, controller: Controller | None = None) -> dict | None:
    """XLA's options for the programs of a batch compiled for ``lanes`` samples (None: XLA's defaults; one sample:
    ``compilation.ONE_SAMPLE_OPTIONS``, and for the closed loop of ``controller`` its
    ``Sizing.one_sample_opt_level``)."""
    if lanes != 1:
        return None
    options = dict(compilation.ONE_SAMPLE_OPTIONS)
    if controller is not None:
        options["xla_backend_optimization_level"] = controller.sizing.one_sample_opt_level
    return options


def _wait(event: threading.Event) -> None:
    """Wait for ``event``, a tenth of a second at a time (Ctrl-C reaches the waiting thread at once)."""
    while not event.wait(0.1):
        pass


def to_host(tree, lanes: int, cycles: int | None = None):
    """``tree``'s leaves as NumPy arrays, their first ``lanes`` samples (and first ``cycles`` cycles): on a CPU
    views of the device's buffers; on an accelerator cut on the device first (one small program), so that only
    what is kept crosses to the host (a one-cycle batch of 100,000 samples compiled for 32 cycle slots and
    131,072 lanes otherwise copies every slot of every lane: 0.678 of its 0.692 s on an H200,
    ``benchmarks/results/accelerator_gpu_host_before.md``; cut first, 0.119 of 0.133 s, ``accelerator_gpu_host.md``)."""
    leaves = jax.tree_util.tree_leaves(tree)
    index = (slice(0, lanes),) if cycles is None else (slice(0, lanes), slice(0, cycles))
    if any(isinstance(x, jax.Array) and any(d.platform != "cpu" for d in x.devices()) for x in leaves):
        tree = _cut(tree, lanes, cycles)
        return jax.tree_util.tree_map(np.asarray, tree)
    return jax.tree_util.tree_map(lambda x: np.asarray(x)[index], tree)


@functools.partial(jax.jit, static_argnames=("lanes", "cycles"))
def _cut(tree, lanes: int, cycles: int | None):
    return jax.tree_util.tree_map(lambda x: x[:lanes] if cycles is None else x[:lanes, :cycles], tree)


def lane_slots(n: int) -> int:
    """The samples a batch of ``n`` is compiled for: the least power of two that holds them (60 and 64 samples
    run one program); the lanes beyond ``n`` repeat the last sample and are dropped."""
    return 1 << max(0, n - 1).bit_length()


def pad_lanes(tree, lanes: int):
    """``tree``'s leaves (leading axis n) with the last sample repeated up to ``lanes``."""
    def pad(x):
        extra = lanes - x.shape[0]
        if isinstance(x, jax.ShapeDtypeStruct):  # a shape (what compiles ahead): the padded one's
            return jax.ShapeDtypeStruct((lanes, *x.shape[1:]), x.dtype)
        return x if extra == 0 else jnp.concatenate([x, jnp.repeat(x[-1:], extra, axis=0)])
    return jax.tree_util.tree_map(pad, tree)


def keys_of(seeds) -> jax.Array:
    """``jax.random.key(s)`` of every seed [n], made on the device in one vectorised call (the same keys as one
    at a time: a seed of 64 bits is split into the key's two words either way), not one transfer per seed."""
    seeds = np.asarray(seeds)
    if seeds.ndim != 1 or not (np.issubdtype(seeds.dtype, np.integer) or seeds.size == 0):
        raise ValueError(f"seeds: must be a list of integers, got {seeds.dtype} of shape {seeds.shape}")
    return _keys_of(jnp.asarray(seeds.astype(np.int64)))


_keys_of = jax.jit(jax.vmap(jax.random.key))


def prepare_params(scenario: Scenario, n: int, controller: Controller | None = None) -> Params:
    """``n`` copies of a scenario's ``Params`` (leading axis n), to edit leaves per sample."""
    params = unstack(prepare([scenario], controller).params, 0)
    return jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (n, *jnp.shape(x))), params)
