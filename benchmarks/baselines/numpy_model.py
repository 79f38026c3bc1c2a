"""The geojax force model (Li 2022, eq. (4)) in plain NumPy, Cartesian ECI, for ``scipy.integrate.solve_ivp``.

Earth point mass + J2 (z of the ECI frame) + Sun and Moon third body + solar
radiation pressure (1/r^2 from the Sun) with the conical Earth shadow of
Montenbruck & Gill (2000), Sec. 3.4.2.  Sun and Moon positions are the Meeus
series of ``geojax.physics.ephemeris`` evaluated with NumPy; only the coefficient
tables and constants are imported from geojax, no JAX code runs here.

Time ``t`` in the right-hand side is seconds since the scenario epoch; the
state is ECI position and velocity (m, m/s) in the frame of that epoch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from geojax.physics import constants as c
from geojax.physics.ephemeris import MOON_ARGUMENTS_DEG, MOON_B_TERMS, MOON_LR_TERMS

_SECONDS_PER_CENTURY = c.SECONDS_PER_DAY * c.DAYS_PER_JULIAN_CENTURY
_ARC_SECONDS = 3600.0

# Meeus Table 47.A/B split into argument multiples, the power of E and the coefficients.
_LR_MULTIPLES = MOON_LR_TERMS[:, :4]
_LR_E_POWER = np.abs(MOON_LR_TERMS[:, 1])
_L_COEFF = MOON_LR_TERMS[:, 4]
_R_COEFF = MOON_LR_TERMS[:, 5]
_B_MULTIPLES = MOON_B_TERMS[:, :4]
_B_E_POWER = np.abs(MOON_B_TERMS[:, 1])
_B_COEFF = MOON_B_TERMS[:, 4]


@dataclass(frozen=True)
class Model:
    """Force-model constants (SI) and the frame epoch; built from a geojax scenario by ``from_scenario``."""

    epoch_tt_s: float
    mass_kg: float
    mu: float = c.MU_EARTH_M3_S2
    r_earth_m: float = c.R_EARTH_M
    j2: float = c.J2
    mu_sun: float = c.MU_SUN_M3_S2
    mu_moon: float = c.MU_MOON_M3_S2
    srp_pressure_1au_n_m2: float = 4.5605e-6
    reflectivity: float = 0.6
    srp_area_m2: float = 0.0
    shadow: bool = True

    @property
    def srp_accel_1au(self) -> float:
        """P(1 AU) (1 + eta) S / m, m/s^2."""
        return self.srp_pressure_1au_n_m2 * (1 + self.reflectivity) * self.srp_area_m2 / self.mass_kg


def from_scenario(scenario, shadow: bool | None = None) -> Model:
    """The NumPy model of a geojax scenario (J2, Sun, Moon and SRP must be on, C22/S22 off)."""
    fm = scenario.force_model
    if (fm.j2_on, fm.sun_on, fm.moon_on, fm.srp_on, fm.c22_on) != (1.0, 1.0, 1.0, 1.0, 0.0):
        raise ValueError("the baselines implement J2 + Sun + Moon + SRP only")
    return Model(
        epoch_tt_s=scenario.epoch_tt_s,
        mass_kg=scenario.mass_kg,
        mu=fm.mu_m3_s2,
        r_earth_m=fm.r_earth_m,
        j2=fm.j2,
        mu_sun=fm.mu_sun_m3_s2,
        mu_moon=fm.mu_moon_m3_s2,
        srp_pressure_1au_n_m2=fm.srp_pressure_1au_n_m2,
        reflectivity=fm.reflectivity,
        srp_area_m2=fm.srp_area_m2,
        shadow=bool(fm.shadow_on) if shadow is None else shadow,
    )


# --- Ephemerides (Meeus, Astronomical Algorithms, 2nd ed., ch. 22, 25 and 47) -----------------


def _poly_rad(coefficients, t):
    """Polynomial in Julian centuries ``t`` with coefficients in degrees, lowest degree first; radians."""
    value = 0.0
    for coefficient in reversed(coefficients):
        value = value * t + coefficient
    return np.deg2rad(value)


def mean_obliquity_rad(t):
    """IAU 1980 mean obliquity (Meeus eq. (22.2))."""
    return np.deg2rad((84381.448 - 46.8150 * t - 0.00059 * t**2 + 0.001813 * t**3) / _ARC_SECONDS)


def general_precession_rad(t):
    """General precession in longitude since J2000.0 (IAU 2006)."""
    return np.deg2rad((5028.796195 * t + 1.1054348 * t**2) / _ARC_SECONDS)


def sun_ecliptic(t):
    """Sun longitude [rad] and distance [m], mean ecliptic and equinox of date (Meeus ch. 25)."""
    l0 = _poly_rad((280.46646, 36000.76983, 0.0003032), t)
    m = _poly_rad((357.52911, 35999.05029, -0.0001537), t)
    e = 0.016708634 - 0.000042037 * t - 0.0000001267 * t**2
    center = np.deg2rad(
        (1.914602 - 0.004817 * t - 0.000014 * t**2) * np.sin(m)
        + (0.019993 - 0.000101 * t) * np.sin(2 * m)
        + 0.000289 * np.sin(3 * m)
    )
    distance_au = 1.000001018 * (1 - e**2) / (1 + e * np.cos(m + center))
    return l0 + center, distance_au * c.AU_M


def moon_ecliptic(t):
    """Moon longitude, latitude [rad] and distance [m], mean ecliptic and equinox of date (Meeus ch. 47)."""
    lp, d, m, mp, f, a1, a2, a3 = (_poly_rad(c, t) for c in MOON_ARGUMENTS_DEG.values())
    ecc = 1 - 0.002516 * t - 0.0000074 * t**2

    fundamental = np.array([d, m, mp, f])
    lr_argument = _LR_MULTIPLES @ fundamental
    lr_scale = ecc**_LR_E_POWER
    b_argument = _B_MULTIPLES @ fundamental
    sum_l = np.dot(_L_COEFF * lr_scale, np.sin(lr_argument))
    sum_l += 3958 * np.sin(a1) + 1962 * np.sin(lp - f) + 318 * np.sin(a2)
    sum_r = np.dot(_R_COEFF * lr_scale, np.cos(lr_argument))
    sum_b = np.dot(_B_COEFF * ecc**_B_E_POWER, np.sin(b_argument))
    sum_b += (
        -2235 * np.sin(lp) + 382 * np.sin(a3) + 175 * np.sin(a1 - f)
        + 175 * np.sin(a1 + f) + 127 * np.sin(lp - mp) - 115 * np.sin(lp + mp)
    )
    return lp + np.deg2rad(sum_l * 1e-6), np.deg2rad(sum_b * 1e-6), (385000.56 + sum_r * 1e-3) * 1e3


def ecliptic_to_eci(longitude, latitude, distance_m, t, frame_t):
    """Ecliptic-of-date spherical coordinates to the ECI frame (mean equator and equinox) of ``frame_t``."""
    longitude = longitude - (general_precession_rad(t) - general_precession_rad(frame_t))
    eps = mean_obliquity_rad(frame_t)
    x = distance_m * np.cos(latitude) * np.cos(longitude)
    y = distance_m * np.cos(latitude) * np.sin(longitude)
    z = distance_m * np.sin(latitude)
    return np.array([x, np.cos(eps) * y - np.sin(eps) * z, np.sin(eps) * y + np.cos(eps) * z])


def sun_moon_eci_m(t_tt_s, frame_epoch_tt_s):
    """Geocentric Sun and Moon positions [3] (m) at a TT time, ECI of ``frame_epoch_tt_s``."""
    t = t_tt_s / _SECONDS_PER_CENTURY
    frame_t = frame_epoch_tt_s / _SECONDS_PER_CENTURY
    sun_lon, sun_dist = sun_ecliptic(t)
    moon_lon, moon_lat, moon_dist = moon_ecliptic(t)
    return (
        ecliptic_to_eci(sun_lon, 0.0, sun_dist, t, frame_t),
        ecliptic_to_eci(moon_lon, moon_lat, moon_dist, t, frame_t),
    )


# --- Accelerations (Li 2022, eq. (4)) ---------------------------------------------------------


def j2_acceleration(r, model: Model):
    """J2 of the Earth, pole along the ECI z axis."""
    r2 = r @ r
    z = r[2]
    factor = 1.5 * model.mu * model.j2 * model.r_earth_m**2 / r2**2.5
    return factor * ((5 * z**2 / r2 - 1) * r - np.array([0.0, 0.0, 2 * z]))


def third_body(r, r_body, mu_body):
    """mu_q (R_q / |R_q|^3 - r_q / |r_q|^3), R_q = r_q - r."""
    rel = r_body - r
    return mu_body * (rel / np.linalg.norm(rel) ** 3 - r_body / np.linalg.norm(r_body) ** 3)


def shadow_fraction(r, r_sun, r_earth_m):
    """Visible fraction of the solar disc, conical umbra and penumbra (Montenbruck & Gill, Sec. 3.4.2)."""
    to_sun = r_sun - r
    d_sun = np.linalg.norm(to_sun)
    d_earth = np.linalg.norm(r)
    a = np.arcsin(c.R_SUN_M / d_sun)
    b = np.arcsin(r_earth_m / d_earth)
    sep = np.arccos(np.clip(-(r @ to_sun) / (d_earth * d_sun), -1.0, 1.0))
    if sep >= a + b:
        return 1.0
    if sep <= b - a:
        return 0.0
    x = (sep**2 + a**2 - b**2) / (2 * sep)
    y = np.sqrt(max(a**2 - x**2, 0.0))
    area = a**2 * np.arccos(np.clip(x / a, -1, 1)) + b**2 * np.arccos(np.clip((sep - x) / b, -1, 1)) - sep * y
    return float(np.clip(1 - area / (np.pi * a**2), 0.0, 1.0))


def srp_acceleration(r, r_sun, model: Model):
    """-P(1 AU) (1 + eta) S/m (1 AU / d)^2 d_hat, d = r_sun - r, times the visible fraction."""
    to_sun = r_sun - r
    d = np.linalg.norm(to_sun)
    light = shadow_fraction(r, r_sun, model.r_earth_m) if model.shadow else 1.0
    return -light * model.srp_accel_1au * (c.AU_M / d) ** 2 * to_sun / d


def acceleration(t_s, r, model: Model):
    """Total ECI acceleration [3] (m/s^2) at ``t_s`` seconds after the epoch."""
    r_sun, r_moon = sun_moon_eci_m(model.epoch_tt_s + t_s, model.epoch_tt_s)
    return (
        -model.mu * r / np.linalg.norm(r) ** 3
        + j2_acceleration(r, model)
        + third_body(r, r_sun, model.mu_sun)
        + third_body(r, r_moon, model.mu_moon)
        + srp_acceleration(r, r_sun, model)
    )


def rhs(t_s, y, model: Model):
    """d(r, v)/dt for ``solve_ivp``."""
    return np.concatenate([y[3:], acceleration(t_s, y[:3], model)])


def propagate(y0, t_end_s, model: Model, t_eval=None, rtol=1e-10, atol=1e-6):
    """Integrate from t = 0 to ``t_end_s`` with DOP853; returns the ``solve_ivp`` result."""
    return solve_ivp(
        rhs, (0.0, t_end_s), np.asarray(y0, dtype=float), method="DOP853",
        t_eval=t_eval, rtol=rtol, atol=atol, args=(model,),
    )
