"""Milankovitch-Lyapunov station-keeping feedback (Gurfil 2024, as written by Katz 2025, eqs. (1)-(4)).

The law acts on the Milankovitch elements (angular momentum h and eccentricity
vector e) of the satellite, in the Earth-fixed (ECEF) frame:

    u = -[k_h dh^T r~ + (k_e / mu) e^T (v~ r~ - h~)]^T                 (1)
      = -k_h (dh x r) - (k_e / mu) (r x (v x e) + h x e),
    dh = h - h_d,  h_d = (0, 0, R_d^2 omega),                          (2)-(3)
    R_d = R + k_lambda (lambda - lambda_d - lambda_b),                  (4)

with a~ the cross-product matrix (a~ b = a x b).  The first term is minus the
gradient, with respect to the velocity, of V_h = |dh|^2 / 2 (dh/dt = r x u, so
dV_h/dt = -k_h |dh x r|^2 for a fixed h_d); the second that of V_e = |e|^2 / 2
(mu de/dt = u x h + v x (r x u) = (v~ r~ - h~) u), so dV_e/dt =
-(k_e / mu^2) |r x (v x e) + h x e|^2.

Readings of the paper (Katz 2025 is terse; each choice is tested):

- **v** is written (x' - omega y, y' + omega x, z'): the ECEF velocity plus
  omega x r, i.e. the *inertial* velocity in ECEF axes.  So h = r x v and e are
  the inertial Milankovitch elements in ECEF axes; h_d = R_d^2 omega z (eq. 3)
  is indeed the inertial angular momentum of a synchronous circular orbit
  (with the ECEF-relative velocity h would be about zero).
- **Units** (the paper's, km and s, and SI here): k_h in 1/(km^2 s) =
  1e-6 1/(m^2 s); k_e in km^2/s^3 = 1e6 m^2/s^3 (both as the paper states and
  dimensionally consistent with eq. (1)).  k_lambda is printed as "km^2/rad",
  which cannot be: R_d in eq. (4) is a length, so k_lambda is in km/rad
  (= 1e3 m/rad); with 3200 km/rad and lambda - lambda_d - lambda_b ~ 1e-3 rad
  the desired radius moves by about 3 km, a drift of ~0.04 deg/day, the scale a
  longitude loop needs (3200 km^2/rad would move it by 4 cm).
- **lambda** is the geocentric sub-satellite longitude atan2(y, x) of the ECEF
  position; lambda - lambda_d - lambda_b is wrapped to [-pi, pi).

The law is a pure function of the ECEF state; time enters only through the
frame rotation, which the closed loop (``geojax.feedback``) applies.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.elements import wrap_angle

# Paper units to SI.
K_H_PAPER_TO_SI = 1e-6  # 1/(km^2 s) -> 1/(m^2 s)
K_E_PAPER_TO_SI = 1e6  # km^2/s^3 -> m^2/s^3
K_LAMBDA_PAPER_TO_SI = 1e3  # km/rad -> m/rad


class LyapunovGains(NamedTuple):
    """Gains of Katz 2025, eqs. (1)-(4), SI units (array leaves: differentiable, sweepable)."""

    k_h_per_m2_s: jnp.ndarray  # > 0
    k_e_m2_per_s3: jnp.ndarray  # > 0
    k_lambda_m_per_rad: jnp.ndarray  # > 0
    lambda_b_rad: jnp.ndarray  # station-dependent longitude bias, any sign


class Station(NamedTuple):
    """The slot the law holds: desired longitude lambda_d and the radius R of eq. (4)."""

    lon_rad: jnp.ndarray
    radius_m: jnp.ndarray
    omega_rad_s: jnp.ndarray
    mu_m3_s2: jnp.ndarray


def accel(gains: LyapunovGains, station: Station, r_ecef_m, v_ecef_mps):
    """Commanded acceleration [3] (m/s^2, ECEF axes) of eq. (1).

    ``r_ecef_m`` [3] is the ECEF position and ``v_ecef_mps`` [3] the inertial
    velocity in ECEF axes, (x' - omega y, y' + omega x, z').
    """
    mu = station.mu_m3_s2
    h, e = milankovitch(r_ecef_m, v_ecef_mps, mu)
    lon = jnp.arctan2(r_ecef_m[1], r_ecef_m[0])
    radius_d = station.radius_m + gains.k_lambda_m_per_rad * wrap_angle(lon - station.lon_rad - gains.lambda_b_rad)
    h_d = jnp.stack([0.0, 0.0, radius_d**2 * station.omega_rad_s])
    dh = h - h_d
    return -gains.k_h_per_m2_s * jnp.cross(dh, r_ecef_m) - gains.k_e_m2_per_s3 / mu * (
        jnp.cross(r_ecef_m, jnp.cross(v_ecef_mps, e)) + jnp.cross(h, e)
    )


def lyapunov_terms(station: Station, r_ecef_m, v_ecef_mps, radius_d_m):
    """(|h - h_d|^2 / 2, |e|^2 / 2) for a fixed desired radius: the functions eq. (1) descends."""
    h, e = milankovitch(r_ecef_m, v_ecef_mps, station.mu_m3_s2)
    dh = h - jnp.stack([0.0, 0.0, radius_d_m**2 * station.omega_rad_s])
    return 0.5 * jnp.sum(dh**2), 0.5 * jnp.sum(e**2)


def milankovitch(r_m, v_mps, mu):
    """Angular momentum h = r x v (m^2/s) and eccentricity vector e = v x h / mu - r / |r| [3]."""
    h = jnp.cross(r_m, v_mps)
    return h, jnp.cross(v_mps, h) / mu - r_m / jnp.linalg.norm(r_m)
