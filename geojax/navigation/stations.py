"""Ground stations: geodetic coordinates on the WGS-84 ellipsoid, their topocentric (ENU) frame, and their
inertial position and velocity at the loop's Earth angle.

A station is fixed in ECEF; ECEF is ECI turned about z by the Earth rotation angle that the loop's environment
grid carries (``physics.propagate.environment_grid``, ``physics.frames.earth_rotation_angle_rad``), so a
station's ECI position at a step is ``frames.ecef_to_eci`` of its ECEF position at that step's angle.  Between
grid times (the light time of a signal, a fraction of a second) the angle advances at ``OMEGA_EARTH_RAD_S``:
the grid's rate differs from it by the equinox's precession, 1e-11 relative (tests/test_frames.py).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.physics.constants import WGS84_A_M, WGS84_F
from geojax.physics.frames import ecef_to_eci

WGS84_E2 = WGS84_F * (2.0 - WGS84_F)  # first eccentricity squared


class Station(NamedTuple):
    """A ground station (leaves may carry leading axes, e.g. [n_stations, ...], to vmap over stations)."""

    r_ecef_m: jnp.ndarray  # [3] position in ECEF, m
    enu_ecef: jnp.ndarray  # [3, 3] rows: the local east, north and up (the ellipsoid's normal) in ECEF


def station_from_geodetic(lat_rad, lon_rad, alt_m) -> Station:
    """The station at geodetic latitude and longitude (rad) and height above the WGS-84 ellipsoid (m).

    ECEF position: x = (N + h) cos(lat) cos(lon), y = (N + h) cos(lat) sin(lon), z = (N (1 - e^2) + h) sin(lat),
    with N = a / sqrt(1 - e^2 sin^2(lat)) the prime-vertical radius (NIMA TR8350.2, eq. 4-14).
    """
    cos_lat, sin_lat = jnp.cos(lat_rad), jnp.sin(lat_rad)
    cos_lon, sin_lon = jnp.cos(lon_rad), jnp.sin(lon_rad)
    n_m = WGS84_A_M / jnp.sqrt(1.0 - WGS84_E2 * sin_lat**2)
    r_ecef_m = jnp.stack([(n_m + alt_m) * cos_lat * cos_lon, (n_m + alt_m) * cos_lat * sin_lon,
                          (n_m * (1.0 - WGS84_E2) + alt_m) * sin_lat], axis=-1)
    zero = jnp.zeros_like(cos_lat * cos_lon)
    east = jnp.stack([-sin_lon + zero, cos_lon + zero, zero], axis=-1)
    north = jnp.stack([-sin_lat * cos_lon, -sin_lat * sin_lon, cos_lat + zero], axis=-1)
    up = jnp.stack([cos_lat * cos_lon, cos_lat * sin_lon, sin_lat + zero], axis=-1)
    return Station(r_ecef_m, jnp.stack([east, north, up], axis=-2))


def station_eci_m(station: Station, earth_angle_rad):
    """The station's ECI position [..., 3] (m) at the Earth angle ``earth_angle_rad``."""
    return ecef_to_eci(station.r_ecef_m, earth_angle_rad)


def to_enu(station: Station, vector_ecef):
    """Components (east, north, up) [..., 3] of an ECEF vector in the station's topocentric frame."""
    return jnp.einsum("...ij,...j->...i", station.enu_ecef, vector_ecef)
