"""Force terms against their potentials (finite differences), closed forms and limits."""

import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics import constants as c
from geojax.physics.forces import (
    Environment,
    ForceModel,
    c22_s22_acceleration,
    j2_acceleration,
    shadow_fraction,
    solar_radiation_pressure,
    sunlit_fraction_xyz,
    third_body,
)

R_TEST = np.array([3.1e7, -2.2e7, 1.5e7])


def numerical_gradient(potential, r, h=1.0):
    return np.array([(potential(r + h * e) - potential(r - h * e)) / (2 * h) for e in np.eye(3)])


def test_j2_is_gradient_of_zonal_potential():
    # U_J2 = -mu J2 R^2 / (2 r^3) (3 z^2 / r^2 - 1), an independent closed form.
    def potential(r):
        rr = np.linalg.norm(r)
        return -c.MU_EARTH_M3_S2 * c.J2 * c.R_EARTH_M**2 / (2 * rr**3) * (3 * r[2] ** 2 / rr**2 - 1)

    got = np.asarray(j2_acceleration(jnp.asarray(R_TEST), c.MU_EARTH_M3_S2, c.J2, c.R_EARTH_M))
    np.testing.assert_allclose(got, numerical_gradient(potential, R_TEST), rtol=1e-7)


def test_c22_s22_is_gradient_of_sectoral_potential():
    # U_22 = mu/r (R/r)^2 3 cos^2(phi) (C22 cos 2 lambda + S22 sin 2 lambda), spherical form, in ECEF.
    angle = 1.1

    def potential(r_eci):
        ca, sa = np.cos(angle), np.sin(angle)
        x, y, z = ca * r_eci[0] + sa * r_eci[1], -sa * r_eci[0] + ca * r_eci[1], r_eci[2]
        rr = np.linalg.norm(r_eci)
        lon, lat = np.arctan2(y, x), np.arcsin(z / rr)
        return (c.MU_EARTH_M3_S2 / rr * (c.R_EARTH_M / rr) ** 2 * 3 * np.cos(lat) ** 2
                * (c.C22 * np.cos(2 * lon) + c.S22 * np.sin(2 * lon)))

    got = np.asarray(c22_s22_acceleration(jnp.asarray(R_TEST), angle, c.MU_EARTH_M3_S2, c.C22, c.S22, c.R_EARTH_M))
    np.testing.assert_allclose(got, numerical_gradient(potential, R_TEST), rtol=1e-6)


def test_c22_equilibria_at_geo():
    # The along-track C22/S22 force at GEO vanishes at the four equilibrium longitudes
    # atan2(S22, C22)/2 + k pi/2 (about -14.9, 75.1, 165.1, -104.9 deg), a closed form.
    lon0 = 0.5 * np.arctan2(c.S22, c.C22)
    for k in range(4):
        lon = lon0 + k * np.pi / 2
        r = 42164e3 * np.array([np.cos(lon), np.sin(lon), 0.0])
        a = np.asarray(c22_s22_acceleration(jnp.asarray(r), 0.0, c.MU_EARTH_M3_S2, c.C22, c.S22, c.R_EARTH_M))
        along = np.dot(a, [-np.sin(lon), np.cos(lon), 0.0])
        assert abs(along) < 1e-15


def test_third_body_tidal_limit():
    # For |r| << |r_q| the third-body term tends to the tidal field mu/d^3 (3 (d_hat . r) d_hat - r).
    r = np.array([42164e3, 0.0, 0.0])
    d = np.array([1.496e11, 2e10, 5e9])
    d_hat = d / np.linalg.norm(d)
    tidal = c.MU_SUN_M3_S2 / np.linalg.norm(d) ** 3 * (3 * np.dot(d_hat, r) * d_hat - r)
    got = np.asarray(third_body(jnp.asarray(r), jnp.asarray(d), c.MU_SUN_M3_S2))
    np.testing.assert_allclose(got, tidal, rtol=1e-3, atol=1e-12)


def test_shadow_fraction_limits_and_penumbra():
    sun = np.array([c.AU_M, 0.0, 0.0])
    sunlit = np.array([0.0, 42164e3, 0.0])
    behind = np.array([-42164e3, 0.0, 0.0])
    assert float(shadow_fraction(jnp.asarray(sunlit), sun, c.R_EARTH_M)) == 1.0
    assert float(shadow_fraction(jnp.asarray(behind), sun, c.R_EARTH_M)) == 0.0
    # Across the shadow edge the visible fraction rises monotonically from 0 to 1
    # over the penumbra width: about 2 R_sun / AU times the GEO radius, ~390 km.
    ys = np.linspace(c.R_EARTH_M - 400e3, c.R_EARTH_M + 400e3, 81)
    frac = np.array([float(shadow_fraction(jnp.array([-42164e3, y, 0.0]), sun, c.R_EARTH_M)) for y in ys])
    assert frac[0] == 0.0 and frac[-1] == 1.0
    assert np.all(np.diff(frac) >= -1e-12)
    width = ys[frac >= 1.0][0] - ys[frac > 0.0][0]
    assert width == pytest.approx(2 * c.R_SUN_M / c.AU_M * 42164e3, rel=0.1)


def test_srp_closed_form_at_one_au():
    # Li 2022, eq. (4): |a| = P (1 + eta) S / m at 1 AU in sunlight, pointing away from the Sun.
    fm = ForceModel(srp_area_m2=200.0, reflectivity=0.6)
    sun = np.array([c.AU_M, 0.0, 0.0])
    r = np.array([0.0, 42164e3, 0.0])
    a = np.asarray(solar_radiation_pressure(jnp.asarray(r), jnp.asarray(sun + r), 5000.0, fm))
    np.testing.assert_allclose(a, [-4.5605e-6 * 1.6 * 200 / 5000, 0, 0], rtol=1e-12, atol=1e-20)


@pytest.mark.slow
def test_shadow_skipped_for_a_sunlit_batch_gives_the_same_numbers_and_derivatives():
    """The batch-level skip of the shadow function (``fusion.skipped_where_idle``): against the plain function
    on GEO positions across the umbra, penumbra and sunlight (bit for bit), on a batch wholly in sunlight
    (exactly 1, through the skipped branch), and its forward and reverse derivatives against the plain
    function's."""
    import jax

    from geojax.physics.forces import near_shadow_cone, shadow_fraction_xyz
    from geojax.physics.fusion import skipped_where_idle

    rng = np.random.default_rng(3)
    sun = jnp.array([c.AU_M, 0.0, 0.0])
    lon, lat = rng.uniform(np.pi - 0.2, np.pi + 0.2, 512), rng.uniform(-0.2, 0.2, 512)
    r = 4.2164e7
    x, y, z = (jnp.asarray(v) for v in (r * np.cos(lat) * np.cos(lon), r * np.cos(lat) * np.sin(lon), r * np.sin(lat)))

    def gated(a, b, d):
        return skipped_where_idle(shadow_fraction_xyz, near_shadow_cone, lambda *xs: jnp.ones_like(xs[0]), a, b, d,
                                  sun, c.R_EARTH_M)

    def plain(a, b, d):
        return shadow_fraction_xyz(a, b, d, sun, c.R_EARTH_M)

    fast, slow = jax.jit(jax.vmap(gated))(x, y, z), jax.vmap(plain)(x, y, z)
    assert 0 < int(jnp.sum(slow == 0)) and 0 < int(jnp.sum((slow > 0) & (slow < 1))) and 0 < int(jnp.sum(slow == 1))
    # Equal where the fraction is 0 or 1; the penumbra's formula is ill-conditioned (a difference of
    # circular segments), so compiled differently it agrees to ~1e-11 there.
    np.testing.assert_array_equal(fast[(slow == 0) | (slow == 1)], slow[(slow == 0) | (slow == 1)])
    np.testing.assert_allclose(fast, slow, rtol=1e-9, atol=1e-12)
    hlo = jax.jit(jax.vmap(gated)).lower(x, y, z).compile().as_text()
    # The batch-level skip is a conditional on the CPU only (``fusion.skipped_where_idle``: on a GPU a
    # conditional costs a host round trip, so the shadow is computed for every lane there).
    assert ("conditional" in hlo) == (jax.default_backend() == "cpu")
    np.testing.assert_array_equal(jax.jit(jax.vmap(gated))(x, y, jnp.abs(z) + 1e7), 1.0)  # all sunlit: skipped
    # Derivatives: penumbra lanes have nonzero ones.
    dz = jax.vmap(jax.grad(gated, argnums=2))(x, y, z)
    np.testing.assert_allclose(dz, jax.vmap(jax.grad(plain, argnums=2))(x, y, z), rtol=1e-7, atol=1e-18)
    assert float(jnp.max(jnp.abs(dz))) > 0
    fwd = jax.jacfwd(lambda d: jax.vmap(gated)(x, y, d).sum())(z)
    np.testing.assert_allclose(fwd, dz, rtol=1e-7, atol=1e-18)


def _on_axis_behind_moon(distance_m, offset_m=0.0):
    """Sun, Moon and a satellite on one line (the satellite ``distance_m`` behind the Moon, displaced
    ``offset_m`` sideways), as an Environment and ECI components."""
    sun, moon = np.array([c.AU_M, 0.0, 0.0]), np.array([3.8e8, 0.0, 0.0])
    r = moon - np.array([distance_m, -offset_m, 0.0])
    env = Environment(jnp.asarray(sun), jnp.asarray(moon), jnp.asarray(0.0), jnp.asarray(1.0), jnp.asarray(0.0))
    return env, tuple(jnp.asarray(v) for v in r)


def test_moon_shadow_umbra_annulus_and_daylight():
    # Closed forms of two concentric discs: behind the Moon where its apparent radius exceeds the Sun's, no
    # light; where it is smaller (annular eclipse), 1 - (a_moon / a_sun)^2 of the disc; far off the axis, 1.
    fm = ForceModel(shadow_on=0.0, moon_radius_m=c.R_MOON_M)
    env, r = _on_axis_behind_moon(3.42e8)  # a GEO satellite: 342,000 km behind the Moon
    assert float(sunlit_fraction_xyz(*r, env, fm)) == 0.0
    env, r = _on_axis_behind_moon(3.8e8 - 4.0e7)  # nearer the Moon's umbra tip: still umbra
    assert float(sunlit_fraction_xyz(*r, env, fm)) == 0.0
    distance = 4.2e8  # beyond the umbra's tip (about 3.74e8 m): annular
    env, r = _on_axis_behind_moon(distance)
    a_sun = np.arcsin(c.R_SUN_M / (c.AU_M - 3.8e8 + distance))
    a_moon = np.arcsin(c.R_MOON_M / distance)
    assert float(sunlit_fraction_xyz(*r, env, fm)) == pytest.approx(1 - (a_moon / a_sun) ** 2, rel=1e-9)
    env, r = _on_axis_behind_moon(3.42e8, offset_m=1e7)
    assert float(sunlit_fraction_xyz(*r, env, fm)) == 1.0
    # Without moon_radius_m the Moon casts no shadow.
    env, r = _on_axis_behind_moon(3.42e8)
    assert float(sunlit_fraction_xyz(*r, env, ForceModel(shadow_on=0.0))) == 1.0
