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
    """One step of a rate- and acceleration-limited slew towards ``target_rad`` (the short way round).

    The new rate w' is the fastest (up to the rate bound, and within a dt of the old rate w) that can still
    stop at the target: the angle covered in the step, (w + w') dt / 2, plus the stopping distance w'^2 / 2a
    must not exceed the error e, so w' <= a (sqrt(dt^2/4 + (2 e - w dt) / a) - dt/2).  Returns (angle, rate).
    """
    error = wrap_angle(target_rad - angle_rad)
    toward = jnp.sign(error)
    a, dt = accel_max_rad_s2, step_s
    stoppable = a * (jnp.sqrt(jnp.maximum(dt * dt / 4 + (2 * jnp.abs(error) - toward * rate_rad_s * dt) / a, 0.0))
                     - dt / 2)
    wanted = toward * jnp.minimum(stoppable, rate_max_rad_s)
    rate = rate_rad_s + jnp.clip(wanted - rate_rad_s, -a * dt, a * dt)
    return angle_rad + 0.5 * (rate_rad_s + rate) * dt, rate


def body_share_rad(wished_rad, joint_low_rad, joint_high_rad):
    """The body's part of a wished angle: what the joint range [low, high] cannot reach (0 inside it)."""
    wished = wrap_angle(wished_rad)
    return wrap_angle(wished - jnp.clip(wished, joint_low_rad, joint_high_rad))


def misalignment_rad(direction_a, direction_b):
    """Angle between two unit vectors [3]; atan2 of cross and dot, accurate near zero."""
    return jnp.arctan2(jnp.linalg.norm(jnp.cross(direction_a, direction_b)), jnp.dot(direction_a, direction_b))
