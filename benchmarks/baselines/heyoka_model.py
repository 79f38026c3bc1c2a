"""The geojax force model (Li 2022, eq. (4)) as a heyoka ODE system in Cartesian ECI.

The state is ECI position and velocity (m, m/s) in the frame of the scenario
epoch; heyoka's time is seconds since that epoch.  The Sun and Moon positions
are the Meeus series of ``geojax.physics.ephemeris`` written as heyoka expressions of
``hy.time`` (one sin/cos term per row of the coefficient tables), so the
Taylor integrator differentiates the ephemeris exactly like the dynamics.

Earth shadow: the conical umbra/penumbra model of geojax can be written with
``hy.select`` (``shadow=True``), but it is not analytic at the penumbra
boundaries (the occulted area goes as (a + b - sep)^(3/2)).  A Taylor step that
starts on one branch extrapolates that branch across a boundary, and a step
that starts inside the penumbra sees a branch point at zero distance, so the
integrator either steps over eclipses or crawls through them.  The benchmark
therefore times every implementation with the shadow switched off, and uses
``shadow=True`` only for an accuracy reference with the step capped (via
``max_delta_t``) during eclipse seasons.
"""

from __future__ import annotations

import heyoka as hy
import numpy as np

from geojax.physics import constants as c
from geojax.physics.ephemeris import MOON_ARGUMENTS_DEG, MOON_B_TERMS, MOON_LR_TERMS

from .numpy_model import Model

_SECONDS_PER_CENTURY = c.SECONDS_PER_DAY * c.DAYS_PER_JULIAN_CENTURY
_DEG = np.pi / 180.0
STATE_NAMES = ("x", "y", "z", "vx", "vy", "vz")


def _poly_rad(coefficients, t):
    """Polynomial expression in Julian centuries ``t`` with coefficients in degrees; radians."""
    value = coefficients[-1] * _DEG
    for coefficient in reversed(coefficients[:-1]):
        value = value * t + coefficient * _DEG
    return value


def _norm(v):
    return hy.sqrt(hy.sum([v[0] * v[0], v[1] * v[1], v[2] * v[2]]))


def _dot(u, v):
    return hy.sum([u[0] * v[0], u[1] * v[1], u[2] * v[2]])


def _julian_centuries(epoch_tt_s):
    """Julian centuries TT since J2000 as an expression of ``hy.time`` (seconds since the epoch)."""
    return epoch_tt_s / _SECONDS_PER_CENTURY + hy.time / _SECONDS_PER_CENTURY


def _ecliptic_to_eci(longitude, latitude_terms, distance_m, t, frame_t):
    """Ecliptic-of-date (longitude, latitude, distance) to ECI of ``frame_t`` (see ``geojax.physics.ephemeris``).

    ``latitude_terms`` is None for the Sun (latitude 0).
    """
    precession = (5028.796195 * t + 1.1054348 * t**2 - (5028.796195 * frame_t + 1.1054348 * frame_t**2)) * (
        _DEG / 3600.0
    )
    longitude = longitude - precession
    eps = np.deg2rad((84381.448 - 46.8150 * frame_t - 0.00059 * frame_t**2 + 0.001813 * frame_t**3) / 3600.0)
    if latitude_terms is None:
        x, y, z = distance_m * hy.cos(longitude), distance_m * hy.sin(longitude), 0.0
    else:
        in_plane = distance_m * hy.cos(latitude_terms)
        x, y, z = in_plane * hy.cos(longitude), in_plane * hy.sin(longitude), distance_m * hy.sin(latitude_terms)
    return [x, np.cos(eps) * y - np.sin(eps) * z, np.sin(eps) * y + np.cos(eps) * z]


def sun_position(t, frame_t):
    """Geocentric Sun position (Meeus ch. 25), list of 3 expressions in metres."""
    l0 = _poly_rad((280.46646, 36000.76983, 0.0003032), t)
    m = _poly_rad((357.52911, 35999.05029, -0.0001537), t)
    e = 0.016708634 - 0.000042037 * t - 0.0000001267 * t**2
    center = _DEG * (
        (1.914602 - 0.004817 * t - 0.000014 * t**2) * hy.sin(m)
        + (0.019993 - 0.000101 * t) * hy.sin(2.0 * m)
        + 0.000289 * hy.sin(3.0 * m)
    )
    distance_m = (1.000001018 * c.AU_M) * (1.0 - e**2) / (1.0 + e * hy.cos(m + center))
    return _ecliptic_to_eci(l0 + center, None, distance_m, t, frame_t)


def _moon_series(table, column, trig, fundamental, ecc):
    """sum_j coeff_j E^|M_j| trig(D_j d + M_j m + M'_j m' + F_j f) over the rows of a Meeus table."""
    ecc_powers = {0: 1.0, 1: ecc, 2: ecc * ecc}
    terms = []
    for row in table:
        coefficient = float(row[column])
        if coefficient == 0.0:
            continue
        argument = hy.sum([float(k) * x for k, x in zip(row[:4], fundamental) if k != 0])
        terms.append(coefficient * ecc_powers[int(abs(row[1]))] * trig(argument))
    return hy.sum(terms)


def moon_position(t, frame_t):
    """Geocentric Moon position (Meeus ch. 47), list of 3 expressions in metres."""
    lp, d, m, mp, f, a1, a2, a3 = (_poly_rad(c, t) for c in MOON_ARGUMENTS_DEG.values())
    ecc = 1.0 - 0.002516 * t - 0.0000074 * t**2
    fundamental = (d, m, mp, f)

    sum_l = _moon_series(MOON_LR_TERMS, 4, hy.sin, fundamental, ecc) + (
        3958.0 * hy.sin(a1) + 1962.0 * hy.sin(lp - f) + 318.0 * hy.sin(a2)
    )
    sum_r = _moon_series(MOON_LR_TERMS, 5, hy.cos, fundamental, ecc)
    sum_b = _moon_series(MOON_B_TERMS, 4, hy.sin, fundamental, ecc) + hy.sum(
        [
            -2235.0 * hy.sin(lp), 382.0 * hy.sin(a3), 175.0 * hy.sin(a1 - f),
            175.0 * hy.sin(a1 + f), 127.0 * hy.sin(lp - mp), -115.0 * hy.sin(lp + mp),
        ]
    )
    longitude = lp + sum_l * (1e-6 * _DEG)
    latitude = sum_b * (1e-6 * _DEG)
    distance_m = 385000.56e3 + sum_r
    return _ecliptic_to_eci(longitude, latitude, distance_m, t, frame_t)


def _third_body(r, r_body, mu_body):
    """Li 2022, eq. (4): mu_q (R_q / |R_q|^3 - r_q / |r_q|^3), R_q = r_q - r."""
    rel = [r_body[j] - r[j] for j in range(3)]
    inv_d3 = _norm(rel) ** -3.0
    inv_rb3 = _norm(r_body) ** -3.0
    return [mu_body * (rel[j] * inv_d3 - r_body[j] * inv_rb3) for j in range(3)]


def shadow_fraction(r, r_sun, r_earth_m):
    """Visible solar-disc fraction with ``hy.select`` (Montenbruck & Gill, Sec. 3.4.2); not analytic at the edges."""
    to_sun = [r_sun[j] - r[j] for j in range(3)]
    d_sun, d_earth = _norm(to_sun), _norm(r)
    a = hy.asin(c.R_SUN_M / d_sun)
    b = hy.asin(r_earth_m / d_earth)
    sep = hy.acos(-_dot(r, to_sun) / (d_earth * d_sun))
    x = (sep * sep + a * a - b * b) / (2.0 * sep)
    y = hy.sqrt(a * a - x * x)
    area = a * a * hy.acos(x / a) + b * b * hy.acos((sep - x) / b) - sep * y
    partial = 1.0 - area / (np.pi * a * a)
    return hy.select(hy.gte(sep, a + b), 1.0, hy.select(hy.lte(sep, b - a), 0.0, partial))


def _srp(r, r_sun, model: Model, shadow: bool):
    """Li 2022, eq. (4): -P(1 AU) (1 + eta) S/m (1 AU / d)^2 d_hat, d = r_sun - r."""
    to_sun = [r_sun[j] - r[j] for j in range(3)]
    d = _norm(to_sun)
    scale = -model.srp_accel_1au * c.AU_M**2 * d**-3.0
    if shadow:
        scale = scale * shadow_fraction(r, r_sun, model.r_earth_m)
    return [scale * to_sun[j] for j in range(3)]


def accelerations(model: Model, shadow: bool = False):
    """(state variables, [ax, ay, az] expressions) of the full force model."""
    state = hy.make_vars(*STATE_NAMES)
    r = state[:3]
    t = _julian_centuries(model.epoch_tt_s)
    frame_t = model.epoch_tt_s / _SECONDS_PER_CENTURY
    r_sun, r_moon = sun_position(t, frame_t), moon_position(t, frame_t)

    r2 = _dot(r, r)
    inv_r3 = r2**-1.5
    j2_factor = (1.5 * model.mu * model.j2 * model.r_earth_m**2) * r2**-2.5
    j2_radial = 5.0 * r[2] * r[2] / r2 - 1.0
    j2 = [j2_factor * j2_radial * r[0], j2_factor * j2_radial * r[1], j2_factor * (j2_radial * r[2] - 2.0 * r[2])]
    sun = _third_body(r, r_sun, model.mu_sun)
    moon = _third_body(r, r_moon, model.mu_moon)
    srp = _srp(r, r_sun, model, shadow)
    accel = [hy.sum([-model.mu * r[j] * inv_r3, j2[j], sun[j], moon[j], srp[j]]) for j in range(3)]
    return state, accel


def ode_system(model: Model, shadow: bool = False):
    """[(variable, rhs)] pairs for ``hy.taylor_adaptive``/``hy.taylor_adaptive_batch``."""
    state, accel = accelerations(model, shadow)
    return list(zip(state, list(state[3:]) + accel))


def acceleration_cfunc(model: Model, shadow: bool = False):
    """Compiled evaluator of the accelerations: f(r [3, n], time=t [n]) -> a [3, n] (for cross-checks)."""
    state, accel = accelerations(model, shadow)
    return hy.cfunc(accel, vars=list(state[:3]))
