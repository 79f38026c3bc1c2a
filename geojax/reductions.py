"""Reductions whose last bit does not depend on the lane width: over a run's cycles, and along a long axis.

Under ``vmap`` a reduction over cycles is one over an array [lanes, cycles], which XLA's CPU compiler vectorises
by the batch's shape, and a product fused into a sum may become one rounding (an FMA) in one loop and two in
another: the order of the additions and the roundings, and so the last bit, then depend on the width (measured:
the navigation filter's RMS and NEES metrics at 24 and 1024 lanes, 5-12 of 24 samples an ulp apart).  Here the
values are stored before they are added (``optimization_barrier``) and added in the cycles' order (a scan), the
same for every width, at a few microseconds per call.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def sum_over_cycles(values):
    """The sum over the leading (cycle) axis, term after term."""
    values = jax.lax.optimization_barrier(values)
    return jax.lax.scan(lambda total, v: (total + v, None), jnp.zeros_like(values[0]), values)[0]


def mean_over_cycles(values):
    """The mean over the leading (cycle) axis (``sum_over_cycles`` over the count)."""
    return sum_over_cycles(values) / values.shape[0]


def sum_in_order(parts):
    """[n, k] -> [n]: the k columns, stored, added first to last."""
    parts = jax.lax.optimization_barrier(parts)
    total = parts[:, 0]
    for column in range(1, parts.shape[1]):
        total = total + parts[:, column]
    return total


def sum_pairwise(values):
    """The sum over the last axis, added in halves (the first half's terms to the second's, then again) until one
    is left: elementwise additions in one fixed order, whatever the batch.  XLA's own reduction of a long axis
    keeps partial sums whose number follows its vectorisation of the whole batch (measured: the interior point's
    complementarity mean over 2160 terms, ``control.lp``, an ulp apart at 2 and 70 lanes)."""
    while values.shape[-1] > 1:
        if values.shape[-1] % 2:
            values = jnp.concatenate([values, jnp.zeros_like(values[..., :1])], -1)
        half = values.shape[-1] // 2
        values = values[..., :half] + values[..., half:]
    return values[..., 0]


def percentile_over_cycles(values, q: float):
    """The ``q``-th percentile over the leading axis, linear between the order statistics (numpy's default)."""
    ordered = jnp.sort(values, axis=0)
    position = q / 100.0 * (values.shape[0] - 1)
    low = int(position)
    high = min(low + 1, values.shape[0] - 1)
    step = jax.lax.optimization_barrier((position - low) * (ordered[high] - ordered[low]))
    return ordered[low] + step
