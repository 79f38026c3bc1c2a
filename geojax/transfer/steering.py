"""GTO-GEO steering: the thrust control angles of Ma & Kong 2023, eq. (1), their two phases and the firing rule.

Reading of eq. (1) (a marked choice; the printed formula has lost its e, which the text still names):

* alpha, the in-plane angle from the radial direction to the thrust (radial positive, eq. (1) and Fig. 2),
  is the velocity direction: tan alpha = (1 + e cos nu) / (e sin nu).  At e = 1 this is the printed
  arctan[-2 cot(nu/2) (1 - sin^2(nu/2)) / (1 + cos nu)] = arctan(-cot(nu/2)) up to the sign convention
  (the parabola's flight-path angle is nu/2), and it is the text's "accelerated along the orbital velocity
  direction".  Perigee and apogee both give alpha = 90 deg (thrust along S).
* beta = -(pi/2) sin(u + pi/2) = -(pi/2) cos u, u the argument of latitude: out-of-plane thrust against the
  orbit normal at the ascending node and along it at the descending node, which lowers the inclination
  (di/dt is proportional to cos u times the normal acceleration).
* The firing rule (the paper gives none; its text: "accelerated along the orbital velocity direction at
  the apogee").  A burn dv along the velocity at true anomaly nu changes the apsis radii by
  d r_a / dv = (2a/v) [(1 + e)(2a/r - 1) + e + cos nu] and d r_p / dv = (2a/v) [(1 - e)(2a/r - 1) - e - cos nu]
  (from da = 2 a^2 v dv / mu and de = 2 (e + cos nu) dv / v); at apogee only the perigee moves, at perigee
  only the apogee.  With the apsis shortfalls E_p = r_GEO - r_p and E_a = r_GEO - r_a, the gain
  G(nu) = E_p d r_p/dv + E_a d r_a/dv is the rate at which a forward burn closes the orbit on GEO (a
  Lyapunov rate of E_p^2 + E_a^2).  The thrust is forward where G > 0, backward where G < 0 ("backward
  thrust allowed"), and fires only where |G| is at least ``efficiency`` times its largest value over the
  orbit (sampled at 36 anomalies): burns gather at the apogee while the perigee is low, and at the perigee
  when the apogee is high.  An orbit whose apsides are both within ``deadband`` of GEO stops firing unless
  the plane change still needs thrust.
* The phases: while the inclination is above half the end threshold (the plane change) the thruster fires
  all orbit long (outside the shadow) with eq. (1)'s beta; below it (the circularisation) it fires by the
  rule above, and beta is eq. (1)'s scaled by i / i_end, so the burns keep holding the inclination against
  the lunisolar drift (about 0.002 deg/day) without switching back to the plane change (a switch that
  chatters at the threshold and makes the transfer time depend on the step).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.physics.trig import atan


class OrbitGeometry(NamedTuple):
    """Osculating quantities of a MEE state that the guidance reads (rad, m)."""

    e: jnp.ndarray
    i_rad: jnp.ndarray
    true_anomaly_rad: jnp.ndarray
    arg_latitude_rad: jnp.ndarray
    a_m: jnp.ndarray
    perigee_m: jnp.ndarray
    apogee_m: jnp.ndarray


def orbit_geometry(mee) -> OrbitGeometry:
    """From MEE [6] (p in m): e = |(f, g)|, i = 2 atan |(h, k)|, nu = L - atan2(g, f), u = L - atan2(k, h)."""
    p, f, g, h, k, true_lon = (mee[j] for j in range(6))
    e = jnp.hypot(f, g)
    a = p / (1 - e**2)
    return OrbitGeometry(e, 2 * atan(jnp.hypot(h, k)), true_lon - jnp.arctan2(g, f),
                         true_lon - jnp.arctan2(k, h), a, a * (1 - e), a * (1 + e))


def alpha_rad(e, true_anomaly_rad):
    """Eq. (1), alpha with e restored: the angle from the radial direction to the velocity, in (0, pi)."""
    return jnp.arctan2(1 + e * jnp.cos(true_anomaly_rad), e * jnp.sin(true_anomaly_rad))


def beta_rad(arg_latitude_rad):
    """Eq. (1): beta = -(pi/2) sin(u + pi/2)."""
    return -0.5 * jnp.pi * jnp.sin(arg_latitude_rad + 0.5 * jnp.pi)


class Command(NamedTuple):
    """The guidance's wish for one step: thrust azimuth from R towards S and elevation towards W (rad), and
    whether the firing rule fires (0 or 1)."""

    azimuth_rad: jnp.ndarray
    elevation_rad: jnp.ndarray
    fire: jnp.ndarray


def apsis_gain(geometry: OrbitGeometry, r_geo_m, true_anomaly_rad, mu):
    """G(nu) of the module docstring (m per m/s of forward burn, times the shortfalls in m), at any anomalies."""
    e, a = geometry.e, geometry.a_m
    r = a * (1 - e**2) / (1 + e * jnp.cos(true_anomaly_rad))
    speed = jnp.sqrt(mu * (2 / r - 1 / a))
    energy_term = 2 * a / r - 1
    d_apogee = (2 * a / speed) * ((1 + e) * energy_term + e + jnp.cos(true_anomaly_rad))
    d_perigee = (2 * a / speed) * ((1 - e) * energy_term - e - jnp.cos(true_anomaly_rad))
    return (r_geo_m - geometry.perigee_m) * d_perigee + (r_geo_m - geometry.apogee_m) * d_apogee


def steer(geometry: OrbitGeometry, r_geo_m, deadband_m, i_end_rad, efficiency, mu) -> Command:
    """The two-phase law (module docstring): eq. (1)'s angles, the plane-change switch and the firing rule."""
    gain = apsis_gain(geometry, r_geo_m, geometry.true_anomaly_rad, mu)
    best = jnp.max(jnp.abs(apsis_gain(geometry, r_geo_m, jnp.linspace(0.0, 2 * jnp.pi, 36, endpoint=False), mu)))
    apsides_off = jnp.maximum(jnp.abs(r_geo_m - geometry.perigee_m), jnp.abs(r_geo_m - geometry.apogee_m))
    plane_change = geometry.i_rad > 0.5 * i_end_rad
    in_plane = (jnp.abs(gain) >= efficiency * best) & (apsides_off > deadband_m)
    fire = (in_plane | plane_change).astype(float)
    alpha = alpha_rad(geometry.e, geometry.true_anomaly_rad) + jnp.where(gain >= 0, 0.0, jnp.pi)
    beta = beta_rad(geometry.arg_latitude_rad) * jnp.clip(geometry.i_rad / i_end_rad, 0.0, 1.0)
    return Command(alpha, beta, fire)


def direction_rsw(azimuth_rad, elevation_rad):
    """Unit vector [3] in RSW at an azimuth from R towards S and an elevation towards W."""
    ce = jnp.cos(elevation_rad)
    return jnp.stack([ce * jnp.cos(azimuth_rad), ce * jnp.sin(azimuth_rad), jnp.sin(elevation_rad)])
