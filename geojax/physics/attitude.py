"""The attitude of a nadir-pointing body and the external torques on it (SI units, ECI unless a name says body).

The body frame of a nadir-pointing spacecraft (the attitude its inner loop holds; Caverly, Di Cairano & Weiss
2021 neglect the attitude errors at the station-keeping time scale, and so does geojax): z toward the Earth's
centre (nadir), y along the orbit's negative normal, x = y x z (along the velocity on a circular orbit)::

    z_b = -r / |r|,   y_b = -(r x v) / |r x v|,   x_b = y_b x z_b.

It turns with the orbit: its rate is ``n = |r x v| / |r|^2`` about the orbit normal, omega_b = (0, -n, 0) in body
axes.  The Sun-tracking solar array turns about the orbit normal once a day; its frame (``array_frame``) is its
axis (the orbit normal, +(r x v)), the direction across it in its plane, and its normal (the Sun's direction
projected onto the orbit plane), so that a centre-of-pressure offset is given "along the array axis, one across
it".

The torques are pure functions of the state the orbit already has: solar radiation pressure acting at a centre
of pressure offset from the centre of mass (``srp_force_eci_n``: the orbit's own SRP model,
``physics.forces.srp_xyz`` with its shadow, times the mass; one model of SRP, not two) and the gravity gradient
of an inertia tensor (``gravity_gradient_torque_body``).  ``geojax.states.momentum`` integrates the wheels'
momentum from them.
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.physics.forces import Environment, ForceModel, srp_xyz, sunlit_fraction_xyz


def nadir_frame(r_eci_m, v_eci_mps):
    """Rows x_b, y_b, z_b [3, 3] of the nadir-pointing body frame in ECI (the ECI -> body rotation matrix)."""
    z = -r_eci_m / jnp.linalg.norm(r_eci_m)
    h = jnp.cross(r_eci_m, v_eci_mps)
    y = -h / jnp.linalg.norm(h)
    return jnp.stack([jnp.cross(y, z), y, z])


def body_rate_rad_s(r_eci_m, v_eci_mps):
    """omega_b [3]: the nadir-pointing body's angular velocity in body axes, (0, -n, 0), n = |r x v| / |r|^2
    (the orbit's instantaneous angular rate; the normal turns too on a perturbed orbit, by parts in 1e7 of n at
    GEO, left out)."""
    n = jnp.linalg.norm(jnp.cross(r_eci_m, v_eci_mps)) / jnp.sum(r_eci_m * r_eci_m)
    return jnp.stack([jnp.zeros_like(n), -n, jnp.zeros_like(n)])


def array_frame(r_eci_m, v_eci_mps, r_sun_eci_m):
    """Rows [3, 3] of the Sun-tracking solar array's frame in ECI: its axis (the orbit normal, (r x v) / |r x v|),
    the direction across it in the array's plane (axis x normal) and its normal (the direction from the
    spacecraft to the Sun projected onto the orbit plane)."""
    h = jnp.cross(r_eci_m, v_eci_mps)
    axis = h / jnp.linalg.norm(h)
    sun = r_sun_eci_m - r_eci_m
    in_plane = sun - jnp.dot(sun, axis) * axis
    normal = in_plane / jnp.linalg.norm(in_plane)
    return jnp.stack([axis, jnp.cross(axis, normal), normal])


def srp_force_eci_n(r_eci_m, env: Environment, fm: ForceModel):
    """[3] the solar radiation pressure force on the spacecraft (N): ``forces.srp_xyz`` (Li 2022 eq. (4)) per kg
    of mass times the mass, with the sunlit fraction of ``forces.sunlit_fraction_xyz`` and the switch
    ``fm.srp_on`` -- the force the orbit feels.  ``env``: one instant."""
    x, y, z = r_eci_m[0], r_eci_m[1], r_eci_m[2]
    light = sunlit_fraction_xyz(x, y, z, env, fm)
    return fm.srp_on * jnp.stack(srp_xyz(x, y, z, env.r_sun_eci_m, 1.0, fm, light))


def inertia_matrix(six_kg_m2):
    """The symmetric inertia tensor [3, 3] of (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) [6], kg m^2 (products of inertia as
    the tensor's off-diagonal entries, I_ij = -integral(x_i x_j dm))."""
    xx, yy, zz, xy, xz, yz = (six_kg_m2[k] for k in range(6))
    return jnp.stack([jnp.stack([xx, xy, xz]), jnp.stack([xy, yy, yz]), jnp.stack([xz, yz, zz])])


def gravity_gradient_torque_body(r_body_m, inertia_kg_m2, mu_m3_s2):
    """[3] the gravity-gradient torque in body axes, N m: 3 mu / |r|^5 (r_b x I r_b), ``r_body_m`` the position of
    the centre of mass in body axes, ``inertia_kg_m2`` [3, 3] (Wie, *Space Vehicle Dynamics and Control*, 2nd ed.,
    eq. (7.40); Hughes, *Spacecraft Attitude Dynamics*, Sec. 8.2)."""
    r2 = jnp.sum(r_body_m * r_body_m)
    return 3.0 * mu_m3_s2 / (r2 * r2 * jnp.sqrt(r2)) * jnp.cross(r_body_m, inertia_kg_m2 @ r_body_m)


def wheel_momentum_body_nms(h_total_eci_nms, eci_to_body, body_momentum_nms):
    """[3] the wheels' momentum h_w in body axes from the total angular momentum H (ECI) of body and wheels,
    H = I omega + h_w: h_w = C H - I omega (``eci_to_body`` C; ``body_momentum_nms`` I omega, body axes).  The one
    wheels' equation of the station-keeping loop (``states.momentum``) and of the transfer (``transfer.wheels``)."""
    return eci_to_body @ h_total_eci_nms - body_momentum_nms


def dumping_fraction(gain_per_s, firing_s):
    """The fraction 1 - exp(-k T) of the way to its target that a dumping law asking dh/dt = -k (h - target)
    goes over a firing time T, held as a zero-order hold (never more than all of it: stable at any gain)."""
    return -jnp.expm1(-gain_per_s * firing_s)
