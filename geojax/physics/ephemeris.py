"""Analytic geocentric Sun and Moon positions.

Sun: Meeus, *Astronomical Algorithms* 2nd ed., ch. 25 (low-accuracy solar
coordinates, stated 0.01 deg).  Moon: Meeus ch. 47 (the 60 + 60 largest terms
of ELP-2000/82, stated 10" in longitude, 4" in latitude).  Both give geometric
coordinates in the mean ecliptic and equinox of date; we rotate them into the
geojax ECI frame.

The geojax ECI frame is the **mean equator and equinox of the scenario
epoch** (a frame frozen at the epoch, "mean of epoch").  Why not EME2000: the
GEO targets of Li 2022 (i_y = 3e-5, eq. 44) and its initial longitude (eq. 43
gives 96.00 deg E only against the equinox of date) are referred to the Earth's
equator of 2020, which is 0.11 deg from the J2000 equator.  Over one year the
true pole moves 20" from the frozen z axis and nutation adds 9"; we neglect
both (0.006 deg, below the 0.1 % inclination-drift budget).  The equinox
precession along the equator (46"/yr) is kept in the Earth rotation angle, see
``frames.earth_rotation_angle_rad``.

Accuracy measured against ERFA (`tests/test_ephemeris.py`), 2000-2050:
Sun direction better than 0.01 deg against ``eraEpv00`` (VSOP2000-based);
Moon direction better than 0.01 deg and distance better than 0.1 % against
``eraMoon98``.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from geojax.physics.constants import AU_M, DAYS_PER_JULIAN_CENTURY, JD_J2000, SECONDS_PER_DAY
from geojax.physics.time import julian_centuries_tt

# Meeus Table 47.A: multiples of (D, M, M', F), then sum_l [1e-6 deg] and
# sum_r [1e-3 km].
MOON_LR_TERMS = np.array([
    [0, 0, 1, 0, 6288774, -20905355], [2, 0, -1, 0, 1274027, -3699111],
    [2, 0, 0, 0, 658314, -2955968], [0, 0, 2, 0, 213618, -569925],
    [0, 1, 0, 0, -185116, 48888], [0, 0, 0, 2, -114332, -3149],
    [2, 0, -2, 0, 58793, 246158], [2, -1, -1, 0, 57066, -152138],
    [2, 0, 1, 0, 53322, -170733], [2, -1, 0, 0, 45758, -204586],
    [0, 1, -1, 0, -40923, -129620], [1, 0, 0, 0, -34720, 108743],
    [0, 1, 1, 0, -30383, 104755], [2, 0, 0, -2, 15327, 10321],
    [0, 0, 1, 2, -12528, 0], [0, 0, 1, -2, 10980, 79661],
    [4, 0, -1, 0, 10675, -34782], [0, 0, 3, 0, 10034, -23210],
    [4, 0, -2, 0, 8548, -21636], [2, 1, -1, 0, -7888, 24208],
    [2, 1, 0, 0, -6766, 30824], [1, 0, -1, 0, -5163, -8379],
    [1, 1, 0, 0, 4987, -16675], [2, -1, 1, 0, 4036, -12831],
    [2, 0, 2, 0, 3994, -10445], [4, 0, 0, 0, 3861, -11650],
    [2, 0, -3, 0, 3665, 14403], [0, 1, -2, 0, -2689, -7003],
    [2, 0, -1, 2, -2602, 0], [2, -1, -2, 0, 2390, 10056],
    [1, 0, 1, 0, -2348, 6322], [2, -2, 0, 0, 2236, -9884],
    [0, 1, 2, 0, -2120, 5751], [0, 2, 0, 0, -2069, 0],
    [2, -2, -1, 0, 2048, -4950], [2, 0, 1, -2, -1773, 4130],
    [2, 0, 0, 2, -1595, 0], [4, -1, -1, 0, 1215, -3958],
    [0, 0, 2, 2, -1110, 0], [3, 0, -1, 0, -892, 3258],
    [2, 1, 1, 0, -810, 2616], [4, -1, -2, 0, 759, -1897],
    [0, 2, -1, 0, -713, -2117], [2, 2, -1, 0, -700, 2354],
    [2, 1, -2, 0, 691, 0], [2, -1, 0, -2, 596, 0],
    [4, 0, 1, 0, 549, -1423], [0, 0, 4, 0, 537, -1117],
    [4, -1, 0, 0, 520, -1571], [1, 0, -2, 0, -487, -1739],
    [2, 1, 0, -2, -399, 0], [0, 0, 2, -2, -381, -4421],
    [1, 1, 1, 0, 351, 0], [3, 0, -2, 0, -340, 0],
    [4, 0, -3, 0, 330, 0], [2, -1, 2, 0, 327, 0],
    [0, 2, 1, 0, -323, 1165], [1, 1, -1, 0, 299, 0],
    [2, 0, 3, 0, 294, 0], [2, 0, -1, -2, 0, 8752],
], dtype=np.float64)

# Meeus Table 47.B: multiples of (D, M, M', F), then sum_b [1e-6 deg].
MOON_B_TERMS = np.array([
    [0, 0, 0, 1, 5128122], [0, 0, 1, 1, 280602], [0, 0, 1, -1, 277693],
    [2, 0, 0, -1, 173237], [2, 0, -1, 1, 55413], [2, 0, -1, -1, 46271],
    [2, 0, 0, 1, 32573], [0, 0, 2, 1, 17198], [2, 0, 1, -1, 9266],
    [0, 0, 2, -1, 8822], [2, -1, 0, -1, 8216], [2, 0, -2, -1, 4324],
    [2, 0, 1, 1, 4200], [2, 1, 0, -1, -3359], [2, -1, -1, 1, 2463],
    [2, -1, 0, 1, 2211], [2, -1, -1, -1, 2065], [0, 1, -1, -1, -1870],
    [4, 0, -1, -1, 1828], [0, 1, 0, 1, -1794], [0, 0, 0, 3, -1749],
    [0, 1, -1, 1, -1565], [1, 0, 0, 1, -1491], [0, 1, 1, 1, -1475],
    [0, 1, 1, -1, -1410], [0, 1, 0, -1, -1344], [1, 0, 0, -1, -1335],
    [0, 0, 3, 1, 1107], [4, 0, 0, -1, 1021], [4, 0, -1, 1, 833],
    [0, 0, 1, -3, 777], [4, 0, -2, 1, 671], [2, 0, 0, -3, 607],
    [2, 0, 2, -1, 596], [2, -1, 1, -1, 491], [2, 0, -2, 1, -451],
    [0, 0, 3, -1, 439], [2, 0, 2, 1, 422], [2, 0, -3, -1, 421],
    [2, 1, -1, 1, -366], [2, 1, 0, 1, -351], [4, 0, 0, 1, 331],
    [2, -1, 1, 1, 315], [2, -2, 0, -1, 302], [0, 0, 1, 3, -283],
    [2, 1, 1, -1, -229], [1, 1, 0, -1, 223], [1, 1, 0, 1, 223],
    [0, 1, -2, -1, -220], [2, 1, -1, -1, -220], [1, 0, 1, 1, -185],
    [2, -1, -2, -1, 181], [0, 1, 2, 1, -177], [4, 0, -2, -1, 176],
    [4, -1, -1, -1, 166], [1, 0, 1, -1, -164], [4, 0, 1, -1, 132],
    [1, 0, -1, -1, -119], [4, -1, 0, -1, 115], [2, -2, 0, 1, 107],
], dtype=np.float64)


# Meeus eqs. (47.1)-(47.5) and p. 338: polynomials in Julian centuries TT, degrees,
# lowest degree first: L' (mean longitude), D, M, M', F, and the arguments A1, A2, A3.
MOON_ARGUMENTS_DEG = {
    "mean_longitude": (218.3164477, 481267.88123421, -0.0015786, 1 / 538841.0, -1 / 65194000.0),
    "elongation": (297.8501921, 445267.1114034, -0.0018819, 1 / 545868.0, -1 / 113065000.0),
    "sun_anomaly": (357.5291092, 35999.0502909, -0.0001536, 1 / 24490000.0),
    "moon_anomaly": (134.9633964, 477198.8675055, 0.0087414, 1 / 69699.0, -1 / 14712000.0),
    "latitude_argument": (93.2720950, 483202.0175233, -0.0036539, -1 / 3526000.0, 1 / 863310000.0),
    "a1": (119.75, 131.849),
    "a2": (53.09, 479264.290),
    "a3": (313.45, 481266.484),
}


def _poly_deg(coefficients, t):
    """Polynomial in Julian centuries t, coefficients from degree 0 up; radians."""
    value = jnp.zeros_like(t)
    for c in reversed(coefficients):
        value = value * t + c
    return jnp.deg2rad(value)


def mean_obliquity_rad(t):
    """Mean obliquity of the ecliptic, IAU 1980 (Meeus eq. (22.2)); t in Julian centuries TT."""
    return jnp.deg2rad((84381.448 - 46.8150 * t - 0.00059 * t**2 + 0.001813 * t**3) / 3600.0)


def general_precession_rad(t):
    """General precession in longitude since J2000.0 (IAU 2006, Capitaine et al. 2003)."""
    return jnp.deg2rad((5028.796195 * t + 1.1054348 * t**2) / 3600.0)


def sun_ecliptic_of_date(t):
    """Geometric Sun longitude [rad] and distance [m], mean ecliptic and equinox of date (Meeus ch. 25)."""
    t = jnp.asarray(t, dtype=jnp.float64)
    l0 = _poly_deg((280.46646, 36000.76983, 0.0003032), t)
    m = _poly_deg((357.52911, 35999.05029, -0.0001537), t)
    e = 0.016708634 - 0.000042037 * t - 0.0000001267 * t**2
    c = jnp.deg2rad(
        (1.914602 - 0.004817 * t - 0.000014 * t**2) * jnp.sin(m)
        + (0.019993 - 0.000101 * t) * jnp.sin(2 * m)
        + 0.000289 * jnp.sin(3 * m)
    )
    true_anomaly = m + c
    distance_au = 1.000001018 * (1 - e**2) / (1 + e * jnp.cos(true_anomaly))
    return l0 + c, distance_au * AU_M


def moon_ecliptic_of_date(t):
    """Geometric Moon longitude, latitude [rad] and distance [m], mean ecliptic and equinox of date (Meeus ch. 47)."""
    t = jnp.asarray(t, dtype=jnp.float64)
    lp, d, m, mp, f, a1, a2, a3 = (_poly_deg(c, t) for c in MOON_ARGUMENTS_DEG.values())
    ecc = 1 - 0.002516 * t - 0.0000074 * t**2

    fundamental = jnp.stack([d, m, mp, f], axis=-1)  # [..., 4]

    def series(table, column, trig):
        argument = fundamental @ table[:, :4].T  # [..., terms]
        # Terms with the Sun's anomaly M carry E^|multiple of M| (Meeus p. 338).
        scale = ecc[..., None] ** np.abs(table[:, 1])
        return jnp.sum(table[:, column] * scale * trig(argument), axis=-1)

    sum_l = series(MOON_LR_TERMS, 4, jnp.sin) + 3958 * jnp.sin(a1) + 1962 * jnp.sin(lp - f) + 318 * jnp.sin(a2)
    sum_r = series(MOON_LR_TERMS, 5, jnp.cos)
    sum_b = (
        series(MOON_B_TERMS, 4, jnp.sin)
        - 2235 * jnp.sin(lp) + 382 * jnp.sin(a3) + 175 * jnp.sin(a1 - f)
        + 175 * jnp.sin(a1 + f) + 127 * jnp.sin(lp - mp) - 115 * jnp.sin(lp + mp)
    )
    longitude = lp + jnp.deg2rad(sum_l * 1e-6)
    latitude = jnp.deg2rad(sum_b * 1e-6)
    distance_m = (385000.56 + sum_r * 1e-3) * 1e3
    return longitude, latitude, distance_m


def ecliptic_of_date_to_eci(longitude, latitude, distance_m, t, frame_t):
    """Spherical ecliptic-of-date coordinates to the ECI frame of epoch ``frame_t`` (Julian centuries TT).

    The equinox is moved back by the general precession accumulated since the
    frame epoch; the 0.47"/yr motion of the ecliptic itself is neglected.
    """
    longitude = longitude - (general_precession_rad(t) - general_precession_rad(frame_t))
    eps = mean_obliquity_rad(frame_t)
    x_ecl = distance_m * jnp.cos(latitude) * jnp.cos(longitude)
    y_ecl = distance_m * jnp.cos(latitude) * jnp.sin(longitude)
    z_ecl = distance_m * jnp.sin(latitude)
    return jnp.stack(
        [x_ecl, jnp.cos(eps) * y_ecl - jnp.sin(eps) * z_ecl, jnp.sin(eps) * y_ecl + jnp.cos(eps) * z_ecl],
        axis=-1,
    )


def sun_position_eci_m(t_tt_s, frame_epoch_tt_s):
    """Geocentric Sun position [..., 3] in metres, ECI of ``frame_epoch_tt_s``."""
    t = julian_centuries_tt(jnp.asarray(t_tt_s, dtype=jnp.float64))
    longitude, distance_m = sun_ecliptic_of_date(t)
    return ecliptic_of_date_to_eci(longitude, jnp.zeros_like(t), distance_m, t, julian_centuries_tt(frame_epoch_tt_s))


def moon_position_eci_m(t_tt_s, frame_epoch_tt_s):
    """Geocentric Moon position [..., 3] in metres, ECI of ``frame_epoch_tt_s``."""
    t = julian_centuries_tt(jnp.asarray(t_tt_s, dtype=jnp.float64))
    longitude, latitude, distance_m = moon_ecliptic_of_date(t)
    return ecliptic_of_date_to_eci(longitude, latitude, distance_m, t, julian_centuries_tt(frame_epoch_tt_s))


# JPL DE421 (Folkner, Williams & Boggs, IPN Progress Report 42-178, 2009), read by jplephem from the `de421`
# package (offline; jplephem's ``ephem`` reader of that package, Chebyshev series of positions in km, ICRF).
def de421_sun_moon_eci_m(t_tt_s, frame_epoch_tt_s):
    """Geocentric Sun and Moon positions [..., 3] (m), ECI of ``frame_epoch_tt_s``, from JPL DE421 (NumPy).

    TDB is taken as TT (they differ by < 2 ms).  ICRF (= mean equator and equinox of J2000.0 to 0.02") is
    turned to the mean equator and equinox of the frame epoch by the IAU 1976 precession angles zeta, z,
    theta (Lieske et al. 1977; Meeus eqs. (21.2)-(21.4)).
    """
    import de421
    from jplephem.ephem import Ephemeris

    ephemeris = Ephemeris(de421)
    jd = JD_J2000 + np.asarray(t_tt_s, dtype=np.float64) / SECONDS_PER_DAY
    moon = ephemeris.position("moon", jd)  # geocentric, km [3, ...]
    earth = ephemeris.position("earthmoon", jd) - moon * ephemeris.earth_share
    sun = ephemeris.position("sun", jd) - earth
    rotation = precession_from_j2000(float(frame_epoch_tt_s))
    shape = np.shape(t_tt_s) + (3,)  # jplephem gives [3, 1] for a scalar time
    return tuple(np.moveaxis(np.einsum("ij,j...->i...", rotation, body), 0, -1).reshape(shape) * 1e3
                 for body in (sun, moon))


def precession_from_j2000(t_tt_s: float) -> np.ndarray:
    """[3, 3]: J2000 mean-equator vector -> mean equator and equinox of ``t_tt_s``, R3(-z) R2(theta) R3(-zeta)."""
    t = t_tt_s / SECONDS_PER_DAY / DAYS_PER_JULIAN_CENTURY
    arcsec = np.pi / 180 / 3600
    zeta = (2306.2181 * t + 0.30188 * t**2 + 0.017998 * t**3) * arcsec
    z = (2306.2181 * t + 1.09468 * t**2 + 0.018203 * t**3) * arcsec
    theta = (2004.3109 * t - 0.42665 * t**2 - 0.041833 * t**3) * arcsec

    def r3(a):
        return np.array([[np.cos(a), np.sin(a), 0.0], [-np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])

    r2 = np.array([[np.cos(theta), 0.0, -np.sin(theta)], [0.0, 1.0, 0.0], [np.sin(theta), 0.0, np.cos(theta)]])
    return r3(-z) @ r2 @ r3(-zeta)
