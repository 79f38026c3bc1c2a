"""Fusion boundaries for XLA's CPU compiler (DESIGN.md, "A step is a few fused kernels").

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
