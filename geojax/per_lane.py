"""A function run lane by lane under ``vmap``, so that its arithmetic is one sample's whatever the batch's width.

XLA's CPU compiler chooses a batched dot's loop order, and a reduction's partial sums, by the whole batch's shape,
so a sample's last bit can depend on how many samples it is batched with (measured: the MPC's condensed dynamics,
``einsum("jsv,jv->js")`` over 12 decisions, 40 of 120 values an ulp apart at 2 and 70 lanes).  ``lane_by_lane(fn)``
is ``fn`` with a batching rule of its own: a ``lax.map`` over the lanes, each computing ``fn`` unbatched in the same
compiled loop body at every width.  What it costs is the vectorisation across the batch inside ``fn``; in exchange
an iterative solve inside it stops lane by lane, not at the batch's slowest lane.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def lane_by_lane(fn):
    """``fn`` (positional array or pytree arguments) whose ``vmap`` maps it over the lanes one after another."""

    @jax.custom_batching.custom_vmap
    def one_lane(*args):
        return fn(*args)

    @one_lane.def_vmap
    def lanes(axis_size, in_batched, *args):
        args = jax.tree_util.tree_map(
            lambda a, batched: a if batched else jnp.broadcast_to(a, (axis_size, *jnp.shape(a))), args,
            tuple(in_batched))
        out = jax.lax.map(lambda lane: one_lane(*lane), args)  # one_lane again: a vmap outside this one maps too
        return out, jax.tree_util.tree_map(lambda _: True, out)

    return one_lane
