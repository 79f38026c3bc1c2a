"""Spreading a batch over the local devices with ``jax.sharding`` (DESIGN.md, "Scale").

On a CPU, XLA runs one device on about one core.  To use every core, start
Python with ``XLA_FLAGS=--xla_force_host_platform_device_count=N`` (N = cores)
before JAX is imported.  A batch whose
leading axis is sharded over the devices then runs on all of them with the
same compiled program; results do not depend on the device count.
"""

from __future__ import annotations

import os

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec


def use_host_cores(count: int | None = None) -> None:
    """Ask XLA for one CPU device per core (``count``, default all), unless ``XLA_FLAGS`` already says.

    Takes effect only if no JAX computation has run yet in this process (the
    ``geojax`` command calls it first thing); later it changes nothing.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" not in flags:
        count = count or os.cpu_count() or 1
        os.environ["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={count}".strip()


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
