"""physics.trig.sincos and atan2 against numpy's libm (an independent implementation) and their own derivatives."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics.trig import atan2, sincos


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


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3, 1e8])
def test_atan2_within_an_ulp_of_libm(scale):
    rng = np.random.default_rng(1)
    y, x = rng.normal(size=100_000) * scale, rng.normal(size=100_000)
    ours, ref = np.asarray(jax.jit(atan2)(jnp.asarray(y), jnp.asarray(x))), np.arctan2(y, x)
    assert np.max(np.abs(ours - ref) / np.spacing(np.abs(ref))) <= 1


def test_atan2_signs_zeros_and_infinities_as_numpy():
    values = np.array([0.0, -0.0, np.inf, -np.inf, 1.0, -1.0, 1e-300, -1e-300, 1e300, np.nan])
    y, x = (a.ravel() for a in np.meshgrid(values, values))
    ours, ref = np.asarray(atan2(jnp.asarray(y), jnp.asarray(x))), np.arctan2(y, x)
    same = (ours == ref) & (np.signbit(ours) == np.signbit(ref))
    assert np.all(same | (np.isnan(ours) & np.isnan(ref)))


def test_atan2_derivative_is_the_closed_form():
    y, x = jnp.linspace(-3.0, 3.0, 13), jnp.linspace(2.0, -2.0, 13) + 0.1
    d_y, d_x = jax.vmap(jax.grad(atan2, argnums=(0, 1)))(y, x)
    r2 = np.asarray(x * x + y * y)
    np.testing.assert_allclose(np.asarray(d_y), np.asarray(x) / r2, rtol=1e-15)
    np.testing.assert_allclose(np.asarray(d_x), -np.asarray(y) / r2, rtol=1e-15)
