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

The quadrilateral layout (``quadrilateral``) is the same model with the joints frozen at (0, 90, 0) deg: its
strong pairs' axis is the body's S axis, the body does all the pointing (towards the wish or against it,
whichever is the nearer slew, ``body_target_rad``), and with no boom arm its eq. (8) torque is zero.  So both
layouts are one compiled program whose joint limits and pair efficiencies are data.

Attitude-control propellant (a stated model; the paper names "unnecessary fuel consumption for attitude
adjustment" without one).  The slews are made by attitude thrusters (a couple of arm L, specific impulse
Isp_rcs): every change of the body's slew rate takes the torque J_k d(omega_k)/dt on its axis, less the part
of eq. (8)'s push that the wheels could not hold and that moved the body by itself (``slew_torque_nm``), and
a torque |tau| held for dt burns |tau| dt / (L Isp_rcs g0) of propellant, whatever the couple's split (two
thrusters of f at arm L: torque 2 f L, flow 2 f / (Isp g0)).  A rest-to-rest slew at rate w on inertia J costs
2 J w / (L Isp_rcs g0): J w to start and J w to stop (``attitude_propellant_kg``).  Wheels that made the slews
would store that momentum and give it back, so this is the cost of slewing with thrusters, the reading under
which the paper's attitude fuel exists.  The wheels hold the boom's eq. (8) torque within their window (not
counted), its push beyond the window moves the body by itself (not counted), and the slews that bring the body
back are counted; ``run.metrics`` also reports what thrusters would burn holding eq. (8) instead of the wheels
(its impulse at the same arm and Isp), a bound on its momentum dumping.  The propellant is booked, not flown:
it is left out of the orbit's mass.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from geojax.physics.constants import G0_MPS2
from geojax.physics.elements import wrap_angle

# The attitude loop's step (s): a dt at the scenarios' slew acceleration (0.001 deg/s^2) is 0.01 deg/s, a tenth of
# their rate bound (0.1 deg/s); at 120 s it would exceed it (slew_over_step).
ATTITUDE_STEP_S = 10.0


def slew_step(angle_rad, rate_rad_s, target_rad, rate_max_rad_s, accel_max_rad_s2, step_s, disturbance_rad_s2=0.0,
              target_rate_rad_s=0.0):
    """One step of a rate- and acceleration-limited slew towards ``target_rad`` (the short way round), which
    moves at ``target_rate_rad_s``, under a disturbing angular acceleration ``disturbance_rad_s2`` (delta,
    torque / inertia) held over the step.

    The achievable acceleration is [-a + delta, a + delta] (module docstring).  In the target's frame (error e,
    moving towards it with sign s), the body can brake at b = a - s delta.  The wished relative rate is the
    discrete braking curve far from the target: the fastest r' from which steps braking at b still stop on the
    target, the angle of this step (r + r') dt / 2 plus the stopping distance r'^2 / 2b within |e|, so
    r' <= b (sqrt(dt^2/4 + (2 |e| - r dt) / b) - dt/2); and |e| / (3 dt) near it: the discrete loop
    e' = e - (r + r') dt / 2 with r' = e / (3 dt) has the real roots 1/2 and 1/3, so it settles without
    overshoot or limit cycle (a law that plans to land exactly
    each step swings its rate across zero step after step).  Then v is added (the target's rate fed forward,
    so a body tracking a moving target does not stop at every step), the rate bound, and the window times dt
    about the old rate.  Where b <= 0 (the torque beats the wheels) nothing can stop the body; the window
    decides what happens.  Returns (angle, rate).
    """
    error = wrap_angle(target_rad - angle_rad)
    toward = jnp.sign(error)
    a, dt = accel_max_rad_s2, step_s
    brake = jnp.maximum(a - toward * disturbance_rad_s2, 1e-30)
    relative = rate_rad_s - target_rate_rad_s
    braking = brake * (jnp.sqrt(jnp.maximum(dt * dt / 4 + (2 * jnp.abs(error) - toward * relative * dt) / brake, 0.0))
                       - dt / 2)
    stoppable = jnp.minimum(braking, jnp.abs(error) / (3 * dt))
    wanted = jnp.clip(target_rate_rad_s + toward * stoppable, -rate_max_rad_s, rate_max_rad_s)
    rate = rate_rad_s + jnp.clip(wanted - rate_rad_s, (disturbance_rad_s2 - a) * dt, (disturbance_rad_s2 + a) * dt)
    return angle_rad + 0.5 * (rate_rad_s + rate) * dt, rate


def slew_over_step(angle_rad, rate_rad_s, target_rad, target_rate_rad_s, rate_max_rad_s, accel_max_rad_s2, step_s,
                   substeps: int, disturbance_rad_s2, slew_inertia):
    """The attitude loop over one integration step: ``substeps`` (static) steps of ``slew_step`` towards a target
    moving at ``target_rate_rad_s`` and reaching ``target_rad`` at the step's end, the disturbance held.  The
    attitude loop runs faster than the orbit's step: at 120 s, a dt (0.12 deg/s at 0.001 deg/s^2) exceeds the
    rate bound and a single discrete slew step falls into a period-2 limit cycle about a moving target (its rate
    swinging +-0.06 deg/s each step on the transfer's day 50, measured), whose rate swings the attitude
    propellant would count.  Returns (angle, rate, the slew torque's impulse [2] over the step, N m s)."""
    dt = step_s / substeps

    def sub(k, carry):
        angle, rate, impulse = carry
        target = target_rad - target_rate_rad_s * (substeps - k) * dt  # where it is as the sub-step starts
        new_angle, new_rate = slew_step(angle, rate, target, rate_max_rad_s, accel_max_rad_s2, dt, disturbance_rad_s2,
                                        target_rate_rad_s)
        torque = slew_torque_nm(rate, new_rate, dt, disturbance_rad_s2, accel_max_rad_s2, slew_inertia)
        return new_angle, new_rate, impulse + jnp.abs(torque) * dt

    return jax.lax.fori_loop(0, substeps, sub, (angle_rad, rate_rad_s, jnp.zeros_like(slew_inertia)))


def target_rate_rad_s(target_rad, previous_target_rad, rate_max_rad_s, step_s):
    """The rate a slew target moves at, for ``slew_step``'s feed-forward: its change over the step, or zero
    where it jumped further than the body could follow in a step (a flip of the wish is a new target, not a
    motion to track)."""
    change = wrap_angle(target_rad - previous_target_rad)
    return jnp.where(jnp.abs(change) <= rate_max_rad_s * step_s, change / step_s, 0.0)


def slew_disturbance_rad_s2(torque_body_nm, theta1_rad, inertia_kg_m2):
    """The angular acceleration [2] that a body-frame torque [3] (N m) gives the body's (azimuth, elevation)
    slew axes: J_body^-1 tau (principal moments ``inertia_kg_m2`` [3] along the body axes) projected on the
    body z axis and on (cos theta1, sin theta1, 0), the axis that lifts a thrust at azimuth 90 deg + theta1."""
    accel = torque_body_nm / inertia_kg_m2
    elevation_axis = jnp.stack([jnp.cos(theta1_rad), jnp.sin(theta1_rad), jnp.zeros_like(theta1_rad)])
    return jnp.stack([accel[2], accel @ elevation_axis])


def body_share_rad(wished_rad, joint_low_rad, joint_high_rad):
    """Ma 2023, Remark 2: the joints first, within their ranges; the body's part of a wished angle is what the
    joint range [low, high] cannot reach (0 inside it)."""
    wished = wrap_angle(wished_rad)
    return wrap_angle(wished - jnp.clip(wished, joint_low_rad, joint_high_rad))


def joint_share_rad(wished_rad, body_rad, joint_low_rad, joint_high_rad):
    """Ma 2023, Remark 2: what the body reached leaves of the wish, for the joints, clipped to their ranges
    (when the body lags its share the joints cover what they can of the lag, never beyond a stop)."""
    return jnp.clip(wrap_angle(wished_rad - body_rad), joint_low_rad, joint_high_rad)


def body_target_rad(wished_rad, body_rad, joint_low_rad, joint_high_rad, reversible):
    """Where the body slews: its share of the wish (``body_share_rad``) or, for a layout with a pair firing the
    other way (``reversible`` true: the quadrilateral's south pair), its share of the reversed wish (azimuth
    + pi, elevation negated), whichever is the nearer slew from ``body_rad`` (the larger of the two axes'
    angles: they slew together)."""
    ahead = body_share_rad(wished_rad, joint_low_rad, joint_high_rad)
    reverse = body_share_rad(jnp.stack([wished_rad[0] + jnp.pi, -wished_rad[1]]), joint_low_rad, joint_high_rad)
    distance = lambda target: jnp.max(jnp.abs(wrap_angle(target - body_rad)))  # noqa: E731
    return jnp.where(reversible & (distance(reverse) < distance(ahead)), reverse, ahead)


def slew_inertia_kg_m2(theta1_rad, inertia_kg_m2):
    """The inertia [2] about the (azimuth, elevation) slew axes (``slew_disturbance_rad_s2``'s axes): J_z, and
    J_x cos^2 theta1 + J_y sin^2 theta1 (principal moments ``inertia_kg_m2`` [3])."""
    c, s = jnp.cos(theta1_rad), jnp.sin(theta1_rad)
    return jnp.stack([inertia_kg_m2[2], inertia_kg_m2[0] * c * c + inertia_kg_m2[1] * s * s])


def slew_torque_nm(rate_before_rad_s, rate_after_rad_s, step_s, disturbance_rad_s2, accel_max_rad_s2, slew_inertia):
    """The attitude thrusters' slewing torque [2] (N m) over a step: J_k ((w'_k - w_k) / dt - push_k), where the
    push is the part of the disturbance delta_k that the wheels cannot hold (beyond +-a) and that drives the
    body by itself (module docstring); with no disturbance, J_k (w'_k - w_k) / dt."""
    push = disturbance_rad_s2 - jnp.clip(disturbance_rad_s2, -accel_max_rad_s2, accel_max_rad_s2)
    return slew_inertia * ((rate_after_rad_s - rate_before_rad_s) / step_s - push)


def attitude_propellant_kg(impulse_nms, arm_m, isp_s):
    """Propellant (kg) of attitude thrusters that deliver an angular impulse (the integral of |tau|, N m s)
    through a couple of arm ``arm_m`` at ``isp_s``: impulse / (L Isp g0) (module docstring)."""
    return impulse_nms / (arm_m * isp_s * G0_MPS2)


def misalignment_rad(direction_a, direction_b):
    """Angle between two unit vectors [3]; atan2 of cross and dot, accurate near zero."""
    return jnp.arctan2(jnp.linalg.norm(jnp.cross(direction_a, direction_b)), jnp.dot(direction_a, direction_b))
