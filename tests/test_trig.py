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


def _at_widths(fn, x, widths=(1, 2, 3, 70)):
    """``fn`` vmapped over ``x`` laid out [len / w, w] for every width w (the same values in the same order)."""
    return [np.asarray(jax.jit(jax.vmap(jax.vmap(fn)))(jnp.asarray(x).reshape(-1, w))).ravel() for w in widths]


def test_tan_and_atan_within_ulps_of_libm_and_the_same_at_every_width():
    from geojax.physics.trig import atan, tan

    x = np.random.default_rng(2).uniform(-1.5, 1.5, 210 * 40)  # tan up to 14, atan of it
    for ours, ref, max_ulp in ((tan, np.tan, 3), (atan, np.arctan, 1)):
        values = _at_widths(ours, x)
        assert np.max(np.abs(values[0] - ref(x)) / np.spacing(np.abs(ref(x)))) <= max_ulp
        for other in values[1:]:  # XLA's own tan and atan differ here between the vector loop and its remainder
            np.testing.assert_array_equal(other, values[0])
    assert float(atan(jnp.asarray(-0.0))) == 0.0 and np.signbit(float(atan(jnp.asarray(-0.0))))
    np.testing.assert_allclose(float(atan(jnp.asarray(np.inf))), np.pi / 2, rtol=0, atol=0)


def test_atan_derivative_is_one_over_one_plus_t_squared():
    from geojax.physics.trig import atan, tan

    t = jnp.linspace(-30.0, 30.0, 121)
    np.testing.assert_allclose(np.asarray(jax.vmap(jax.grad(atan))(t)), 1 / (1 + np.asarray(t) ** 2), rtol=1e-15)
    x = jnp.linspace(-1.4, 1.4, 57)  # tan's from sincos's: 1 / cos^2
    np.testing.assert_allclose(np.asarray(jax.vmap(jax.grad(tan))(x)), 1 / np.cos(np.asarray(x)) ** 2, rtol=1e-14)
