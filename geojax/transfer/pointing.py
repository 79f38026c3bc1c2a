"""Where the thrust can point: the body's bounded slew and the split of a wished direction between body and boom.

Directions are (azimuth from R towards S, elevation towards W) in the orbit frame RSW.  The body attitude
is modelled by its own azimuth and elevation offsets, each slewing under a rate and an acceleration bound
(the body's attitude control, eqs. (5)-(6) reduced to its limits); the boom adds its joint angles on top
(``boom.thrust_direction_body``: azimuth 90 deg + theta1, elevation theta3).  Adding the offsets is exact for
the azimuth and first order for the elevation (|theta3| <= 15 deg), a marked simplification.

The fixed quadrilateral layout is the same model with the joints frozen at (0, 90, 0) deg: its thrust is
along the body's S axis and the body does all the pointing.  So both layouts are one compiled program whose
joint limits are data.
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.physics.elements import wrap_angle


def slew_step(angle_rad, rate_rad_s, target_rad, rate_max_rad_s, accel_max_rad_s2, step_s):
    """One step of a rate- and acceleration-limited slew towards ``target_rad`` (the short way round): the
    rate heads for the fastest rate that can still stop at the target (sqrt(2 a |error|), capped by the rate
    bound and by reaching the target within the step), changing by at most a dt.  Returns (angle, rate)."""
    error = wrap_angle(target_rad - angle_rad)
    speed = jnp.minimum(jnp.minimum(jnp.sqrt(2 * accel_max_rad_s2 * jnp.abs(error)), rate_max_rad_s),
                        jnp.abs(error) / step_s)
    change = jnp.clip(jnp.sign(error) * speed - rate_rad_s, -accel_max_rad_s2 * step_s, accel_max_rad_s2 * step_s)
    rate = rate_rad_s + change
    return angle_rad + 0.5 * (rate_rad_s + rate) * step_s, rate


def body_share_rad(wished_rad, joint_low_rad, joint_high_rad):
    """The body's part of a wished angle: what the joint range [low, high] cannot reach (0 inside it)."""
    wished = wrap_angle(wished_rad)
    return wrap_angle(wished - jnp.clip(wished, joint_low_rad, joint_high_rad))


def misalignment_rad(direction_a, direction_b):
    """Angle between two unit vectors [3]; atan2 of cross and dot, accurate near zero."""
    return jnp.arctan2(jnp.linalg.norm(jnp.cross(direction_a, direction_b)), jnp.dot(direction_a, direction_b))
