"""Monte Carlo sweeps: a grid over scenario parameters x repetitions x controllers (DESIGN.md "Contracts", "Scale").

A sweep file names a base scenario, fixed overrides, a grid of values for
parameters given by dotted paths (``thrusters.beta_max_deg``,
``controller.horizon``, ``errors.h_rv``, ...), the controllers and the
repetitions:

    name = "fig9"
    scenario = "li2022-qffc"
    controllers = ["qffc", "fompc"]
    repetitions = 20
    seed = 0
    cycles = false             # true: also keep per-cycle records (/cycles/<name> [controller, grid..., reps, cycle])
    [set]                      # fixed overrides, any scenario key
    "thrusters.alpha_max_deg" = 90.0
    [grid]                     # one axis per key, in this order
    "thrusters.beta_max_deg" = [45.0, 50.0, 60.0, 70.0, 80.0, 90.0]

Every swept value is validated by loading the scenario with it (so the ranges
and the arm-limit checks of ``geojax.scenario`` apply).  Swept parameters are
array leaves of ``simulate.LoopParams``, so each controller compiles once
(the FOMPC's horizon padded to the largest N of the sweep) and the batch is
vmapped and sharded over the local devices, ``LANES_PER_DEVICE`` samples per
device per call whatever the sweep, so memory does not grow with it.  Sample
``j`` of a controller (grid point ``j // reps``, repetition ``j % reps``) draws
its errors and annealing from ``fold_in(key(seed), j)``: the same draws for both
controllers (a paired comparison) and independent of the chunk size, the device
count and the resume point.

Each finished chunk is saved at once to ``OUT.parts/`` (written to a temporary
name and renamed, so a kill leaves either the whole chunk or nothing); when
every chunk is in, the HDF5 file is written atomically and the parts removed.
``resume=True`` picks up the saved chunks (with the cut they were made with).
The file's ``wall_s`` and ``compile_s`` count the last run only.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import math
import os
import shutil
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from geojax import run, scenario as scenario_mod, store
from geojax.metrics import CYCLE_NAMES, NAMES as METRIC_NAMES
from geojax.parallel import shard_batch
from geojax.progress import Progress


# Parameters a sweep may vary: the scenario keys that are array leaves of simulate.LoopParams.
SWEEPABLE = (
    "thrusters.beta_max_deg", "thrusters.beta_min_deg", "thrusters.alpha_max_deg", "thrusters.alpha_min_deg",
    "thrusters.thrust_n", "thrusters.isp_s", "thrusters.min_burn_s",
    "errors.h_rv", "errors.h_att",
    "controller.horizon", "controller.di_max", "controller.penalty", "controller.vdt_estimate",
)
STATUS_OK, STATUS_NO_SOLUTION, STATUS_UNSTABLE = 0, 1, 2
# Samples per device in one compiled call, per controller (measured on 2 CPU cores, one year of li2022):
# the QFFC's per-step work is small, so wide batches amortise the loop (s per orbit per sample: 3.2e-4
# at 8 lanes, 1.2e-4 at 64); the FOMPC's annealing is already a wide vmap, so 8 lanes reach its
# throughput (2.4e-3 at 8 and at 32) and a small sweep pads less.  Fixed per controller, whatever the
# sweep or the chunk, because XLA's vectorisation (and so the last bit of every result) depends on
# the batch shape; memory is bounded by this width, not by the sweep.
LANES_PER_DEVICE = {"qffc": 64, "fompc": 8}


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
    cycles: bool = False  # keep the per-cycle records (metrics.CYCLE_NAMES)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.grid.values())

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)


def load(path: str | Path, changes: dict | None = None) -> Sweep:
    """Read and validate a sweep file; ``ValueError`` with one line naming the fault.

    ``changes`` replaces top-level keys and adds to ``[set]`` (a study's quick
    run: ``{"repetitions": 2, "set": {"duration.days": 30}}``); the sweep then
    stores its changed text.
    """
    from geojax.simulate import CONTROLLERS

    path = Path(path)
    raw, text = scenario_mod.read_toml_file(path, "sweep")
    if changes:
        raw = {**raw, **changes, "set": {**raw.get("set", {}), **changes.get("set", {})}}
        text = scenario_mod.to_toml(raw)
    allowed = {"name", "scenario", "controllers", "repetitions", "seed", "set", "grid", "cycles"}
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown key; allowed: {', '.join(sorted(allowed))}")
    if "scenario" not in raw:
        raise ValueError("scenario: missing (the base scenario, a shipped name or a .toml path)")
    controllers = raw.get("controllers", ["qffc"])
    if not (isinstance(controllers, list) and controllers and all(c in CONTROLLERS for c in controllers)):
        raise ValueError(f"controllers: must be a non-empty list of {', '.join(CONTROLLERS)}, got {controllers!r}")
    reps, seed = raw.get("repetitions", 1), raw.get("seed", 0)
    if not (isinstance(reps, int) and not isinstance(reps, bool) and reps >= 1):
        raise ValueError(f"repetitions: must be an integer >= 1, got {reps!r}")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"seed: must be an integer >= 0, got {seed!r}")
    if not isinstance(raw.get("cycles", False), bool):
        raise ValueError(f"cycles: must be true or false, got {raw['cycles']!r}")
    grid = raw.get("grid", {})
    if not isinstance(grid, dict) or not grid:
        raise ValueError("grid: must be a table with at least one parameter, e.g. \"thrusters.beta_max_deg\" = [60, 70]")
    fixed = dict(raw.get("set", {}))
    for key, values in grid.items():
        if key not in SWEEPABLE:
            raise ValueError(f"grid.{key}: unknown parameter path; sweepable: {', '.join(SWEEPABLE)}")
        if not isinstance(values, list) or not values:
            raise ValueError(f"grid.{key}: must be a non-empty list of numbers, got {values!r}")
        for value in values:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"grid.{key}: must be a list of numbers, got {value!r}")
    sweep = Sweep(str(raw.get("name", path.stem)), str(raw["scenario"]), tuple(controllers), reps, seed, fixed,
                  {k: list(v) for k, v in grid.items()}, text, raw.get("cycles", False))
    for point in _points(sweep):  # every value within its range, every combination physically possible
        _scenario(sweep, sweep.controllers[0], point)
    return sweep


def _points(sweep: Sweep):
    keys = list(sweep.grid)
    for values in itertools.product(*sweep.grid.values()):
        yield dict(zip(keys, values, strict=True))


def _scenario(sweep: Sweep, controller: str, point: dict):
    overrides = {**sweep.fixed, **point, "controller.kind": controller}
    if "controller.horizon" in point:
        overrides["controller.horizon"] = int(point["controller.horizon"])
    if "controller.vdt_estimate" in point:
        overrides["controller.vdt_estimate"] = bool(point["controller.vdt_estimate"])
    return scenario_mod.load(sweep.scenario, overrides)


def run_sweep(sweep: Sweep, out: str | Path, resume: bool = False, chunk: int | None = None,
              progress: bool | None = None) -> Path:
    """Run every sample not yet saved, then write ``out`` (HDF5).  Returns its path."""
    out = Path(out)
    parts = out.with_name(out.name + ".parts")
    digest = hashlib.sha256(sweep.text.encode()).hexdigest()
    if out.exists() and not resume:
        raise ValueError(f"--out {str(out)!r}: exists; pass --resume to continue it or choose another file")
    if out.exists() and not parts.exists():
        if store.read_h5(out)[1].get("config_toml") != sweep.text:
            raise ValueError(f"--resume: {str(out)!r} holds the results of a different sweep file")
        return out  # finished earlier
    n_samples = sweep.n_points * sweep.repetitions
    if chunk is not None and chunk < 1:
        raise ValueError(f"--chunk: must be >= 1, got {chunk}")
    if parts.exists():
        if not resume:
            raise ValueError(f"--out {str(out)!r}: an unfinished sweep is in {str(parts)!r}; pass --resume")
        if (parts / "sweep.sha256").read_text().strip() != digest:
            raise ValueError(f"--resume: {str(parts)!r} belongs to a different sweep file")
        # The chunks on disk fix the cut: a resumed sweep keeps it, whatever the device count.
        started = int((parts / "chunk").read_text())
        if chunk is not None and chunk != started:
            raise ValueError(f"--chunk: the unfinished sweep in {str(parts)!r} was cut into chunks of {started}; "
                             f"resume with --chunk {started} or without --chunk")
        chunk = started
    else:
        chunk = chunk or default_chunk(n_samples)
        fresh = parts.with_name(f".{parts.name}.tmp-{os.getpid()}")  # complete before it is visible
        shutil.rmtree(fresh, ignore_errors=True)
        fresh.mkdir(parents=True)
        _atomic_write(fresh / "chunk", str(chunk).encode())
        _atomic_write(fresh / "sweep.sha256", digest.encode())
        os.replace(fresh, parts)

    start = time.perf_counter()
    results, compile_s = {}, 0.0
    total = len(sweep.controllers) * n_samples
    with Progress(total, "samples", enabled=progress) as bar:
        for controller in sweep.controllers:
            done = {int(p.stem.split("_")[-1]): p for p in parts.glob(f"{controller}_*.npz")}
            bar.update(sum(_chunk_len(s, chunk, n_samples) for s in done))
            todo = [s for s in range(0, n_samples, chunk) if s not in done]
            width = LANES_PER_DEVICE[controller] * jax.device_count()
            if todo:
                batch_fn, params, seconds = _compiled_batch(sweep, controller, width)
                compile_s += seconds
            for s in todo:
                pieces = []
                for lane0 in range(s, s + _chunk_len(s, chunk, n_samples), width):
                    idx = np.minimum(np.arange(lane0, lane0 + width), n_samples - 1)  # pad with the last sample
                    out_lanes = batch_fn(_lanes(params, idx // sweep.repetitions), idx)
                    pieces.append({k: np.asarray(v) for k, v in out_lanes.items()})
                    bar.update(min(width, s + _chunk_len(s, chunk, n_samples) - lane0))
                values = {k: np.concatenate([p[k] for p in pieces])[: _chunk_len(s, chunk, n_samples)] for k in pieces[0]}
                _atomic_write(parts / f"{controller}_{s:09d}.npz", _npz_bytes(values))
            files = sorted(parts.glob(f"{controller}_*.npz"))
            pieces = [dict(np.load(f)) for f in files]
            results[controller] = {k: np.concatenate([p[k] for p in pieces]) for k in pieces[0]}
    shape = (len(sweep.controllers), *sweep.shape, sweep.repetitions)
    stacked = lambda k: np.stack([results[c][k] for c in sweep.controllers])  # noqa: E731
    metrics = {k: stacked(k).reshape(shape) for k in METRIC_NAMES}
    groups = {}
    if sweep.cycles:
        groups["cycles"] = {k: stacked(f"cycles__{k}").reshape(*shape, -1) for k in CYCLE_NAMES}
    status = np.where(metrics["cycles_without_solution"] > 0, STATUS_NO_SOLUTION, STATUS_OK)
    unstable = ~np.isfinite(metrics["dv_per_year_mps"]) | (metrics["max_abs_dlon_deg"] > _box_deg(sweep))
    status = np.where(unstable, STATUS_UNSTABLE, status).astype(np.int8)
    grid = {k.replace(".", "__"): np.asarray(v, dtype=float) for k, v in sweep.grid.items()}
    grid["controller"] = np.array(sweep.controllers, dtype="S")
    wall_s = time.perf_counter() - start
    store.write_h5(out, {"grid": grid, "metrics": metrics, "status": {"code": status}, **groups}, sweep.text, wall_s,
                   attrs={"kind": "sweep", "name": sweep.name, "grid_axes": ",".join(["controller", *sweep.grid]),
                          "compile_s": compile_s,
                          "status_codes": "0 ok, 1 cycles without solution, 2 unstable (left the box)"})
    shutil.rmtree(parts)
    return out


def default_chunk(n_samples: int) -> int:
    """Samples per saved chunk: one compiled batch of the widest controller (about a minute of FOMPC
    years on 2 cores), so a kill loses little and no compiled batch is left half empty.

    Memory is bounded by the compiled batch (``LANES_PER_DEVICE`` per device), not by the chunk.
    """
    return max(1, min(n_samples, max(LANES_PER_DEVICE.values()) * jax.device_count()))


def _box_deg(sweep: Sweep) -> float:
    return float(_scenario(sweep, sweep.controllers[0], next(_points(sweep))).config["station"]["box_half_width_deg"])


def _chunk_len(start: int, chunk: int, n_samples: int) -> int:
    return min(chunk, n_samples - start)


def _compiled_batch(sweep: Sweep, controller: str, width: int):
    """(function of (params [width], sample indices [width]) -> metrics, params of every grid point [n_points],
    compilation seconds)."""
    from geojax.metrics import closed_loop_metrics, cycle_series
    from geojax.simulate import rollout

    scenarios = [_scenario(sweep, controller, p) for p in _points(sweep)]
    loop = run.closed_loop_setup(scenarios[0], max(s.config["controller"]["horizon"] for s in scenarios))
    params = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *[run.loop_params(s) for s in scenarios])
    fm, base_key = scenarios[0].force_model, jax.random.key(sweep.seed)

    def one(p, j):
        final, rec = rollout(loop.state, loop.cycles_env, fm, loop.step_s, loop.reference, p,
                             jax.random.fold_in(base_key, j), controller, loop.annealing)
        out = closed_loop_metrics(rec, final, p.target, loop.n_cycles)
        if sweep.cycles:
            out.update({f"cycles__{k}": v for k, v in cycle_series(rec).items()})
        return out

    def placed(p, idx):
        args = (p, jnp.asarray(idx))
        return shard_batch(args) if jax.device_count() > 1 else args

    start = time.perf_counter()
    lanes = np.zeros(width, dtype=int)
    compiled = jax.jit(jax.vmap(one)).lower(*placed(_lanes(params, lanes), lanes)).compile()
    return lambda p, idx: compiled(*placed(p, idx)), params, time.perf_counter() - start


def _lanes(params, point_index):
    """The params of each lane's grid point."""
    return jax.tree_util.tree_map(lambda x: x[point_index], params)


def _npz_bytes(values: dict) -> bytes:
    import io

    buffer = io.BytesIO()
    np.savez(buffer, **values)
    return buffer.getvalue()


def _atomic_write(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
