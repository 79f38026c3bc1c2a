"""Reductions over a run's cycles whose last bit does not depend on the lane width.

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


def percentile_over_cycles(values, q: float):
    """The ``q``-th percentile over the leading axis, linear between the order statistics (numpy's default)."""
    ordered = jnp.sort(values, axis=0)
    position = q / 100.0 * (values.shape[0] - 1)
    low = int(position)
    high = min(low + 1, values.shape[0] - 1)
    step = jax.lax.optimization_barrier((position - low) * (ordered[high] - ordered[low]))
    return ordered[low] + step
