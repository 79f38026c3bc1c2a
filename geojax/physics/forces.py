"""Force models: Earth point mass, J2, C22/S22 or the field to degree N, Sun, Moon, solar radiation pressure
with the Earth's (and optionally the Moon's) shadow.

Each term is a small pure function of the ECI position's components ``(x, y, z)``
(``*_xyz``), written so that a step compiles to a few elementwise loops: no
reductions over a length-3 axis, no per-sample rotation of batch-invariant
vectors (what the Sun, Moon and Earth angle alone give is computed once per
stage, outside the vmapped lanes).  The array forms (``point_mass(r_eci, ...)``
with ``r_eci`` [..., 3]) wrap them for tests and callers with vectors.  ``ForceModel`` is a pytree
whose switches (1.0 on, 0.0 off) and coefficients are all array leaves, so a
sweep can vary any of them without recompiling and a gradient can flow into
any coefficient.  ``Environment`` holds what is the same for every sample of a
batch at one instant (Sun and Moon positions, Earth rotation angle); it is
computed once per scenario (docs/design.md, "Ephemerides are batch-invariant").
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax.numpy as jnp

from geojax.physics import constants as c
from geojax.physics.fusion import materialized, skipped_where_idle
from geojax.physics.geopotential import Geopotential, geopotential_xyz


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
    # The Earth's field to degree and order N (``physics.geopotential``), replacing the J2 and C22/S22 terms
    # (their switches are then not read); None: the papers' J2 (and C22/S22) model.  Static structure.
    gravity: Geopotential | None = None
    # The Moon as a second occulting body of the Sun (conical, penumbra included; ``sunlit_fraction_xyz``):
    # its radius in m; None: the Earth's shadow only.  Static structure.
    moon_radius_m: float | None = None


class Environment(NamedTuple):
    """Batch-invariant quantities at one instant (or a stack of instants)."""

    r_sun_eci_m: jnp.ndarray  # [..., 3]
    r_moon_eci_m: jnp.ndarray  # [..., 3]
    earth_angle_rad: jnp.ndarray  # [...], ECI x axis to Greenwich
    cos_earth_angle: jnp.ndarray  # [...], its cosine and sine: once per instant for the batch (inside the vmapped
    sin_earth_angle: jnp.ndarray  # step XLA evaluates a batch-invariant cos per lane, in every kernel reading it)


def _xyz(vector):
    return vector[..., 0], vector[..., 1], vector[..., 2]


def _stacked(components):
    return jnp.stack(jnp.broadcast_arrays(*components), -1)



def point_mass_xyz(x, y, z, mu):
    """-mu r / |r|^3."""
    r2 = x * x + y * y + z * z
    k = -mu / (r2 * jnp.sqrt(r2))
    return k * x, k * y, k * z


def j2_xyz(x, y, z, mu, j2, r_earth_m):
    """Li 2022, eq. (4), J2 term; the ECI z axis is the Earth's mean pole of the epoch."""
    r2 = x * x + y * y + z * z
    factor = 1.5 * mu * j2 * r_earth_m**2 / (r2 * r2 * jnp.sqrt(r2))
    q = 5 * z * z / r2 - 1
    return factor * q * x, factor * q * y, factor * (q - 2) * z


def c22_s22_xyz(x, y, z, cos_angle, sin_angle, mu, c22, s22, r_earth_m):
    """Sectoral degree-2 field, the gradient of U22 = 3 mu R^2 / r^5 (C22 (x^2 - y^2) + 2 S22 x y) in ECEF;
    ``cos_angle``, ``sin_angle`` of the Earth rotation angle (ECI x axis to Greenwich)."""
    xe, ye = cos_angle * x + sin_angle * y, -sin_angle * x + cos_angle * y
    r2 = x * x + y * y + z * z
    poly_r2 = (c22 * (xe * xe - ye * ye) + 2 * s22 * xe * ye) / r2
    factor = 3 * mu * r_earth_m**2 / (r2 * r2 * jnp.sqrt(r2))
    ae = factor * (2 * (c22 * xe + s22 * ye) - 5 * poly_r2 * xe)
    an = factor * (2 * (s22 * xe - c22 * ye) - 5 * poly_r2 * ye)
    return cos_angle * ae - sin_angle * an, sin_angle * ae + cos_angle * an, -factor * 5 * poly_r2 * z


def third_body_xyz(x, y, z, body, mu_body):
    """Li 2022, eq. (4): mu_q (R_q / |R_q|^3 - r_q / |r_q|^3), R_q = r_q - r, for the body at ``body`` [3].

    The direct difference loses about 3.5 digits at GEO for the Sun, leaving a
    relative error near 1e-12, far below what the ephemeris allows.
    """
    bx, by, bz = _xyz(body)
    rx, ry, rz = bx - x, by - y, bz - z
    d2 = rx * rx + ry * ry + rz * rz
    b2 = bx * bx + by * by + bz * bz
    k, kb = mu_body / (d2 * jnp.sqrt(d2)), mu_body / (b2 * jnp.sqrt(b2))  # kb: once per stage, not per sample
    return k * rx - kb * bx, k * ry - kb * by, k * rz - kb * bz


def shadow_fraction_xyz(x, y, z, r_sun_eci, r_earth_m):
    """Fraction of the solar disc visible from the satellite: conical umbra and penumbra.

    Montenbruck & Gill, *Satellite Orbits* (2000), Sec. 3.4.2: apparent radii of
    Sun and Earth and their separation give the occulted area of two discs.
    1 in sunlight, 0 in umbra, in between in the penumbra (smooth, so gradients
    through the edge exist).
    """
    sx, sy, sz = _xyz(r_sun_eci)
    tx, ty, tz = sx - x, sy - y, sz - z
    d_sun = jnp.sqrt(tx * tx + ty * ty + tz * tz)
    d_earth = jnp.sqrt(x * x + y * y + z * z)
    # arcsin(x) = x (1 + x^2/6 + 3 x^4/40) + O(x^7): exact in float64 for the
    # Sun's apparent radius (x < 0.005) and much cheaper than arcsin.
    u = c.R_SUN_M / d_sun
    a = u * (1 + u**2 / 6 + 0.075 * u**4)
    b = jnp.arcsin(jnp.clip(r_earth_m / d_earth, 0.0, 1.0))
    cos_sep = -(x * tx + y * ty + z * tz) / (d_earth * d_sun)
    sep = _safe_arccos(cos_sep)
    # Occulted area of two overlapping discs of angular radii a (Sun) and b (Earth).
    safe_sep = jnp.maximum(sep, 1e-12)
    u = (safe_sep**2 + a**2 - b**2) / (2 * safe_sep)
    v = _safe_sqrt(a**2 - u**2)
    area = a**2 * _safe_arccos(u / a) + b**2 * _safe_arccos((safe_sep - u) / b) - safe_sep * v
    partial = 1 - area / (jnp.pi * a**2)
    full_umbra = sep <= b - a
    # Both branches are evaluated under vmap; where() picks per sample.
    return jnp.where(sep >= a + b, 1.0, jnp.where(full_umbra, 0.0, jnp.clip(partial, 0.0, 1.0)))


def near_shadow_cone(x, y, z, r_sun_eci, r_earth_m):
    """True where ``shadow_fraction_xyz`` may be below 1: the separation of the Sun's and the Earth's discs
    is below the sum of their radii, with a margin of 1e-9 in its cosine (a few nanoradians, a million
    times the rounding of the full formula), tested with square roots only.  Where False, the shadow
    fraction is exactly 1; NaN positions test True, so they reach the full formula as before."""
    sx, sy, sz = _xyz(r_sun_eci)
    tx, ty, tz = sx - x, sy - y, sz - z
    d_sun = jnp.sqrt(tx * tx + ty * ty + tz * tz)
    d_earth = jnp.sqrt(x * x + y * y + z * z)
    sin_a = c.R_SUN_M / d_sun
    sin_b = jnp.clip(r_earth_m / d_earth, 0.0, 1.0)
    cos_sum = jnp.sqrt(1 - sin_a * sin_a) * jnp.sqrt(1 - sin_b * sin_b) - sin_a * sin_b  # cos(a + b)
    cos_sep = -(x * tx + y * ty + z * tz) / (d_earth * d_sun)
    return ~(cos_sep <= cos_sum - 1e-9)


def _sunlit(x, y, z, r_sun_eci, r_earth_m):
    return jnp.ones_like(x * r_earth_m)


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


def srp_xyz(x, y, z, r_sun_eci, mass_kg, fm: ForceModel, light=None):
    """Li 2022, eq. (4): -P (1 + eta) S/m R_hat_sun, times the Earth-shadow fraction ``light`` (computed here
    if not given).

    The pressure scales as (1 AU / distance to the Sun)^2 with
    P(1 AU) = ``fm.srp_pressure_1au_n_m2`` (Li's rho_sun).  Eq. (4) writes the
    scale as r_sun^2 / Delta_sun^2 with rho_sun at the Earth's distance; the
    1/r^2 law with P at 1 AU is the physical reading (3.3 % annual modulation).
    """
    if light is None:
        light = 1.0 - fm.shadow_on * (1.0 - shadow_fraction_xyz(x, y, z, r_sun_eci, fm.r_earth_m))
    sx, sy, sz = _xyz(r_sun_eci)
    tx, ty, tz = sx - x, sy - y, sz - z
    d2 = tx * tx + ty * ty + tz * tz
    k = -light * fm.srp_pressure_1au_n_m2 * (1 + fm.reflectivity) * fm.srp_area_m2 / mass_kg * c.AU_M**2 / (
        d2 * jnp.sqrt(d2))
    return k * tx, k * ty, k * tz


def perturbing_xyz(x, y, z, mass_kg, env: Environment, fm: ForceModel, boundaries: bool = False):
    """Sum of the switched-on perturbations (Li 2022, eq. (3)) in ECI, m/s^2, as components.

    With ``boundaries`` (static: see ``physics.propagate.for_lanes``), the shadow function (an arcsine and
    three arccosines) is evaluated for a batch only when some sample is near the shadow cone
    (``fusion.skipped_where_idle``: a GEO batch at one station needs it on 1.0 % of a year's steps, 350 of
    35,136 at 96 per sidereal day; 1.7 % for a batch spread over 10 deg of longitude), behind a conditional that also keeps XLA's CPU fusion from evaluating
    it again in every kernel that reads it.
    """
    cos_angle, sin_angle = env.cos_earth_angle, env.sin_earth_angle
    if fm.gravity is None:  # the papers' model, summed in its original order
        ax, ay, az = (fm.j2_on * a for a in j2_xyz(x, y, z, fm.mu_m3_s2, fm.j2, fm.r_earth_m))
        terms = [(fm.c22_on, c22_s22_xyz(x, y, z, cos_angle, sin_angle, fm.mu_m3_s2, fm.c22, fm.s22,
                                         fm.r_earth_m))]
    else:
        ax, ay, az = geopotential_xyz(x, y, z, cos_angle, sin_angle, fm.mu_m3_s2, fm.r_earth_m, fm.gravity)
        terms = []
    for switch, term in terms + [
        (fm.sun_on, third_body_xyz(x, y, z, env.r_sun_eci_m, fm.mu_sun_m3_s2)),
        (fm.moon_on, third_body_xyz(x, y, z, env.r_moon_eci_m, fm.mu_moon_m3_s2)),
    ]:
        ax, ay, az = ax + switch * term[0], ay + switch * term[1], az + switch * term[2]
    light = sunlit_fraction_xyz(x, y, z, env, fm, boundaries)
    sx, sy, sz = srp_xyz(x, y, z, env.r_sun_eci_m, mass_kg, fm, light)
    return ax + fm.srp_on * sx, ay + fm.srp_on * sy, az + fm.srp_on * sz


def sunlit_fraction_xyz(x, y, z, env: Environment, fm: ForceModel, boundaries: bool = False):
    """Visible fraction of the solar disc at ECI (x, y, z): the Earth's shadow (where ``fm.shadow_on``) and,
    where ``fm.moon_radius_m`` is set, the Moon's (the same conical model with the Moon as the occulting body,
    Montenbruck & Gill Sec. 3.4.2).  The occulted fractions add, clipped at no light: the overlap of the two
    discs over the Sun's, a double eclipse, is not modelled.  With ``boundaries`` each shadow function is
    evaluated for a batch only when some sample is near its cone (``perturbing_xyz``)."""
    def fraction(x, y, z, sun, radius_m):
        if boundaries:
            return skipped_where_idle(shadow_fraction_xyz, near_shadow_cone, _sunlit, x, y, z, sun, radius_m)
        return shadow_fraction_xyz(x, y, z, sun, radius_m)

    light = 1.0 - fm.shadow_on * (1.0 - fraction(x, y, z, env.r_sun_eci_m, fm.r_earth_m))
    if fm.moon_radius_m is None:
        return light
    mx, my, mz = _xyz(env.r_moon_eci_m)
    moon = fraction(x - mx, y - my, z - mz, env.r_sun_eci_m - env.r_moon_eci_m, fm.moon_radius_m)
    return jnp.clip(light - (1.0 - moon), 0.0, 1.0)


def perturbing_behind_boundary(x, y, z, mass_kg, env: Environment, fm: ForceModel, boundaries: bool = False):
    """``perturbing_xyz`` behind a fusion boundary (``fusion.materialized``, where ``boundaries``) for the
    equations of motion.  With the field to degree N the three components cross the boundary as one array
    [..., 3] (``_one_array``): XLA's CPU compiler makes one kernel per output of the boundary and copies the
    whole field into each, and one output evaluates it once.  Measured in the degree-8 MEE step at batch 1024,
    one core, the forms compiled in one process and timed alternately (ns per right-hand side per sample,
    relative to the J2 + C22/S22 step): three outputs 2.13x, (a_x, a_y) as one complex number and a_z 1.82x
    (this module's previous form), one array 1.34x (with ``geopotential``'s per-order sums; 1.80x with its
    previous recursion).  The papers' model keeps its three real outputs (and its numbers, bit for bit)."""
    if fm.gravity is None:
        return materialized(partial(perturbing_xyz, boundaries=boundaries), x, y, z, mass_kg, env, fm,
                            anchor=env.earth_angle_rad, enabled=boundaries)

    def packed(*args):
        return _one_array(*perturbing_xyz(*args, boundaries=boundaries))

    a = materialized(packed, x, y, z, mass_kg, env, fm, anchor=env.earth_angle_rad, enabled=boundaries)
    return a[..., 0], a[..., 1], a[..., 2]


def _one_array(ax, ay, az):
    """(a_x, a_y, a_z) -> [..., 3] by selects on the last axis.  Not ``jnp.stack``: a concatenation's kernel
    evaluates each operand's whole expression in its own branch (measured on a chain of 200 multiply-adds with
    three outputs, one core: 231 ns per sample stacked, 71 as three outputs, 23 as one array by one-hot
    products, 19 for one output alone; selects and one-hot products within 10 % of each other in a second run);
    in one array the three components of an element are one expression, which LLVM evaluates once."""
    axis = jnp.arange(3)
    return jnp.where(axis == 0, ax[..., None], jnp.where(axis == 1, ay[..., None], az[..., None]))


# Array forms: position [..., 3] in, acceleration [..., 3] out.
def point_mass(r_eci, mu):
    return _stacked(point_mass_xyz(*_xyz(r_eci), mu))


def j2_acceleration(r_eci, mu, j2, r_earth_m):
    return _stacked(j2_xyz(*_xyz(r_eci), mu, j2, r_earth_m))


def c22_s22_acceleration(r_eci, earth_angle_rad, mu, c22, s22, r_earth_m):
    return _stacked(c22_s22_xyz(*_xyz(r_eci), jnp.cos(earth_angle_rad), jnp.sin(earth_angle_rad), mu, c22, s22,
                                r_earth_m))


def third_body(r_eci, r_body_eci, mu_body):
    return _stacked(third_body_xyz(*_xyz(r_eci), r_body_eci, mu_body))


def shadow_fraction(r_eci, r_sun_eci, r_earth_m):
    return shadow_fraction_xyz(*_xyz(r_eci), r_sun_eci, r_earth_m)


def solar_radiation_pressure(r_eci, r_sun_eci, mass_kg, fm: ForceModel):
    return _stacked(srp_xyz(*_xyz(r_eci), r_sun_eci, jnp.asarray(mass_kg), fm))


def perturbing_acceleration(r_eci, mass_kg, env: Environment, fm: ForceModel):
    return _stacked(perturbing_xyz(*_xyz(r_eci), jnp.asarray(mass_kg), env, fm))
