"""physics.trig.sincos against numpy's libm (an independent implementation) and its own derivative."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics.trig import sincos


@pytest.mark.parametrize("limit, max_ulp", [(1.0, 1), (10.0, 1), (3000.0, 2), (1e5, 2)])
def test_sincos_within_ulps_of_libm(limit, max_ulp):
    x = np.random.default_rng(0).uniform(-limit, limit, 100_000)
    cos, sin = jax.jit(sincos)(jnp.asarray(x))
    for ours, ref in ((np.asarray(cos), np.cos(x)), (np.asarray(sin), np.sin(x))):
        assert np.max(np.abs(ours - ref) / np.spacing(np.abs(ref))) <= max_ulp


def test_sincos_quadrant_boundaries_and_special_values():
    x = np.concatenate([np.arange(-16, 17) * np.pi / 4, [0.0, -0.0, 1e-300, 2 ** -30]])
    cos, sin = sincos(jnp.asarray(x))
    np.testing.assert_allclose(np.asarray(cos), np.cos(x), rtol=0, atol=2e-16)
    np.testing.assert_allclose(np.asarray(sin), np.sin(x), rtol=0, atol=2e-16)
    assert np.all(np.isnan(np.asarray(sincos(jnp.asarray([np.nan, np.inf, -np.inf])))))


def test_sincos_derivative_is_minus_sin_cos():
    x = jnp.linspace(-20.0, 20.0, 101)
    d_cos = jax.vmap(jax.grad(lambda a: sincos(a)[0]))(x)
    d_sin = jax.vmap(jax.grad(lambda a: sincos(a)[1]))(x)
    np.testing.assert_allclose(np.asarray(d_cos), -np.sin(np.asarray(x)), atol=1e-15)
    np.testing.assert_allclose(np.asarray(d_sin), np.cos(np.asarray(x)), atol=1e-15)
