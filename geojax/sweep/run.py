"""A sweep's run: the chunk plan, resume, the executor (``local`` or ``cluster``) and the HDF5 file."""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import os
import time
from pathlib import Path

import numpy as np

from geojax import scenario as scenario_mod, store
from geojax.sweep import epochs as epoch_axis
from geojax.loop.metrics import STATUS_TEXT
from geojax.progress import TICK_S, Progress
from geojax.results import dims_of_sweep
from geojax.sweep import cluster, local
from geojax.sweep.batch import ChunkRunner, default_chunk, lane_plan
from geojax.sweep.spec import Sweep, _scenario


def run_sweep(sweep: Sweep, out: str | Path, resume: bool = False, chunk: int | None = None,
              progress: bool | None = None, ray: str | None = None, workers: int | None = None,
              lanes: int | None = None, force: bool = False) -> Path:
    """Run every sample not yet saved, then write ``out`` (HDF5).  Returns its path.

    An ``out`` that exists (or its unfinished parts) is refused unless ``resume`` (continue it: the same sweep
    file) or ``force`` (start afresh: the unfinished parts are discarded, the file replaced when the new one is
    written).

    ``lanes``: samples per device per compiled call, instead of the sweep file's or the platform's
    (``geojax.lanes``); one that cannot fit the device is refused before anything is compiled or written.

    ``ray``: run the chunks as Ray tasks (``geojax.sweep.cluster``): ``"local"`` starts a Ray instance on this
    machine, ``"auto"``, ``"HOST:PORT"`` or ``"ray://HOST:PORT"`` joins a running cluster; ``workers`` Ray
    worker processes (default one per GPU, or per node without GPUs).  The results are bit for bit those of a
    local run.
    """
    out = store.check_output_file(out)
    if workers is not None and ray is None:
        raise ValueError("workers: only with ray=ADDRESS (a local sweep uses this process's devices)")
    if workers is not None and not 1 <= workers <= 10_000:
        raise ValueError(f"workers: must be from 1 to 10000, got {workers}")
    parts = out.with_name(out.name + ".parts")
    digest = hashlib.sha256(sweep.text.encode()).hexdigest()
    if chunk is not None and chunk < 1:
        raise ValueError(f"chunk: must be >= 1, got {chunk}")
    if force and resume:
        raise ValueError("force: not with resume=True (resume continues a sweep, force starts it afresh)")
    if (out.exists() or parts.exists()) and not (resume or force):
        where = str(out) if out.exists() else f"{str(parts)!r} (an unfinished sweep)"
        raise ValueError(f"out={str(out)!r}: {where} exists; pass resume=True to continue it, force=True to replace it, or choose another file")
    store.remove_stale(out)
    store.remove_stale(parts)
    if force and parts.exists():
        store.discard_folder(parts)
    if out.exists() and resume:
        if store.read_attrs(out).get("config_toml") != sweep.text:
            raise ValueError(f"resume: {str(out)!r} holds the results of a different sweep file")
        if parts.exists():  # killed while removing its parts after the file was written
            store.discard_folder(parts)
        return out  # finished earlier
    n_samples = sweep.n_points * sweep.repetitions
    if lanes is not None:
        sweep = dataclasses.replace(sweep, lanes=lanes)  # the file's identity (its text) unchanged: resumable
    widths = {c: lane_plan(sweep, c).lanes for c in sweep.controllers}  # refused here if it cannot fit
    with contextlib.ExitStack() as connection:
        if ray is not None:  # reach the cluster before anything is written
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
        raise ValueError(f"resume: {str(parts)!r} is not the parts folder of a geojax sweep; "
                         f"remove it or choose another output file") from None
    if saved_digest != digest:
        raise ValueError(f"resume: {str(parts)!r} belongs to a different sweep file")
    # The chunks on disk fix the cut: a resumed sweep keeps it, whatever the device count.
    if chunk is not None and chunk != started:
        raise ValueError(f"chunk: the unfinished sweep in {str(parts)!r} was cut into chunks of {started}; "
                         f"resume with chunk={started} or with no chunk given")
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

    with Progress(total, "samples", enabled=progress, tick_s=TICK_S) as bar:
        bar.skip(done)  # what an earlier run did is not in the rate
        if on_ray:
            compile_s = cluster.run_chunks(sweep, todo, save, bar, workers, make_runner=ChunkRunner)
            widths = ""
        else:
            compile_s, lanes = local.run_chunks(todo, save, bar,
                                                make_runner=lambda controller, on_phase: ChunkRunner(sweep, controller, chunk,
                                                                                            on_phase=on_phase))
            widths = ", ".join(f"{c} {n}" for c, n in lanes.items())
    return _write_results(sweep, out, parts, wall_s=time.perf_counter() - start, compile_s=compile_s, lanes=widths)


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
        kept = [k.removeprefix("cycles__") for k in results[sweep.controllers[0]] if k.startswith("cycles__")]
        groups["cycles"] = {k: np.stack([results[c][f"cycles__{k}"] for c in sweep.controllers]).reshape(*shape, -1)
                            for k in kept}  # CYCLE_NAMES and the extra states' columns (loop.metrics.cycle_series)
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


def saved_samples(out: str | Path) -> tuple[Path, int, int]:
    """(parts folder, chunks saved, samples they hold) of an unfinished sweep writing ``out``: what
    ``resume=True`` starts from (0, 0 where nothing was saved)."""
    parts = Path(out).with_name(Path(out).name + ".parts")
    chunks, samples = 0, 0
    for path in parts.glob("*.npz"):
        with np.load(path) as values:
            chunks, samples = chunks + 1, samples + len(values[values.files[0]])
    return parts, chunks, samples


def ray_nodes() -> list[dict]:
    import ray

    return ray.nodes()


def _chunk_len(start: int, chunk: int, n_samples: int) -> int:
    return min(chunk, n_samples - start)


def _npz_bytes(values: dict) -> bytes:
    import io

    buffer = io.BytesIO()
    np.savez(buffer, **values)
    return buffer.getvalue()
