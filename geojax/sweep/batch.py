"""One controller of a sweep compiled for this process's devices: the lane plan and the batch a chunk runs."""

from __future__ import annotations

import math
import time

import jax
import jax.numpy as jnp
import numpy as np

from geojax import lanes as lanes_mod
from geojax.sweep import epochs as epoch_axis
from geojax.physics.frames import earth_rotation_angle_rad
from geojax.loop.metrics import CYCLE_NAMES, cycle_series
from geojax.runner.rollout import record_bytes_per_cycle, rollout_fn
from geojax.control import REGISTRY
from geojax.runner.setup import (Batch, controller_of, cycle_count, disperse, prepare, program_identity,
                               reference_per_sample)
from geojax.params import static_settings
from geojax.states import of_config as states_of
from geojax.parallel import per_device
from geojax.sweep.clusters import compiled_cluster_batch
from geojax.sweep.spec import DISPERSION_STREAM, Sweep, _points, _scenario


class ChunkRunner:
    """One controller of a sweep, compiled once for this process's devices: ``run(first, length)`` gives the
    metrics of samples ``first .. first + length - 1`` (numpy, one row per sample).

    The batch is ``plan.lanes`` samples per device whatever the chunk (the last call padded with the chunk's
    last sample); a sample's numbers depend on neither the chunk, the width, the device count nor the process
    that runs it: a local sweep and every Ray worker use this.
    """

    def __init__(self, sweep: Sweep, controller: str, chunk: int | None = None, on_phase=None):
        self.n_samples = sweep.n_points * sweep.repetitions
        self.repetitions = sweep.repetitions
        self.plan = lane_plan(sweep, controller, chunk)
        self.devices = devices_for(min(chunk or self.n_samples, self.n_samples), self.plan.lanes)
        self.width = self.plan.lanes * len(self.devices)
        self._batch_fn, self._params, self._group_of_point, self.compile_s = _compiled_batch(
            sweep, controller, self.width, on_phase or (lambda name: None), self.devices)

    def run(self, first: int, length: int, on_samples=None) -> dict:
        samples = np.arange(first, first + length)
        group_of_sample = self._group_of_point[samples // self.repetitions]
        pieces = []  # (rows of the chunk, metrics of those rows)
        for group in dict.fromkeys(group_of_sample.tolist()):  # a compiled call never mixes epochs
            rows = np.flatnonzero(group_of_sample == group)
            for lane0 in range(0, len(rows), self.width):
                taken = rows[lane0:lane0 + self.width]
                # Padded with the samples after, or (several epochs) with the call's last: a lane of another
                # epoch would run with this epoch's Sun and Moon, and a solver's loop waits for its slowest lane.
                pad = samples[taken[-1]] if self._group_of_point.max() > 0 else self.n_samples - 1
                idx = np.minimum(samples[taken[0]] + np.arange(self.width), pad)
                idx[:len(taken)] = samples[taken]
                out_lanes = self._batch_fn(_lanes(self._params, idx // self.repetitions), idx, group)
                pieces.append((taken, {k: np.asarray(v)[:len(taken)] for k, v in out_lanes.items()}))
                if on_samples is not None:
                    on_samples(len(taken))
        out = {k: np.empty((length, *v.shape[1:]), v.dtype) for k, v in pieces[0][1].items()}
        for rows, values in pieces:
            for k, v in values.items():
                out[k][rows] = v
        return out


def devices_for(samples: int, lanes_per_device: int) -> list:
    """The local devices a call of ``samples`` samples at ``lanes_per_device`` runs on: as few as hold them.

    Each device runs its own compiled copy of the program (``parallel.per_device``), so a device whose lanes
    would all be padding costs a whole compilation for nothing: on a CPU 15-30 s of a core per controller,
    the bulk of a small sweep's wall time (a 4-point sweep at the QFFC's 64 lanes per device fits one)."""
    devices = jax.local_devices()
    return devices[:max(1, min(len(devices), math.ceil(samples / lanes_per_device)))]


def default_chunk(n_samples: int, lanes_per_device: int) -> int:
    """Samples per saved chunk: one compiled batch of the widest controller on every local device (on 2 CPU
    cores about a minute of FOMPC years; on a GPU one call of tens of thousands of lanes), so a kill loses
    little and no compiled batch is left half empty.  Memory is bounded by the compiled batch, not the chunk."""
    return max(1, min(n_samples, lanes_per_device * jax.local_device_count()))


def lane_plan(sweep: Sweep, controller: str, chunk: int | None = None) -> lanes_mod.LanePlan:
    """The width of ``controller``'s compiled call on this process's devices (``geojax.lanes.plan``): the
    sweep's ``lanes`` if set (``ValueError`` if it cannot fit), else the platform's for a chunk of ``chunk``
    samples (default: the whole sweep)."""
    points = list(_points(sweep))
    scenarios = [_scenario(sweep, controller, points[i]) for i in epoch_axis.groups(points)[0]]  # one epoch's
    ctrl = sweep.custom.get(controller) or controller_of(scenarios)
    n_satellites = len(scenarios[0].satellites) or 1  # a cluster's lane flies all its satellites
    if scenarios[0].satellites:
        scenarios = [m for sc in scenarios for m in sc.satellites]
    samples = math.ceil(min(chunk or math.inf, sweep.n_points * sweep.repetitions) / jax.local_device_count())
    n_cycles = cycle_count(scenarios[0].days)
    own_reference = reference_per_sample(scenarios, ctrl)
    states = states_of(scenarios[0].config, sweep.parts)  # the parts' kept columns
    kept = len(CYCLE_NAMES) + sum(m.columns_per_cycle for m in states) if sweep.cycles else 0

    def records():  # traced only where the width depends on memory (``lanes.plan``)
        return record_bytes_per_cycle(prepare(scenarios[:1], sweep.custom.get(controller), states=sweep.parts,
                                              shapes_only=True))

    plan = lanes_mod.plan(ctrl, n_cycles, samples * n_satellites, records, kept_records=kept,
                          reference_cycles=n_cycles + ctrl.reference_cycles if own_reference else 0,
                          requested=None if sweep.lanes is None else sweep.lanes * n_satellites)
    return plan if n_satellites == 1 else plan._replace(lanes=max(1, plan.lanes // n_satellites))


def _compiled_batch(sweep: Sweep, controller: str, width: int, on_phase, devices=None):
    """(function of (params [width], sample indices [width], epoch group) -> metrics, params of every grid point
    [n_points], the epoch group of every grid point [n_points], set-up seconds: each epoch's shared arrays and
    reference run, and the one compilation).  ``on_phase(name)`` is told when the compilation starts.

    What the samples of one epoch share (the environment grid, the predictor's reference or the segments each
    sample runs its own on, the Earth angle at the start) is an argument of the compiled call, not a constant
    in it, so one program serves every epoch (``geojax.sweep.epochs``)."""
    begun = time.perf_counter()
    points = list(_points(sweep))
    groups = epoch_axis.groups(points)
    scenarios = [_scenario(sweep, controller, p) for p in points]
    if scenarios[0].satellites:
        return compiled_cluster_batch(sweep, controller, width, on_phase, devices, scenarios, groups, _lanes,
                                      DISPERSION_STREAM)
    batches = [prepare([scenarios[i] for i in group], sweep.custom.get(controller), states=sweep.parts)
               for group in groups]
    batch = batches[0]
    if any(b.reference_per_sample != batch.reference_per_sample for b in batches):
        raise ValueError(f"grid.{epoch_axis.KEY}: the other axes must vary the same leaves at every epoch")
    # The step compiled for the controller's CPU width whatever the batch (``Sizing.lanes_cpu``): the
    # fusion boundaries it sets move the last bit, so every width gives the same numbers.
    one_rollout = rollout_fn(batch, lanes=batch.controller.sizing.lanes_cpu)
    base_key = jax.random.key(sweep.seed)
    dispersion = (jnp.asarray(sweep.dispersion["mee_1sigma"]) * jnp.array([1e3, 1, 1, 1, 1, 1]),
                  jnp.asarray(sweep.dispersion["offset_ecef_1sigma_km"]) * 1e3)

    def shared_of(b: Batch, group) -> tuple:
        first = scenarios[group[0]]
        angle0 = earth_rotation_angle_rad(first.epoch_tt_s, first.epoch_tt_s, first.tt_minus_ut1_s)
        return b.shared, b.reference_env if b.reference_per_sample else None, jnp.asarray(angle0)

    def one(p, j, shared, reference_env, angle0):
        key = jax.random.fold_in(base_key, j)
        if sweep.dispersed:
            p = disperse(p, jax.random.fold_in(key, DISPERSION_STREAM), *dispersion, angle0, batch.dynamics)
        _, records, out = one_rollout(p, key, shared=shared, reference_env=reference_env)
        if sweep.cycles:
            out.update({f"cycles__{k}": v for k, v in cycle_series(records, batch.states).items()})
        return out

    shared = [shared_of(b, g) for b, g in zip(batches, groups, strict=True)]
    on_phase(f"{controller}: compiling")
    lanes = np.zeros(width, dtype=int)
    run, _ = per_device(jax.vmap(one, in_axes=(0, 0, None, None, None)), (_lanes(batch.params, lanes), lanes),
                        devices=devices, shared=shared[0], traced_as=("sweep", _identity(sweep, controller, scenarios[0], batch)))
    # Every grid point's params, in point order (each group's batch stacks its own points).
    order = np.concatenate(groups)
    params = jax.tree_util.tree_map(lambda *xs: jnp.concatenate(xs)[np.argsort(order)], *[b.params for b in batches])
    group_of_point = np.empty(len(points), dtype=int)
    for g, group in enumerate(groups):
        group_of_point[group] = g
    return (lambda p, idx, g: run(p, np.asarray(idx), shared=shared[g]), params, group_of_point,
            time.perf_counter() - begun)


def _identity(sweep: Sweep, controller: str, sc, batch: Batch):
    """What, beside its arguments' shapes, fixes the program ``_compiled_batch`` compiles (``geojax.traced``): the
    closed loop's settings as ``simulate`` keeps them, and what ``one`` reads of the sweep (seed, dispersion, cycle
    records, the metrics' cycle count); None for a user's controller (its code is not in traced's digest)."""
    if sweep.custom.get(controller) is not None or controller not in REGISTRY or sweep.parts or sc.config["states"]:
        return None  # a user's code (a controller's, a part's) is not in traced's digest
    settings = repr(sorted(static_settings(sc.config["controller"], batch.controller.fields).items()))
    return program_identity(sc, controller, settings, batch.controller.sizing.lanes_cpu, batch.step_s, batch.n_cycles,
                            batch.reference_per_sample, sweep.seed, sweep.dispersed, repr(sweep.dispersion),
                            sweep.cycles)


@jax.jit  # one small program for every leaf (eagerly, a gather compiled per leaf shape, each waiting for a core
#           while the controllers' loops compile: 2-10 s of a cold two-controller sweep)
def _lanes(params, point_index):
    """The params of each lane's grid point."""
    return jax.tree_util.tree_map(lambda x: x[point_index], params)
