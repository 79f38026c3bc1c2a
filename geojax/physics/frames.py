"""Reference frames: ECI (mean equator and equinox of the scenario epoch), ECEF, RSW.

ECEF is the ECI frame turned about its z axis by the Earth rotation angle; polar
motion and the pole's precession within a run are neglected (see
``geojax.physics.ephemeris`` for the ECI definition and the size of what is left out).
RSW is (radial, along-track, cross-track): R = r/|r|, W = (r x v)/|r x v|,
S = W x R (Li 2022, Fig. 1).
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.physics.ephemeris import general_precession_rad, mean_obliquity_rad
from geojax.physics.time import gmst_rad, julian_centuries_tt
from geojax.physics.trig import atan2


def earth_rotation_angle_rad(t_tt_s, frame_epoch_tt_s, tt_minus_ut1_s):
    """Angle from the ECI x axis to the Greenwich meridian, radians.

    GMST is measured from the mean equinox of date; the ECI x axis is the
    equinox of the frame epoch.  The precession of the equinox along the
    equator since the frame epoch (general precession times cos(obliquity),
    46"/yr) is subtracted so that longitudes are right to 1e-5 deg over a year.
    """
    t = julian_centuries_tt(t_tt_s)
    t0 = julian_centuries_tt(frame_epoch_tt_s)
    equinox_shift = (general_precession_rad(t) - general_precession_rad(t0)) * jnp.cos(mean_obliquity_rad(t0))
    return gmst_rad(t_tt_s, tt_minus_ut1_s) - equinox_shift


def rotate_z(vector, angle_rad):
    """Components of ``vector`` [..., 3] in a frame turned by ``angle_rad`` about z (passive rotation)."""
    c, s = jnp.cos(angle_rad), jnp.sin(angle_rad)
    x, y, z = vector[..., 0], vector[..., 1], vector[..., 2]
    return jnp.stack([c * x + s * y, -s * x + c * y, z], axis=-1)


def eci_to_ecef(r_eci, earth_angle_rad):
    """Position [..., 3] from ECI to ECEF."""
    return rotate_z(r_eci, earth_angle_rad)


def ecef_to_eci(r_ecef, earth_angle_rad):
    """Position [..., 3] from ECEF to ECI."""
    return rotate_z(r_ecef, -earth_angle_rad)


def rsw_basis(r_eci, v_eci):
    """Rows R, S, W [..., 3, 3] of the RSW frame from position and velocity."""
    r_hat = r_eci / jnp.linalg.norm(r_eci, axis=-1, keepdims=True)
    h = jnp.cross(r_eci, v_eci)
    w_hat = h / jnp.linalg.norm(h, axis=-1, keepdims=True)
    s_hat = jnp.cross(w_hat, r_hat)
    return jnp.stack([r_hat, s_hat, w_hat], axis=-2)


def eci_to_rsw(vector_eci, r_eci, v_eci):
    """Components [..., 3] of an ECI vector along R, S, W."""
    return jnp.einsum("...ij,...j->...i", rsw_basis(r_eci, v_eci), vector_eci)


def rsw_to_eci(vector_rsw, r_eci, v_eci):
    """ECI components [..., 3] of a vector given along R, S, W."""
    return jnp.einsum("...ji,...j->...i", rsw_basis(r_eci, v_eci), vector_rsw)


def rsw_to_eci_xyz(vector_rsw, r_eci, v_eci):
    """``rsw_to_eci`` on components: each argument a tuple (x, y, z) of arrays; returns a tuple."""
    (u_r, u_s, u_w), (x, y, z), (vx, vy, vz) = vector_rsw, r_eci, v_eci
    hx, hy, hz = y * vz - z * vy, z * vx - x * vz, x * vy - y * vx
    r, h = jnp.sqrt(x * x + y * y + z * z), jnp.sqrt(hx * hx + hy * hy + hz * hz)
    rx, ry, rz, wx, wy, wz = x / r, y / r, z / r, hx / h, hy / h, hz / h
    sx, sy, sz = wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx
    return u_r * rx + u_s * sx + u_w * wx, u_r * ry + u_s * sy + u_w * wy, u_r * rz + u_s * sz + u_w * wz


def subsatellite_lon_lat_rad(r_ecef):
    """Geocentric longitude and latitude (radians) of an ECEF position."""
    return subsatellite_lon_lat_xyz_rad(r_ecef[..., 0], r_ecef[..., 1], r_ecef[..., 2])


def subsatellite_lon_lat_xyz_rad(x, y, z):
    """``subsatellite_lon_lat_rad`` on components, with ``physics.trig.atan2`` (fdlibm in plain arithmetic,
    within 1 ulp of libm; XLA's CPU arctan2 runs one element at a time)."""
    lon, tan_lat = subsatellite_lon_tan_lat_xyz(x, y, z)
    return lon, latitude_rad(tan_lat)


def subsatellite_lon_tan_lat_xyz(x, y, z):
    """Geocentric longitude (radians) and the tangent of the latitude, z / sqrt(x^2 + y^2), of ECEF components.

    The loop records these at every step: the latitude is monotone in its tangent, so a cycle's extremes of
    latitude are ``latitude_rad`` of the extremes of the tangent, one arc tangent per cycle instead of one per
    step, and the same numbers (``atan2(z, rho)`` reduces to atan(|z| / rho) exactly as ``latitude_rad`` does).
    """
    return atan2(y, x), z / jnp.sqrt(x * x + y * y)


def latitude_rad(tan_lat):
    """The latitude of its tangent (``subsatellite_lon_tan_lat_xyz``), in [-pi/2, pi/2]."""
    return atan2(tan_lat, jnp.ones_like(tan_lat))
