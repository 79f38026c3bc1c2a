"""Orbital elements: Cartesian <-> Keplerian <-> modified equinoctial, GEO elements, cycle means.

Modified equinoctial elements (MEE) follow Li 2022, eq. (5) and Walker, Ireland
& Owens (1985): (p, f, g, h, k, L) with p in metres and L the true longitude in
radians, stacked on the last axis.  GEO elements follow Li 2022, eq. (8) and
Sec. 3.1: eccentricity vector (e_x, e_y) = (f, g), inclination vector
(i_x, i_y) = (h, k) = tan(i/2) (cos Omega, sin Omega).
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.physics.trig import atan, sincos, tan

P, F, G, H, K, L = range(6)


def kepler_to_cartesian(a_m, e, i_rad, raan_rad, argp_rad, true_anomaly_rad, mu):
    """Keplerian elements to ECI position and velocity [..., 3] (m, m/s)."""
    p = a_m * (1 - e**2)
    r = p / (1 + e * jnp.cos(true_anomaly_rad))
    perifocal_r = jnp.stack([r * jnp.cos(true_anomaly_rad), r * jnp.sin(true_anomaly_rad), jnp.zeros_like(r)], -1)
    speed = jnp.sqrt(mu / p)
    perifocal_v = jnp.stack(
        [-speed * jnp.sin(true_anomaly_rad), speed * (e + jnp.cos(true_anomaly_rad)), jnp.zeros_like(r)], -1
    )
    rotation = _perifocal_to_eci(i_rad, raan_rad, argp_rad)
    return jnp.einsum("...ij,...j->...i", rotation, perifocal_r), jnp.einsum("...ij,...j->...i", rotation, perifocal_v)


def _perifocal_to_eci(i, raan, argp):
    co, so, cw, sw, ci, si = jnp.cos(raan), jnp.sin(raan), jnp.cos(argp), jnp.sin(argp), jnp.cos(i), jnp.sin(i)
    return jnp.stack(
        [
            jnp.stack([co * cw - so * sw * ci, -co * sw - so * cw * ci, so * si], -1),
            jnp.stack([so * cw + co * sw * ci, -so * sw + co * cw * ci, -co * si], -1),
            jnp.stack([sw * si, cw * si, ci], -1),
        ],
        -2,
    )


def cartesian_to_kepler(r_eci, v_eci, mu):
    """ECI state to (a, e, i, raan, argp, true anomaly); singular for e = 0 or i = 0 (use MEE there)."""
    h = jnp.cross(r_eci, v_eci)
    r = jnp.linalg.norm(r_eci, axis=-1)
    e_vec = jnp.cross(v_eci, h) / mu - r_eci / r[..., None]
    e = jnp.linalg.norm(e_vec, axis=-1)
    h_norm = jnp.linalg.norm(h, axis=-1)
    i = jnp.arccos(h[..., 2] / h_norm)
    node = jnp.stack([-h[..., 1], h[..., 0], jnp.zeros_like(r)], -1)
    raan = jnp.mod(jnp.arctan2(node[..., 1], node[..., 0]), 2 * jnp.pi)
    node_hat = node / jnp.linalg.norm(node, axis=-1, keepdims=True)
    h_hat = h / h_norm[..., None]
    argp = jnp.mod(
        jnp.arctan2(jnp.sum(jnp.cross(node_hat, e_vec) * h_hat, -1), jnp.sum(node_hat * e_vec, -1)), 2 * jnp.pi
    )
    nu = jnp.mod(
        jnp.arctan2(jnp.sum(jnp.cross(e_vec, r_eci) * h_hat, -1), jnp.sum(e_vec * r_eci, -1) * 1.0), 2 * jnp.pi
    )
    a = h_norm**2 / mu / (1 - e**2)
    return a, e, i, raan, argp, nu


def kepler_to_mee(a_m, e, i_rad, raan_rad, argp_rad, true_anomaly_rad):
    """Li 2022, eq. (5)."""
    tan_half_i = tan(i_rad / 2)
    return jnp.stack(
        [
            a_m * (1 - e**2),
            e * jnp.cos(argp_rad + raan_rad),
            e * jnp.sin(argp_rad + raan_rad),
            tan_half_i * jnp.cos(raan_rad),
            tan_half_i * jnp.sin(raan_rad),
            raan_rad + argp_rad + true_anomaly_rad,
        ],
        -1,
    )


def mee_to_kepler(mee):
    """Inverse of eq. (5); angles in [0, 2 pi)."""
    p, f, g, h, k, true_lon = (mee[..., j] for j in range(6))
    e = jnp.hypot(f, g)
    i = 2 * atan(jnp.hypot(h, k))
    raan = jnp.mod(jnp.arctan2(k, h), 2 * jnp.pi)
    lon_peri = jnp.arctan2(g, f)
    argp = jnp.mod(lon_peri - raan, 2 * jnp.pi)
    nu = jnp.mod(true_lon - lon_peri, 2 * jnp.pi)
    return p / (1 - e**2), e, i, raan, argp, nu


def mee_rsw_rows(h, k, cos_l, sin_l):
    """Rows R, S, W of the RSW frame of a MEE state, each a tuple of its ECI components.

    R = r / |r|, W = the orbit normal, S = W x R (Walker, Ireland & Owens 1985):
    R = (cos L (1 + a2) + 2hk sin L, sin L (1 - a2) + 2hk cos L, 2 (h sin L - k cos L)) / s2,
    S = (-sin L (1 + a2) + 2hk cos L, cos L (1 - a2) - 2hk sin L, 2 (h cos L + k sin L)) / s2,
    W = (2k, -2h, 1 - h^2 - k^2) / s2, with a2 = h^2 - k^2 and s2 = 1 + h^2 + k^2.
    """
    hh, kk = h * h, k * k
    a2, hk2 = hh - kk, 2 * h * k
    inv_s2 = 1 / (1 + hh + kk)
    return (
        ((cos_l * (1 + a2) + hk2 * sin_l) * inv_s2, (sin_l * (1 - a2) + hk2 * cos_l) * inv_s2,
         2 * (h * sin_l - k * cos_l) * inv_s2),
        ((-sin_l * (1 + a2) + hk2 * cos_l) * inv_s2, (cos_l * (1 - a2) - hk2 * sin_l) * inv_s2,
         2 * (h * cos_l + k * sin_l) * inv_s2),
        (2 * k * inv_s2, -2 * h * inv_s2, (1 - hh - kk) * inv_s2),
    )


def mee_to_cartesian(mee, mu):
    """MEE [..., 6] to ECI position and velocity [..., 3].

    r = (p / w) R and v = sqrt(mu / p) ((f sin L - g cos L) R + w S) in the RSW
    basis of ``mee_rsw_rows``.
    """
    r_xyz, v_xyz = mee_to_rv_xyz(*(mee[..., j] for j in range(6)), mu)
    return jnp.stack(jnp.broadcast_arrays(*r_xyz), -1), jnp.stack(jnp.broadcast_arrays(*v_xyz), -1)


def mee_to_rv_xyz(p, f, g, h, k, true_lon, mu):
    """``mee_to_cartesian`` on components: ((x, y, z), (vx, vy, vz))."""
    cos_l, sin_l = sincos(true_lon)
    w = 1 + f * cos_l + g * sin_l
    rows = mee_rsw_rows(h, k, cos_l, sin_l)
    speed = jnp.sqrt(mu / p)
    r, v_r, v_s = p / w, speed * (f * sin_l - g * cos_l), speed * w
    return (tuple(r * c for c in rows[0]),
            tuple(v_r * c_r + v_s * c_s for c_r, c_s in zip(rows[0], rows[1], strict=True)))


def cartesian_to_mee(r_eci, v_eci, mu):
    """ECI position and velocity to MEE [..., 6]; prograde orbits (i < 180 deg)."""
    h_vec = jnp.cross(r_eci, v_eci)
    h_norm = jnp.linalg.norm(h_vec, axis=-1)
    h_hat = h_vec / h_norm[..., None]
    p = h_norm**2 / mu
    h = -h_hat[..., 1] / (1 + h_hat[..., 2])
    k = h_hat[..., 0] / (1 + h_hat[..., 2])
    s2 = 1 + h**2 + k**2
    f_hat = jnp.stack([1 - k**2 + h**2, 2 * h * k, -2 * k], -1) / s2[..., None]
    g_hat = jnp.stack([2 * h * k, 1 + k**2 - h**2, 2 * h], -1) / s2[..., None]
    r = jnp.linalg.norm(r_eci, axis=-1)
    e_vec = jnp.cross(v_eci, h_vec) / mu - r_eci / r[..., None]
    f = jnp.sum(e_vec * f_hat, -1)
    g = jnp.sum(e_vec * g_hat, -1)
    true_lon = jnp.arctan2(jnp.sum(r_eci * g_hat, -1), jnp.sum(r_eci * f_hat, -1))
    return jnp.stack([p, f, g, h, k, true_lon], -1)


def semi_major_axis_m(mee):
    """a = p / (1 - f^2 - g^2)."""
    return mee[..., P] / (1 - mee[..., F] ** 2 - mee[..., G] ** 2)


def wrap_angle(angle_rad):
    """Angle wrapped to [-pi, pi)."""
    return jnp.mod(angle_rad + jnp.pi, 2 * jnp.pi) - jnp.pi


def cycle_mean(samples):
    """One-cycle mean (Li 2022, eq. (9)) of samples taken at equal steps over one cycle.

    ``samples`` is [n + 1, ...] with both ends of the cycle included.  The
    trapezoid rule is exact for the secular drift and converges exponentially
    for the periodic part, so this is the averaging operator of eq. (9) to
    round-off at any reasonable step.
    """
    inner = jnp.sum(samples[1:-1], axis=0)
    return (inner + 0.5 * (samples[0] + samples[-1])) / (samples.shape[0] - 1)
