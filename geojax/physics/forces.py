"""Force models: Earth point mass, J2, C22/S22, Sun, Moon, solar radiation pressure with Earth shadow.

Each term is a small pure function of ECI position.  ``ForceModel`` is a pytree
whose switches (1.0 on, 0.0 off) and coefficients are all array leaves, so a
sweep can vary any of them without recompiling and a gradient can flow into
any coefficient.  ``Environment`` holds what is the same for every sample of a
batch at one instant (Sun and Moon positions, Earth rotation angle); it is
computed once per scenario (DESIGN.md, "Ephemerides are batch-invariant").
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.physics import constants as c
from geojax.physics.frames import ecef_to_eci, eci_to_ecef


class ForceModel(NamedTuple):
    """Switches and coefficients of the perturbing accelerations (SI units)."""

    mu_m3_s2: float = c.MU_EARTH_M3_S2
    r_earth_m: float = c.R_EARTH_M
    j2_on: float = 1.0
    j2: float = c.J2
    c22_on: float = 0.0
    c22: float = c.C22
    s22: float = c.S22
    sun_on: float = 1.0
    mu_sun_m3_s2: float = c.MU_SUN_M3_S2
    moon_on: float = 1.0
    mu_moon_m3_s2: float = c.MU_MOON_M3_S2
    srp_on: float = 1.0
    srp_pressure_1au_n_m2: float = 4.5605e-6
    reflectivity: float = 0.6
    srp_area_m2: float = 0.0
    shadow_on: float = 1.0


class Environment(NamedTuple):
    """Batch-invariant quantities at one instant (or a stack of instants)."""

    r_sun_eci_m: jnp.ndarray  # [..., 3]
    r_moon_eci_m: jnp.ndarray  # [..., 3]
    earth_angle_rad: jnp.ndarray  # [...], ECI x axis to Greenwich


def point_mass(r_eci, mu):
    """-mu r / |r|^3."""
    r = jnp.linalg.norm(r_eci, axis=-1, keepdims=True)
    return -mu * r_eci / r**3


def j2_acceleration(r_eci, mu, j2, r_earth_m):
    """Li 2022, eq. (4), J2 term; the ECI z axis is the Earth's mean pole of the epoch."""
    r2 = jnp.sum(r_eci**2, axis=-1, keepdims=True)
    z = r_eci[..., 2:3]
    z_hat = jnp.array([0.0, 0.0, 1.0])
    factor = 1.5 * mu * j2 * r_earth_m**2 / r2**2.5
    return factor * ((5 * z**2 / r2 - 1) * r_eci - 2 * z * z_hat)


def c22_s22_acceleration(r_eci, earth_angle_rad, mu, c22, s22, r_earth_m):
    """Sectoral degree-2 field, the gradient of U22 = 3 mu R^2 / r^5 (C22 (x^2 - y^2) + 2 S22 x y) in ECEF."""
    x_ecef = eci_to_ecef(r_eci, earth_angle_rad)
    x, y = x_ecef[..., 0], x_ecef[..., 1]
    r2 = jnp.sum(x_ecef**2, axis=-1)
    poly = c22 * (x**2 - y**2) + 2 * s22 * x * y
    grad_poly = jnp.stack([2 * (c22 * x + s22 * y), 2 * (s22 * x - c22 * y), jnp.zeros_like(x)], -1)
    factor = 3 * mu * r_earth_m**2 / r2**2.5
    a_ecef = factor[..., None] * (grad_poly - 5 * (poly / r2)[..., None] * x_ecef)
    return ecef_to_eci(a_ecef, earth_angle_rad)


def third_body(r_eci, r_body_eci, mu_body):
    """Li 2022, eq. (4): mu_q (R_q / |R_q|^3 - r_q / |r_q|^3), R_q = r_q - r.

    The direct difference loses about 3.5 digits at GEO for the Sun, leaving a
    relative error near 1e-12, far below what the ephemeris allows.
    """
    rel = r_body_eci - r_eci
    d = jnp.linalg.norm(rel, axis=-1, keepdims=True)
    rb = jnp.linalg.norm(r_body_eci, axis=-1, keepdims=True)
    return mu_body * (rel / d**3 - r_body_eci / rb**3)


def shadow_fraction(r_eci, r_sun_eci, r_earth_m):
    """Fraction of the solar disc visible from the satellite: conical umbra and penumbra.

    Montenbruck & Gill, *Satellite Orbits* (2000), Sec. 3.4.2: apparent radii of
    Sun and Earth and their separation give the occulted area of two discs.
    1 in sunlight, 0 in umbra, in between in the penumbra (smooth, so gradients
    through the edge exist).
    """
    to_sun = r_sun_eci - r_eci
    d_sun = jnp.linalg.norm(to_sun, axis=-1)
    d_earth = jnp.linalg.norm(r_eci, axis=-1)
    # arcsin(x) = x (1 + x^2/6 + 3 x^4/40) + O(x^7): exact in float64 for the
    # Sun's apparent radius (x < 0.005) and much cheaper than arcsin.
    x = c.R_SUN_M / d_sun
    a = x * (1 + x**2 / 6 + 0.075 * x**4)
    b = jnp.arcsin(jnp.clip(r_earth_m / d_earth, 0.0, 1.0))
    cos_sep = -jnp.sum(r_eci * to_sun, axis=-1) / (d_earth * d_sun)
    sep = _safe_arccos(cos_sep)
    # Occulted area of two overlapping discs of angular radii a (Sun) and b (Earth).
    safe_sep = jnp.maximum(sep, 1e-12)
    x = (safe_sep**2 + a**2 - b**2) / (2 * safe_sep)
    y = _safe_sqrt(a**2 - x**2)
    area = a**2 * _safe_arccos(x / a) + b**2 * _safe_arccos((safe_sep - x) / b) - safe_sep * y
    partial = 1 - area / (jnp.pi * a**2)
    full_umbra = sep <= b - a
    # Both branches are evaluated under vmap; where() picks per sample.
    return jnp.where(sep >= a + b, 1.0, jnp.where(full_umbra, 0.0, jnp.clip(partial, 0.0, 1.0)))


# Gradient-safe forms: outside the discs' overlap these are evaluated and then selected away (or
# multiplied by a switch that is off); the plain sqrt / arccos would put an infinite derivative there,
# and 0 * inf = NaN would poison every gradient through the force model.
def _safe_sqrt(x):
    """sqrt(max(x, 0)) with a zero gradient where x <= 0."""
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def _safe_arccos(x):
    """arccos(clip(x, -1, 1)) with a zero gradient where |x| >= 1."""
    inside = jnp.abs(x) < 1.0
    return jnp.where(inside, jnp.arccos(jnp.where(inside, x, 0.0)), jnp.where(x >= 1.0, 0.0, jnp.pi))


def solar_radiation_pressure(r_eci, r_sun_eci, mass_kg, fm: ForceModel):
    """Li 2022, eq. (4): -P (1 + eta) S/m R_hat_sun, times the Earth-shadow fraction.

    The pressure scales as (1 AU / distance to the Sun)^2 with
    P(1 AU) = ``fm.srp_pressure_1au_n_m2`` (Li's rho_sun).  Eq. (4) writes the
    scale as r_sun^2 / Delta_sun^2 with rho_sun at the Earth's distance; the
    1/r^2 law with P at 1 AU is the physical reading (3.3 % annual modulation).
    """
    to_sun = r_sun_eci - r_eci
    d = jnp.linalg.norm(to_sun, axis=-1, keepdims=True)
    light = 1.0 - fm.shadow_on * (1.0 - shadow_fraction(r_eci, r_sun_eci, fm.r_earth_m))[..., None]
    magnitude = fm.srp_pressure_1au_n_m2 * (1 + fm.reflectivity) * fm.srp_area_m2 / jnp.asarray(mass_kg)[..., None] * (c.AU_M / d) ** 2
    return -light * magnitude * to_sun / d


def perturbing_acceleration(r_eci, mass_kg, env: Environment, fm: ForceModel):
    """Sum of the switched-on perturbations (Li 2022, eq. (3)) in ECI, m/s^2."""
    a = fm.j2_on * j2_acceleration(r_eci, fm.mu_m3_s2, fm.j2, fm.r_earth_m)
    a = a + fm.c22_on * c22_s22_acceleration(r_eci, env.earth_angle_rad, fm.mu_m3_s2, fm.c22, fm.s22, fm.r_earth_m)
    a = a + fm.sun_on * third_body(r_eci, env.r_sun_eci_m, fm.mu_sun_m3_s2)
    a = a + fm.moon_on * third_body(r_eci, env.r_moon_eci_m, fm.mu_moon_m3_s2)
    return a + fm.srp_on * solar_radiation_pressure(r_eci, env.r_sun_eci_m, mass_kg, fm)
