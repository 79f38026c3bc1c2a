"""Fusion boundaries for XLA's CPU compiler (docs/design.md, "A step is a few fused kernels").

XLA's CPU fusion copies an elementwise producer into every consumer fusion that
reads it, however expensive the producer: in the MEE step, cos L and sin L were
computed 107 times per step where 8 are needed, inside 137 fusions.  A
conditional is a boundary XLA keeps: what its branch computes is stored once and
read by every consumer.  ``materialized`` puts a function of per-sample values
behind one, on the CPU only (GPU compilers weigh duplication themselves, and a
conditional there costs a host round trip).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def materialized(fn, *args, anchor, enabled: bool = True):
    """``fn(*args)``, computed as its own kernel on the CPU (if ``enabled``, a static choice: a conditional
    costs a few microseconds per call, which a batch of a few lanes does not win back).

    ``anchor`` is a traced scalar shared by the whole batch (not vmapped), finite: the Earth angle of the
    step.  The conditional's other branch (taken only if ``anchor`` is not finite) gives zeros; under a vmap
    that batches ``anchor`` both branches run and the result is still ``fn(*args)`` where ``anchor`` is finite.
    """
    if not enabled or jax.default_backend() != "cpu":
        return fn(*args)
    shapes = jax.eval_shape(fn, *args)
    zeros = lambda *_: jax.tree_util.tree_map(lambda s: jnp.zeros(s.shape, s.dtype), shapes)  # noqa: E731
    return jax.lax.cond(jnp.isfinite(anchor), fn, zeros, *args)


def skipped_where_idle(fn, active, idle_value, *args, lanes_from: int = 8):
    """``fn(*args)`` per sample, with the work skipped for a whole batch when no sample needs it.

    ``active(*args) -> bool`` is a cheap per-sample test; where it is False, ``fn(*args)`` must equal
    ``idle_value(*args)`` exactly (e.g. the shadow function is exactly 1 outside the penumbra cone), so the
    result is the same number either way.  Unbatched, or under a vmap of fewer than ``lanes_from`` lanes, or
    off the CPU, this is ``fn(*args)``.  Under a vmap of more lanes on the CPU, the batch evaluates
    ``fn`` (vmapped) only if some lane is active (one ``lax.cond`` on ``any(active)``: a batch-level
    condition that ``vmap`` of a per-sample ``cond`` cannot express, since it turns the cond into a select
    that computes both sides).  Derivatives (forward and reverse) are those of ``fn``: the tangent is
    always computed in full.
    """

    @jax.custom_jvp
    @jax.custom_batching.custom_vmap
    def gated(*xs):
        return fn(*xs)

    @gated.def_vmap
    def batched(axis_size, in_batched, *xs):
        full = jax.vmap(fn, in_axes=tuple(0 if b else None for b in in_batched))
        if axis_size < lanes_from or jax.default_backend() != "cpu":
            return full(*xs), True
        needed = jnp.any(jax.vmap(active, in_axes=tuple(0 if b else None for b in in_batched))(*xs))
        idle = jax.vmap(idle_value, in_axes=tuple(0 if b else None for b in in_batched))
        out = jax.lax.cond(needed, full, idle, *xs)
        return out, True

    @gated.defjvp
    def tangent(primals, tangents):
        return gated(*primals), jax.jvp(fn, primals, tangents)[1]

    return gated(*args)
