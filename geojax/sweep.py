"""Monte Carlo sweeps: a grid over scenario parameters x repetitions x controllers (DESIGN.md "Contracts", "Scale").

A sweep file names a base scenario, fixed overrides, a grid of values for
any scenario keys given by dotted paths (``thrusters.beta_max_deg``,
``controller.horizon``, ``errors.h_rv``, ``station.lon_deg``,
``spacecraft.srp_area_m2``, ``orbit.L_rad``, ...), the controllers, the
repetitions and optional Monte Carlo dispersions of the initial state:

    name = "fig9"
    scenario = "li2022-qffc"
    controllers = ["qffc", "fompc"]
    repetitions = 20
    seed = 0
    cycles = false             # true: also keep per-cycle records (/cycles/<name> [controller, grid..., reps, cycle])
    lanes = 1024               # optional: samples per device per compiled call (default: the platform's, geojax.lanes)
    [set]                      # fixed overrides, any scenario key
    "thrusters.alpha_max_deg" = 90.0
    [grid]                     # one axis per key, in this order
    "thrusters.beta_max_deg" = [45.0, 50.0, 60.0, 70.0, 80.0, 90.0]
    [dispersion]               # optional: 1-sigma Gaussian errors of each sample's initial state
    mee_1sigma = [0.1, 1e-6, 1e-6, 1e-6, 1e-6, 1e-5]   # p (km), f, g, h, k, L (rad)
    offset_ecef_1sigma_km = [1.0, 1.0, 1.0]             # position offset along ECEF x, y, z

A grid axis ``"epoch.utc" = ["2027-01-01T12:00:00", ...]`` (dates, not numbers) flies the same slot from
each date: the base scenario moved as ``scenario.started_at`` moves it (``geojax.epoch_axis`` says how, and
why the points of one epoch share their environment in every compiled call).

Every grid point is a scenario loaded with its values, so every range and
check of ``geojax.scenario`` applies and every key that becomes an array leaf
of ``params.Params`` (or changes the initial state or the force model) can be
swept; keys that set the compiled loop's shape (step, duration, dynamics,
epoch, the FOMPC's annealing size, a thrust law) cannot, and say so.  Each
controller compiles once (the FOMPC's horizon padded to the largest N of the
sweep); a sweep that varies the initial state or the forces runs each sample's
own predictor reference inside the batch.  The batch is
vmapped and spread over the local devices, each running one compiled call of
the platform's width (``geojax.lanes``: the controller's measured width on a
CPU, the widest batch that fits an accelerator's memory; ``lanes = N`` in the
file or ``--lanes N`` fixes it), so memory does not grow with the sweep and a
sample's numbers do not depend on the width.  Sample
``j`` of a controller (grid point ``j // reps``, repetition ``j % reps``) draws
its errors and annealing from ``fold_in(key(seed), j)`` and its dispersion from
``fold_in(fold_in(key(seed), j), DISPERSION_STREAM)``: the same draws for both
controllers (a paired comparison) and independent of the chunk size, the device
count and the resume point.

Each finished chunk is saved at once to ``OUT.parts/`` (written to a temporary
name and renamed, so a kill leaves either the whole chunk or nothing); when
every chunk is in, the HDF5 file is written atomically and the parts removed.
``resume=True`` picks up the saved chunks (with the cut they were made with).
The file's ``wall_s`` and ``compile_s`` count the last run only; ``compile_s`` is the set-up of every
controller's batch: its shared arrays and the predictor's reference run, and the compilation.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import itertools
import math
import os
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from geojax import epoch_axis, lanes as lanes_mod, scenario as scenario_mod, store
from geojax.physics.frames import earth_rotation_angle_rad
from geojax.loop.metrics import CYCLE_NAMES, STATUS_TEXT, cycle_series
from geojax.loop.rollout import rollout_fn
from geojax.loop.setup import Batch, controller_of, cycle_count, disperse, prepare, reference_per_sample
from geojax.params import Field, check_table
from geojax.parallel import per_device
from geojax.progress import Progress
from geojax.results import dims_of_sweep


MAX_SAMPLES = 10_000_000  # samples per sweep file (a larger campaign is several files, or a cluster)
DISPERSION_STREAM = 0x5EED  # the key stream of the initial-state dispersion, apart from the rollout's cycles
DISPERSION_FIELDS = {
    "mee_1sigma": Field(list, [0.0] * 6, length=6),
    "offset_ecef_1sigma_km": Field(list, [0.0] * 3, length=3),
}


@dataclasses.dataclass(frozen=True)
class Sweep:
    name: str
    scenario: str
    controllers: tuple[str, ...]
    repetitions: int
    seed: int
    fixed: dict
    grid: dict  # {path: [values]}, in axis order
    text: str  # the sweep file, stored in the results
    cycles: bool = False  # keep the per-cycle records (loop.metrics.CYCLE_NAMES)
    dispersion: dict = dataclasses.field(default_factory=lambda: {k: f.default for k, f in DISPERSION_FIELDS.items()})
    custom: dict = dataclasses.field(default_factory=dict)  # {name: Controller} of a user's own controllers
    lanes: int | None = None  # samples per device per compiled call; None: the platform's (``geojax.lanes``)

    @property
    def dispersed(self) -> bool:
        return any(x != 0.0 for values in self.dispersion.values() for x in values)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.grid.values())

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)


def load(path: str | Path, changes: dict | None = None, controllers: dict | None = None) -> Sweep:
    """Read and validate a sweep file; ``ValueError`` with one line naming the fault.

    ``changes`` replaces top-level keys and adds to ``[set]`` (a study's quick
    run: ``{"repetitions": 2, "set": {"duration.days": 30}}``); the sweep then
    stores its changed text.  ``controllers`` ({name: Controller}) adds a user's own controllers, named
    in the file's ``controllers`` list like the registered ones.
    """
    from geojax.control import REGISTRY, lookup

    path = Path(path)
    controllers_arg = controllers
    raw, text = scenario_mod.read_toml_file(path, "sweep")
    if changes:
        raw = {**raw, **changes, "set": {**raw.get("set", {}), **changes.get("set", {})}}
        text = scenario_mod.to_toml(raw)
    allowed = {"name", "scenario", "controllers", "repetitions", "seed", "set", "grid", "cycles", "dispersion",
               "lanes"}
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown key; allowed: {', '.join(sorted(allowed))}")
    if "scenario" not in raw:
        raise ValueError("scenario: missing (the base scenario, a shipped name or a .toml path)")
    if not isinstance(raw.get("name", ""), str) or not isinstance(raw["scenario"], str):
        key = "name" if not isinstance(raw.get("name", ""), str) else "scenario"
        raise ValueError(f"{key}: must be a string, got {raw[key]!r}")
    controllers = raw.get("controllers", ["qffc"])
    known = {**REGISTRY, **(controllers_extra := dict(controllers_arg or {}))}
    if not (isinstance(controllers, list) and controllers
            and all(isinstance(c, str) and (c in known or ":" in c) for c in controllers)
            and len(set(controllers)) == len(controllers)):
        raise ValueError(f"controllers: must be a non-empty list of distinct names from {', '.join(known)} or "
                         f"controllers of one's own as 'package.module:NAME', got {controllers!r}")
    for name in controllers:
        if name not in known:
            try:
                lookup(name)
            except ValueError as err:
                raise ValueError(f"controllers: {str(err).removeprefix('controller.kind: ')}") from None
    reps, seed = raw.get("repetitions", 1), raw.get("seed", 0)
    if not (isinstance(reps, int) and not isinstance(reps, bool) and 1 <= reps <= MAX_SAMPLES):
        raise ValueError(f"repetitions: must be an integer from 1 to {MAX_SAMPLES}, got {reps!r}")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"seed: must be an integer >= 0, got {seed!r}")
    lanes = lanes_mod.checked(raw.get("lanes"))
    if not isinstance(raw.get("cycles", False), bool):
        raise ValueError(f"cycles: must be true or false, got {raw['cycles']!r}")
    grid = raw.get("grid", {})
    if not isinstance(grid, dict) or not grid:
        raise ValueError("grid: must be a table with at least one parameter, e.g. \"thrusters.beta_max_deg\" = [60, 70]")
    fixed = raw.get("set", {})
    if not isinstance(fixed, dict):
        raise ValueError(f"set: must be a table of scenario keys, e.g. \"duration.days\" = 30, got {fixed!r}")
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ValueError(f"grid.{key}: must be a non-empty list of values, got {values!r}")
        if key == epoch_axis.KEY:
            epoch_axis.check_values(values)
            continue
        for value in values:
            if not isinstance(value, (int, float, bool)):
                raise ValueError(f"grid.{key}: must be a list of numbers (or true/false), got {value!r}")
    n_samples = math.prod(len(v) for v in grid.values()) * reps * len(controllers)
    if n_samples > MAX_SAMPLES:
        raise ValueError(f"grid: {n_samples} samples in all, more than {MAX_SAMPLES}; split the sweep")
    dispersion = check_table("dispersion.", raw.get("dispersion", {}), DISPERSION_FIELDS)
    sweep = Sweep(str(raw.get("name", path.stem)), str(raw["scenario"]), tuple(controllers), reps, seed, dict(fixed),
                  {k: list(v) for k, v in grid.items()}, text, raw.get("cycles", False), dispersion,
                  {k: v for k, v in controllers_extra.items() if k in controllers}, lanes)
    for controller in sweep.controllers:  # every value within its range, every batch compilable
        prepare_check(sweep, controller)
    return sweep


def prepare_check(sweep: Sweep, controller: str) -> None:
    """Load every grid point's scenario (the ranges and checks of ``geojax.scenario``) and check that they
    differ only in array leaves (``loop.setup``), naming the grid key at fault."""
    from geojax.loop.setup import _check_static, controller_of

    points = list(_points(sweep))
    scenarios = [_scenario(sweep, controller, p) for p in points]
    ctrl = sweep.custom.get(controller) or controller_of(scenarios)
    groups = epoch_axis.groups(points)
    try:
        for group in groups:  # within an epoch, as every sweep
            _check_static([scenarios[i] for i in group], ctrl)
        _check_static([scenarios[g[0]] for g in groups], ctrl, skip=epoch_axis.STATIC_KEYS)  # and between them
    except ValueError as err:
        raise ValueError(f"grid.{err}") from None


def _points(sweep: Sweep):
    keys = list(sweep.grid)
    for values in itertools.product(*sweep.grid.values()):
        yield dict(zip(keys, values, strict=True))


def _scenario(sweep: Sweep, controller: str, point: dict):
    overrides = {**sweep.fixed, **point, "controller.kind": controller}
    if isinstance(point.get("controller.vdt_estimate"), (int, float)):
        overrides["controller.vdt_estimate"] = bool(point["controller.vdt_estimate"])  # 0 / 1 on a numeric axis
    if epoch_axis.KEY in point:
        return epoch_axis.scenario_at(sweep.scenario, overrides.pop(epoch_axis.KEY), overrides,
                                      sweep.custom.get(controller))
    return scenario_mod.load(sweep.scenario, overrides, sweep.custom.get(controller))


def run_sweep(sweep: Sweep, out: str | Path, resume: bool = False, chunk: int | None = None,
              progress: bool | None = None, ray: str | None = None, workers: int | None = None,
              lanes: int | None = None) -> Path:
    """Run every sample not yet saved, then write ``out`` (HDF5).  Returns its path.

    ``lanes``: samples per device per compiled call, instead of the sweep file's or the platform's
    (``geojax.lanes``); one that cannot fit the device is refused before anything is compiled or written.

    ``ray``: run the chunks as Ray tasks (``geojax.cluster``): ``"local"`` starts a Ray instance on this
    machine, ``"auto"``, ``"HOST:PORT"`` or ``"ray://HOST:PORT"`` joins a running cluster; ``workers`` Ray
    worker processes (default one per GPU, or per node without GPUs).  The results are bit for bit those of a
    local run.
    """
    out = store.check_output_file(out)
    if workers is not None and ray is None:
        raise ValueError("--workers: only with --ray (a local sweep uses this process's devices)")
    if workers is not None and not 1 <= workers <= 10_000:
        raise ValueError(f"--workers: must be from 1 to 10000, got {workers}")
    parts = out.with_name(out.name + ".parts")
    digest = hashlib.sha256(sweep.text.encode()).hexdigest()
    if chunk is not None and chunk < 1:
        raise ValueError(f"--chunk: must be >= 1, got {chunk}")
    if (out.exists() or parts.exists()) and not resume:
        where = str(out) if out.exists() else f"{str(parts)!r} (an unfinished sweep)"
        raise ValueError(f"--out {str(out)!r}: {where} exists; pass --resume to continue it or choose another file")
    store.remove_stale(out)
    store.remove_stale(parts)
    if out.exists():
        if store.read_attrs(out).get("config_toml") != sweep.text:
            raise ValueError(f"--resume: {str(out)!r} holds the results of a different sweep file")
        if parts.exists():  # killed while removing its parts after the file was written
            store.discard_folder(parts)
        return out  # finished earlier
    n_samples = sweep.n_points * sweep.repetitions
    if lanes is not None:
        sweep = dataclasses.replace(sweep, lanes=lanes)  # the file's identity (its text) unchanged: resumable
    widths = {c: lane_plan(sweep, c).lanes for c in sweep.controllers}  # refused here if it cannot fit
    with contextlib.ExitStack() as connection:
        if ray is not None:  # reach the cluster before anything is written
            from geojax import cluster

            connection.enter_context(cluster.connected(ray))
        if parts.exists():
            chunk = _resumed_chunk(parts, digest, chunk)
        else:
            if chunk is None and ray is not None:
                chunk = cluster.default_chunk(n_samples, ray_nodes())
            chunk = chunk or default_chunk(n_samples, max(widths.values()))
            fresh = store.temporary(parts)  # complete before it is visible
            fresh.mkdir(parents=True)
            store.atomic_write(fresh / "chunk", str(chunk).encode())
            store.atomic_write(fresh / "sweep.sha256", digest.encode())
            os.replace(fresh, parts)
        try:
            return _run_chunks(sweep, out, parts, chunk, progress, ray is not None, workers)
        except BaseException:
            if parts.exists() and not any(parts.glob("*.npz")):
                store.discard_folder(parts)  # nothing computed: leave nothing behind
            raise


def _resumed_chunk(parts: Path, digest: str, chunk: int | None) -> int:
    """The chunk size an unfinished sweep in ``parts`` was cut with (``ValueError`` if it is not ours)."""
    try:
        saved_digest = (parts / "sweep.sha256").read_text().strip()
        started = int((parts / "chunk").read_text())
    except (OSError, ValueError):
        raise ValueError(f"--resume: {str(parts)!r} is not the parts folder of a geojax sweep; "
                         f"remove it or choose another --out") from None
    if saved_digest != digest:
        raise ValueError(f"--resume: {str(parts)!r} belongs to a different sweep file")
    # The chunks on disk fix the cut: a resumed sweep keeps it, whatever the device count.
    if chunk is not None and chunk != started:
        raise ValueError(f"--chunk: the unfinished sweep in {str(parts)!r} was cut into chunks of {started}; "
                         f"resume with --chunk {started} or without --chunk")
    store.remove_stale_in(parts)  # chunk files a killed run was writing
    return started


def _run_chunks(sweep: Sweep, out: Path, parts: Path, chunk: int, progress: bool | None,
                on_ray: bool = False, workers: int | None = None) -> Path:
    n_samples = sweep.n_points * sweep.repetitions
    start = time.perf_counter()
    total = len(sweep.controllers) * n_samples
    todo, done = [], 0
    for controller in sweep.controllers:
        saved = {int(p.stem.split("_")[-1]) for p in parts.glob(f"{controller}_*.npz")}
        done += sum(_chunk_len(s, chunk, n_samples) for s in saved)
        todo += [(controller, s, _chunk_len(s, chunk, n_samples)) for s in range(0, n_samples, chunk) if s not in saved]

    def save(controller: str, first: int, values: dict) -> None:
        store.atomic_write(parts / f"{controller}_{first:09d}.npz", _npz_bytes(values))

    with Progress(total, "samples", enabled=progress) as bar:
        bar.skip(done)  # what an earlier run did is not in the rate
        if on_ray:
            from geojax import cluster

            compile_s = cluster.run_chunks(sweep, todo, save, bar, workers, make_runner=ChunkRunner)
        else:
            compile_s, runners = 0.0, {}
            for controller, first, length in todo:
                if controller not in runners:
                    runners[controller] = ChunkRunner(sweep, controller, chunk)
                    compile_s += runners[controller].compile_s
                    bar.restart(f"{controller} compiled in {runners[controller].compile_s:.1f} s "
                                f"({runners[controller].plan.lanes} lanes per device)")
                save(controller, first, runners[controller].run(first, length, bar.update))
    widths = "" if on_ray else ", ".join(f"{c} {r.plan.lanes}" for c, r in runners.items())
    return _write_results(sweep, out, parts, wall_s=time.perf_counter() - start, compile_s=compile_s, lanes=widths)


class ChunkRunner:
    """One controller of a sweep, compiled once for this process's devices: ``run(first, length)`` gives the
    metrics of samples ``first .. first + length - 1`` (numpy, one row per sample).

    The batch is ``plan.lanes`` samples per device whatever the chunk (the last call padded with the chunk's
    last sample); a sample's numbers depend on neither the chunk, the width, the device count nor the process
    that runs it: a local sweep and every Ray worker use this.
    """

    def __init__(self, sweep: Sweep, controller: str, chunk: int | None = None):
        self.n_samples = sweep.n_points * sweep.repetitions
        self.repetitions = sweep.repetitions
        self.plan = lane_plan(sweep, controller, chunk)
        self.width = self.plan.lanes * jax.local_device_count()
        self._batch_fn, self._params, self._group_of_point, self.compile_s = _compiled_batch(sweep, controller,
                                                                                            self.width)

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


def _write_results(sweep: Sweep, out: Path, parts: Path, wall_s: float, compile_s: float, lanes: str = "") -> Path:
    """Join the saved chunks of every controller into ``out`` (written atomically), then remove the parts.
    ``lanes``: the widths this run compiled ("qffc 128, fompc 32"; empty on a cluster, where each worker
    chooses its own)."""
    results = {}
    for controller in sweep.controllers:
        pieces = [dict(np.load(f)) for f in sorted(parts.glob(f"{controller}_*.npz"))]
        results[controller] = {k: np.concatenate([p[k] for p in pieces]) for k in pieces[0]}
    shape = (len(sweep.controllers), *sweep.shape, sweep.repetitions)
    names = sorted({k for c in sweep.controllers for k in results[c]})
    n_samples = sweep.n_points * sweep.repetitions

    def stacked(k):  # a metric one controller does not report (burns of a feedback law) is NaN there
        return np.stack([results[c].get(k, np.full(n_samples, np.nan)) for c in sweep.controllers])

    metrics = {k: stacked(k).reshape(shape) for k in names if k != "status" and not k.startswith("cycles__")}
    groups = {}
    if sweep.cycles:
        groups["cycles"] = {k: np.stack([results[c][f"cycles__{k}"] for c in sweep.controllers]).reshape(*shape, -1)
                            for k in CYCLE_NAMES}
    status = stacked("status").reshape(shape).astype(np.int8)
    grid = {k.replace(".", "__"): np.asarray(v, dtype="S" if k == epoch_axis.KEY else float)
            for k, v in sweep.grid.items()}
    grid["controller"] = np.array(sweep.controllers, dtype="S")
    base = scenario_mod.to_toml(_scenario(sweep, sweep.controllers[0], {}).config)  # [set] applied, fully resolved
    store.write_h5(out, {"grid": grid, "metrics": metrics, "status": {"code": status}, **groups}, sweep.text, wall_s,
                   attrs={"kind": "sweep", "name": sweep.name, "grid_axes": ",".join(["controller", *sweep.grid]),
                          "compile_s": compile_s, "lanes_per_device": lanes, "base_scenario_toml": base,
                          "status_codes": STATUS_TEXT},
                   dims=dims_of_sweep(list(sweep.grid), sweep.cycles))
    store.discard_folder(parts)
    return out


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
    samples = math.ceil(min(chunk or math.inf, sweep.n_points * sweep.repetitions) / jax.local_device_count())
    n_cycles = cycle_count(scenarios[0].days)
    own_reference = reference_per_sample(scenarios, ctrl)
    return lanes_mod.plan(ctrl, n_cycles, samples, kept_records=len(CYCLE_NAMES) if sweep.cycles else 0,
                          reference_cycles=n_cycles + ctrl.reference_cycles if own_reference else 0,
                          requested=sweep.lanes)


def ray_nodes() -> list[dict]:
    import ray

    return ray.nodes()


def _chunk_len(start: int, chunk: int, n_samples: int) -> int:
    return min(chunk, n_samples - start)


def _compiled_batch(sweep: Sweep, controller: str, width: int):
    """(function of (params [width], sample indices [width], epoch group) -> metrics, params of every grid point
    [n_points], the epoch group of every grid point [n_points], set-up seconds: each epoch's shared arrays and
    reference run, and the one compilation).

    What the samples of one epoch share (the environment grid, the predictor's reference or the segments each
    sample runs its own on, the Earth angle at the start) is an argument of the compiled call, not a constant
    in it, so one program serves every epoch (``geojax.epoch_axis``)."""
    begun = time.perf_counter()
    points = list(_points(sweep))
    groups = epoch_axis.groups(points)
    scenarios = [_scenario(sweep, controller, p) for p in points]
    batches = [prepare([scenarios[i] for i in group], sweep.custom.get(controller)) for group in groups]
    batch = batches[0]
    if any(b.reference_per_sample != batch.reference_per_sample for b in batches):
        raise ValueError(f"grid.{epoch_axis.KEY}: the other axes must vary the same leaves at every epoch")
    # The step compiled for the controller's CPU width whatever the batch (``Controller.lanes_cpu``): the
    # fusion boundaries it sets move the last bit, so every width gives the same numbers.
    one_rollout = rollout_fn(batch, lanes=batch.controller.lanes_cpu)
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
            out.update({f"cycles__{k}": v for k, v in cycle_series(records).items()})
        return out

    shared = [shared_of(b, g) for b, g in zip(batches, groups, strict=True)]
    lanes = np.zeros(width, dtype=int)
    run, _ = per_device(jax.vmap(one, in_axes=(0, 0, None, None, None)), (_lanes(batch.params, lanes), lanes),
                        shared=shared[0])
    # Every grid point's params, in point order (each group's batch stacks its own points).
    order = np.concatenate(groups)
    params = jax.tree_util.tree_map(lambda *xs: jnp.concatenate(xs)[np.argsort(order)], *[b.params for b in batches])
    group_of_point = np.empty(len(points), dtype=int)
    for g, group in enumerate(groups):
        group_of_point[group] = g
    return (lambda p, idx, g: run(p, np.asarray(idx), shared=shared[g]), params, group_of_point,
            time.perf_counter() - begun)


def _lanes(params, point_index):
    """The params of each lane's grid point."""
    return jax.tree_util.tree_map(lambda x: x[point_index], params)


def _npz_bytes(values: dict) -> bytes:
    import io

    buffer = io.BytesIO()
    np.savez(buffer, **values)
    return buffer.getvalue()

