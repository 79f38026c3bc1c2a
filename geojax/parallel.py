"""Spreading a batch over the local devices with ``jax.sharding`` (docs/design.md, "Scale").

On a CPU, XLA runs one device on about one core.  To use every core, start
Python with ``XLA_FLAGS=--xla_force_host_platform_device_count=N`` (N = cores)
before JAX is imported.  A batch whose
leading axis is sharded over the devices then runs on all of them with the
same compiled program.  ``per_device`` goes further: every device runs the very
program that one device would run on its share, so results do not depend on
the device count bit for bit (a sharded ``jit`` goes through XLA's SPMD
pipeline, which may fuse differently).
"""

from __future__ import annotations

import os

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec


DEVICE_COUNT_FLAG = "--xla_force_host_platform_device_count"


def use_host_cores(count: int | None = None, replace: bool = False) -> None:
    """Ask XLA for one CPU device per core (``count``, default all), unless ``XLA_FLAGS`` already says
    (``replace``: whatever it says; a Ray worker inherits its driver's flags but not its node).

    Takes effect only if no JAX computation has run yet in this process (the
    ``geojax`` command calls it first thing); later it changes nothing.
    """
    flags = with_host_device_count(os.environ.get("XLA_FLAGS", ""), count or os.cpu_count() or 1, replace)
    os.environ["XLA_FLAGS"] = flags


def with_host_device_count(flags: str, count: int, replace: bool = False) -> str:
    """``XLA_FLAGS`` text ``flags`` asking for ``count`` CPU devices: a device count ``flags`` gives is kept
    unless ``replace``; every other flag is kept, in its order."""
    kept = flags.split()
    if replace:
        kept = [f for f in kept if f.split("=", 1)[0] != DEVICE_COUNT_FLAG]
    if any(f.split("=", 1)[0] == DEVICE_COUNT_FLAG for f in kept):
        return " ".join(kept)
    return " ".join([*kept, f"{DEVICE_COUNT_FLAG}={count}"])


def batch_mesh() -> Mesh:
    return Mesh(np.array(jax.devices()), ("batch",))


def shard_batch(tree, mesh: Mesh | None = None):
    """Place a pytree whose leaves share a leading batch axis across the devices.

    The batch size must be a multiple of the device count (pad it if not).
    """
    mesh = mesh or batch_mesh()
    size = jax.tree_util.tree_leaves(tree)[0].shape[0]
    if size % mesh.size:
        raise ValueError(f"batch: {size} samples cannot be split evenly over {mesh.size} devices; pad to a multiple")
    return jax.device_put(tree, NamedSharding(mesh, PartitionSpec("batch")))


def replicate(tree, mesh: Mesh | None = None):
    """Place a pytree (the shared environment grid, the force model) on every device."""
    mesh = mesh or batch_mesh()
    return jax.device_put(tree, NamedSharding(mesh, PartitionSpec()))


def per_device(fn, example_args, devices=None, shared=(), traced_as=None):
    """``fn`` (every argument and result with a leading batch axis) compiled once for each device as the
    same single-device program, and a function that splits a batch evenly over the devices, runs the shares
    concurrently and joins the results (numpy).  Returns ``(run, compile_s)``.

    Each device runs exactly the program one device would run on its share, so results are bit for bit
    those of one device, whatever the device count.  (A ``jit`` sharded over a mesh, even through
    ``shard_map``, goes through XLA's SPMD pipeline, whose fusion choices can move the last bit; on a CPU it
    is also slower: propagation at batch 1024 on two devices ran 87 orbit-years/s sharded against 242 this
    way, ``benchmarks/propagate.py``.)  ``example_args`` fix the shapes: their batch is the whole batch, a
    multiple of the device count.

    ``shared``: arguments every device reads whole (an environment grid, a force model), passed after the
    batched ones, ``fn(*args, *shared)``; they are placed on each device once, and ``run(*args,
    shared=...)`` may replace them by values of the same shapes.

    ``traced_as``: (name, identity) to keep the traced program between runs (``geojax.traced``: a later run
    compiles, or loads from the cache, without tracing ``fn`` again); None traces it every run.
    """
    import time

    devices = list(devices or jax.local_devices())
    jitted = jax.jit(fn)

    def shares(args):
        size = jax.tree_util.tree_leaves(args)[0].shape[0]
        if size % len(devices):
            raise ValueError(f"batch: {size} samples cannot be split evenly over {len(devices)} devices; pad it")
        n = size // len(devices)
        return [jax.device_put(jax.tree_util.tree_map(lambda x: x[i * n:(i + 1) * n], args), d)
                for i, d in enumerate(devices)]

    def placed(values):
        return [jax.device_put(tuple(values), d) for d in devices]

    start = time.perf_counter()
    on_devices = placed(shared)
    if traced_as is not None:
        from geojax import traced

        jitted = traced.jitted(jitted, *traced_as, *shares(example_args)[0], *on_devices[0])
    compiled = _concurrently([lambda pair=pair: jitted.lower(*pair[0], *pair[1]).compile()
                              for pair in zip(shares(example_args), on_devices)])
    compile_s = time.perf_counter() - start

    def run(*args, shared=None):
        common = on_devices if shared is None else placed(shared)
        outs = [c(*share, *rest) for c, share, rest in zip(compiled, shares(args), common, strict=True)]  # async
        return jax.tree_util.tree_map(lambda *xs: np.concatenate([np.asarray(x) for x in xs]), *outs)

    return run, compile_s


def _concurrently(tasks):
    """The results of ``tasks`` (functions of nothing) run in threads at once (XLA compiles outside the GIL)."""
    return [task.result() for task in [Background(task) for task in tasks]]


class Background:
    """``task()`` (a function of nothing) started now in a thread of its own; ``result()`` waits for it and
    returns its value or raises its error.

    A daemon thread, joined a tenth of a second at a time: Ctrl-C reaches the waiting thread at once and the
    process may end without waiting for a compilation to finish (a thread pool would hold it for the whole
    compile; ``cli._interrupted`` ends such a process with ``os._exit``).
    """

    def __init__(self, task):
        import threading

        self._value, self._error = None, None
        self._thread = threading.Thread(target=self._run, args=(task,), daemon=True)
        self._thread.start()

    def _run(self, task):
        try:
            self._value = task()
        except BaseException as err:  # noqa: BLE001 (raised again in the caller's thread)
            self._error = err

    def result(self):
        while self._thread.is_alive():
            self._thread.join(0.1)
        if self._error is not None:
            raise self._error
        return self._value
