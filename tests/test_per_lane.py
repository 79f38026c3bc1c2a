"""Arithmetic whose last bit does not depend on the batch's width: ``reductions.sum_pairwise`` and
``per_lane.lane_by_lane``.  Independent checks: ``math.fsum`` (a correctly rounded sum) and the same function
called on one sample unbatched."""

import math

import jax
import jax.numpy as jnp
import numpy as np

from geojax.per_lane import lane_by_lane
from geojax.reductions import sum_pairwise


def test_sum_pairwise_is_near_the_exact_sum_and_the_same_at_every_width():
    rows = np.random.default_rng(0).standard_normal((70, 2160)) * 10.0 ** np.random.default_rng(1).uniform(-3, 3, 2160)
    ours = np.asarray(jax.jit(sum_pairwise)(jnp.asarray(rows)))
    exact = np.array([math.fsum(row) for row in rows])
    scale = np.sum(np.abs(rows), 1)
    assert np.all(np.abs(ours - exact) <= 12 * np.finfo(float).eps * scale)  # pairwise: log2(2160) < 12 levels
    for width in (1, 2, 5, 70):
        again = np.concatenate([np.asarray(jax.jit(jax.vmap(sum_pairwise))(jnp.asarray(rows[i:i + width])))
                                for i in range(0, 70, width)])
        np.testing.assert_array_equal(again, ours)
    assert float(sum_pairwise(jnp.asarray([3.0]))) == 3.0 and sum_pairwise(jnp.ones((4, 7, 5))).shape == (4, 7)


def _solve(a, b, steps):
    """Gauss-Seidel-like iterations with a data-dependent stop: a small iterative solve of one lane."""
    def body(carry):
        x, k = carry
        return x + 0.5 * (b - a @ x) / jnp.diag(a), k + 1

    def unfinished(carry):
        x, k = carry
        return (k < steps) & (jnp.max(jnp.abs(a @ x - b)) > 1e-12)

    return jax.lax.while_loop(unfinished, body, (jnp.zeros_like(b), 0))


def test_lane_by_lane_gives_each_lane_its_unbatched_value_at_every_width():
    rng = np.random.default_rng(3)
    n = 12
    a = jnp.asarray(rng.standard_normal((70, n, n)) + 3 * n * np.eye(n))
    b = jnp.asarray(rng.standard_normal((70, n)))
    one = [jax.tree_util.tree_map(np.asarray, jax.jit(_solve)(a[i], b[i], 200)) for i in range(70)]
    mapped = lane_by_lane(_solve)
    for width in (2, 7, 70):
        x, k = jax.jit(jax.vmap(mapped, in_axes=(0, 0, None)))(a[:width], b[:width], 200)
        for i in range(width):
            np.testing.assert_array_equal(np.asarray(x[i]), one[i][0])
            assert int(k[i]) == int(one[i][1])  # each lane stops at its own iteration, not the slowest's
    assert len({int(o[1]) for o in one}) > 1  # the lanes do stop at different iterations
    nested = jax.jit(jax.vmap(jax.vmap(mapped, in_axes=(0, 0, None)), in_axes=(0, 0, None)))(
        a.reshape(7, 10, n, n), b.reshape(7, 10, n), 200)[0]
    np.testing.assert_array_equal(np.asarray(nested).reshape(70, n), np.stack([o[0] for o in one]))
