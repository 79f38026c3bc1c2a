"""Where the thrust can point: the body's bounded slew, the boom's torque on it, and the split of a wished
direction between body and boom.

Directions are (azimuth from R towards S, elevation towards W) in the orbit frame RSW.  The body attitude
is modelled by its own azimuth and elevation offsets, each slewing under a rate and an acceleration bound
(the body's attitude control, eqs. (5)-(6) reduced to its limits); the boom adds its joint angles on top
(``boom.thrust_direction_body``: azimuth 90 deg + theta1, elevation theta3).  Adding the offsets is exact for
the azimuth and first order for the elevation (|theta3| <= 15 deg), a marked simplification.

The boom's coupling torque, eq. (8), acts on the body.  Eq. (6) adds tau_thrust,b to the attitude control's
torque tau_c (the printed equation puts the torques inside the gyroscopic cross product with the momenta,
which is dimensionally a typo: we read J_body d(omega)/dt = -omega x (J_body omega + h_f) + tau_d + tau_c +
tau_thrust,b).  At the slew rates here (<= 0.2 deg/s) the gyroscopic term is second order in the rates (and
zero for an isotropic J_body), so each slew axis k obeys d(omega_k)/dt = tau_c,k / J_k + delta_k with
delta = J_body^-1 tau_thrust,b projected on the axis.  The wheels' torque is bounded, |tau_c,k| / J_k <= a
(the slew acceleration bound), so the body's achievable angular acceleration is the window
[-a + delta_k, a + delta_k]: the torque takes away acceleration against it and adds it along it, and
where |delta_k| > a the wheels cannot hold the body, which is driven off its pointing (the thruster then
stops at the misalignment gate, and the torque with it).  The attitude loop knows the torque (it follows
from the joint angles and the commanded thrust, eq. (8)), so it plans its slew with the shifted window
(``slew_step``).  The slew axes are the body z axis (the azimuth) and the horizontal axis perpendicular to
the thrust, (cos theta1, sin theta1, 0) in the body frame (the elevation: a rotation about it lifts the
thrust towards W); the torque's component about the thrust's own in-plane direction does not move the
thrust, so the wheels absorb it without a pointing cost.  Not modelled: the wheels' momentum (the torque's
impulse, which a real spacecraft dumps; ``rollout.Stats.torque_impulse_nms`` reports it) and the reaction
of the joints' own accelerations (link inertias are not given).

The fixed quadrilateral layout is the same model with the joints frozen at (0, 90, 0) deg: its thrust is
along the body's S axis and the body does all the pointing; with no boom arm its eq. (8) torque is zero.  So
both layouts are one compiled program whose joint limits are data.
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.physics.elements import wrap_angle


def slew_step(angle_rad, rate_rad_s, target_rad, rate_max_rad_s, accel_max_rad_s2, step_s, disturbance_rad_s2=0.0):
    """One step of a rate- and acceleration-limited slew towards ``target_rad`` (the short way round) under a
    disturbing angular acceleration ``disturbance_rad_s2`` (delta, torque / inertia) held over the step.

    The achievable acceleration is [-a + delta, a + delta] (module docstring).  Moving towards the target
    (sign s), the body can brake at b = a - s delta.  The new rate w' is the fastest (up to the rate bound, and
    within the window times dt of the old rate w) that can still stop at the target: the angle covered in the
    step, (w + w') dt / 2, plus the stopping distance w'^2 / 2b must not exceed the error e, so
    w' <= b (sqrt(dt^2/4 + (2 e - w dt) / b) - dt/2).  Where b <= 0 (the torque beats the wheels) nothing can
    stop the body and w' = 0 is wished; the window decides what happens.  Returns (angle, rate).
    """
    error = wrap_angle(target_rad - angle_rad)
    toward = jnp.sign(error)
    a, dt = accel_max_rad_s2, step_s
    brake = jnp.maximum(a - toward * disturbance_rad_s2, 1e-30)
    stoppable = brake * (jnp.sqrt(jnp.maximum(dt * dt / 4 + (2 * jnp.abs(error) - toward * rate_rad_s * dt) / brake,
                                              0.0)) - dt / 2)
    wanted = toward * jnp.minimum(stoppable, rate_max_rad_s)
    rate = rate_rad_s + jnp.clip(wanted - rate_rad_s, (disturbance_rad_s2 - a) * dt, (disturbance_rad_s2 + a) * dt)
    return angle_rad + 0.5 * (rate_rad_s + rate) * dt, rate


def slew_disturbance_rad_s2(torque_body_nm, theta1_rad, inertia_kg_m2):
    """The angular acceleration [2] that a body-frame torque [3] (N m) gives the body's (azimuth, elevation)
    slew axes: J_body^-1 tau (principal moments ``inertia_kg_m2`` [3] along the body axes) projected on the
    body z axis and on (cos theta1, sin theta1, 0), the axis that lifts a thrust at azimuth 90 deg + theta1."""
    accel = torque_body_nm / inertia_kg_m2
    elevation_axis = jnp.stack([jnp.cos(theta1_rad), jnp.sin(theta1_rad), jnp.zeros_like(theta1_rad)])
    return jnp.stack([accel[2], accel @ elevation_axis])


def body_share_rad(wished_rad, joint_low_rad, joint_high_rad):
    """The body's part of a wished angle: what the joint range [low, high] cannot reach (0 inside it)."""
    wished = wrap_angle(wished_rad)
    return wrap_angle(wished - jnp.clip(wished, joint_low_rad, joint_high_rad))


def misalignment_rad(direction_a, direction_b):
    """Angle between two unit vectors [3]; atan2 of cross and dot, accurate near zero."""
    return jnp.arctan2(jnp.linalg.norm(jnp.cross(direction_a, direction_b)), jnp.dot(direction_a, direction_b))
