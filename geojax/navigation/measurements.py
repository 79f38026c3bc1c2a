"""Measurement models: two-way range with light time, two-way range rate, azimuth and elevation from a ground
station, and a GNSS-in-GEO position fix; their noise, bias, visibility and Jacobian.

Every model is ``h(x_eci, station, earth_angle_rad) -> [m]``: ``x_eci`` [6] the satellite's ECI position (m)
and velocity (m/s) at the measurement's time tag, the station's reception time t_R; ``earth_angle_rad`` the
loop's Earth angle at t_R (``stations``).  Times inside the light-time solution are offsets from t_R, so no
absolute time enters.  The satellite is moved off t_R by its second-order Taylor series under point-mass
gravity, r - v tau + a tau^2 / 2: at GEO (|v| 3.07 km/s, |a| 0.22 m/s^2, jerk 1.6e-5 m/s^3) the third-order
term over the 0.12 s leg is 5e-9 m.

Light time.  The down leg tau_d solves tau_d = |r_sat(t_R - tau_d) - r_stn(t_R)| / c, the up leg tau_u =
|r_sat(t_R - tau_d) - r_stn(t_R - tau_d - tau_u)| / c; each is iterated ``LIGHT_TIME_ITERATIONS`` times
from the instantaneous distance.  The iteration contracts by |d rho / dt| / c <= (3.07 + 0.47) km/s / c =
1.2e-5 per pass (the satellite's and a station's inertial speeds), and the first guess is off by at most the
distance the satellite moves in 0.12 s, 370 m: after one pass 4.4 mm, after two 5e-8 m, after three 6e-13 m,
below the 7e-9 m spacing of float64 at 3.6e7 m.  Three passes therefore give the solution to rounding.

Range rate is instantaneous: the time derivative of the two-way light-time range at t_R (``jax.jvp`` along the
satellite's motion and the Earth's rotation).  A Doppler count averaged over T_c measures the mean over
[t_R - T_c, t_R]; for a GEO satellite seen from the ground (range acceleration < 1e-4 m/s^2) the two differ
by less than 5e-5 T_c m/s, under any Doppler noise for counts up to a minute.

Azimuth and elevation are the direction of the down-leg line of sight, r_sat(t_R - tau_d) - r_stn(t_R), in the
station's ENU frame at t_R; azimuth from north through east in [0, 2 pi), elevation from the horizon.  Diurnal
aberration (|v_stn| / c <= 1.6e-6 rad, 0.3") is left out.  The light time shows: a geostationary satellite
appears shifted west by omega tau_d r / rho, 1.0e-5 rad (2"), the arc it turned through during the down leg.
Residuals of azimuth must be wrapped to (-pi, pi] by the filter.

The GNSS-in-GEO fix is the ECI position itself (a receiver's ECEF solution turned by the loop's Earth angle),
each component with the same sigma.

Noise and bias enter as ``observed``: z = h(x) + bias + sigma * N(0, 1), the bias a constant drawn per sample
(per station and measurement type), sigma the white noise per component.  ``jacobian`` is d h / d x_eci by
``jax.jacfwd``.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp

from geojax.navigation.stations import Station, station_eci_m, to_enu
from geojax.physics.constants import C_MPS, MU_EARTH_M3_S2, OMEGA_EARTH_RAD_S
from geojax.physics.frames import eci_to_ecef
from geojax.physics.trig import atan2

LIGHT_TIME_ITERATIONS = 3


def two_way_range_m(x_eci, station: Station, earth_angle_rad):
    """Two-way range c (tau_d + tau_u) / 2 (m), [1]: station to satellite and back, received at t_R."""
    tau_down_s, tau_up_s = light_times_s(x_eci, station, earth_angle_rad)
    return (0.5 * C_MPS * (tau_down_s + tau_up_s))[None]


def range_rate_mps(x_eci, station: Station, earth_angle_rad):
    """Instantaneous two-way range rate (m/s), [1]: d/dt_R of ``two_way_range_m``."""

    def at(dt_s):
        return two_way_range_m(_satellite_after(x_eci, dt_s), station, earth_angle_rad + OMEGA_EARTH_RAD_S * dt_s)

    return jax.jvp(at, (jnp.zeros_like(x_eci[0]),), (jnp.ones_like(x_eci[0]),))[1]


def azimuth_elevation_rad(x_eci, station: Station, earth_angle_rad):
    """Azimuth (from north through east, [0, 2 pi)) and elevation of the down-leg line of sight (rad), [2]."""
    east, north, up = _line_of_sight_enu_m(x_eci, station, earth_angle_rad)
    azimuth = jnp.mod(atan2(east, north), 2.0 * jnp.pi)
    return jnp.stack([azimuth, atan2(up, jnp.sqrt(east**2 + north**2))])


def gnss_position_m(x_eci, station: Station, earth_angle_rad):
    """GNSS-in-GEO position fix (m), [3]: the ECI position (``station`` and ``earth_angle_rad`` unused)."""
    del station, earth_angle_rad
    return x_eci[:3]


class Model(NamedTuple):
    """One measurement type: its function ``h(x_eci, station, earth_angle_rad) -> [size]``, its size and unit."""

    h: Callable
    size: int
    unit: str


MODELS = {
    "range": Model(two_way_range_m, 1, "m"),
    "range_rate": Model(range_rate_mps, 1, "m/s"),
    "angles": Model(azimuth_elevation_rad, 2, "rad"),
    "gnss": Model(gnss_position_m, 3, "m"),
}


def elevation_visible(x_eci, station: Station, earth_angle_rad, mask_rad):
    """1.0 where the satellite is at or above the station's elevation mask (rad), else 0.0 (a weight, no branch)."""
    elevation = azimuth_elevation_rad(x_eci, station, earth_angle_rad)[1]
    return jnp.where(elevation >= mask_rad, 1.0, 0.0)


def jacobian(h: Callable, x_eci, station: Station, earth_angle_rad):
    """d h / d x_eci [size, 6] by forward-mode differentiation (six tangents)."""
    return jax.jacfwd(h)(x_eci, station, earth_angle_rad)


def observed(h: Callable, x_eci, station: Station, earth_angle_rad, sigma, bias, key):
    """A noisy measurement [size]: h(x) + bias + sigma * N(0, 1); ``sigma`` and ``bias`` in h's unit, scalars
    or [size]."""
    value = h(x_eci, station, earth_angle_rad)
    return value + bias + sigma * jax.random.normal(key, value.shape, value.dtype)


def light_times_s(x_eci, station: Station, earth_angle_rad):
    """Down-leg and up-leg light times (s) of a two-way measurement received at t_R (module docstring)."""
    tau_down_s, r_bounce_m, _ = _down_leg(x_eci, station, earth_angle_rad)
    tau_up_s = tau_down_s
    for _ in range(LIGHT_TIME_ITERATIONS):
        r_station_tx = station_eci_m(station, earth_angle_rad - OMEGA_EARTH_RAD_S * (tau_down_s + tau_up_s))
        tau_up_s = jnp.linalg.norm(r_bounce_m - r_station_tx) / C_MPS
    return tau_down_s, tau_up_s


def _down_leg(x_eci, station: Station, earth_angle_rad):
    """The down leg's light time (s), the satellite's ECI position when the signal left it and the station's at
    reception (m)."""
    r_station_rx = station_eci_m(station, earth_angle_rad)
    tau_down_s = jnp.linalg.norm(x_eci[:3] - r_station_rx) / C_MPS
    for _ in range(LIGHT_TIME_ITERATIONS):
        tau_down_s = jnp.linalg.norm(_satellite_after(x_eci, -tau_down_s)[:3] - r_station_rx) / C_MPS
    return tau_down_s, _satellite_after(x_eci, -tau_down_s)[:3], r_station_rx


def _line_of_sight_enu_m(x_eci, station: Station, earth_angle_rad):
    """(east, north, up) of r_sat(t_R - tau_d) - r_stn(t_R), m."""
    _, r_bounce_m, r_station_rx = _down_leg(x_eci, station, earth_angle_rad)
    enu = to_enu(station, eci_to_ecef(r_bounce_m - r_station_rx, earth_angle_rad))
    return enu[0], enu[1], enu[2]


def _satellite_after(x_eci, dt_s):
    """The state [6] dt_s later by its Taylor series under point-mass gravity (second order in position)."""
    r, v = x_eci[:3], x_eci[3:]
    a = -MU_EARTH_M3_S2 * r / jnp.linalg.norm(r) ** 3
    return jnp.concatenate([r + v * dt_s + 0.5 * a * dt_s**2, v + a * dt_s])
