"""The reaction wheels over a transfer: the momentum the boom's eq. (8) torque leaves in them, and its dumping.

Ma & Kong 2023 compute the boom's coupling torque (eq. (8)) and add it to the attitude dynamics (eq. (6)), but do
not follow the momentum it leaves: ``pointing`` books the slews' propellant and ``run.metrics`` the integral of
|eq. (8)| (``torque_impulse_nms``), a bound on what holding it by thrusters would burn.  This module carries
the wheels' momentum, so the transfer says what the wheels store, how often they must be unloaded and what that
costs, with attitude thrusters or with the boom itself.

Frames.  The body axes are R, S, W at zero attitude (``boom``); the body's azimuth and elevation offsets
(``rollout.Attitude.body_rad``) turn it by Rz(azimuth) then about the horizontal axis k = (cos theta1, sin theta1,
0) (body axes) by the elevation, the slew axes of ``pointing`` (``body_to_rsw``): that rotation takes the boom's
thrust direction ``boom.thrust_direction_body`` exactly onto the direction the rollout flies,
``steering.direction_rsw`` at the summed angles.  RSW -> ECI from the orbit's r and v (``rsw_to_eci``).

The equation.  The total angular momentum of body and wheels obeys dH/dt = tau_ext in ECI (Euler's law), and
H = I omega + h_w (``states.momentum`` derives the body-axis form).  Who supplies which torque is a stated model:
the attitude thrusters make the slews (``pointing``: their propellant is booked there), so the I omega of the
slew rates is theirs and leaves the wheels alone; the wheels hold the body against the external torques, the
boom's eq. (8) (tilted by the dumping below) and the gravity gradient of the body's principal moments
(``physics.attitude.gravity_gradient_torque_body``: zero for the shipped isotropic 2000 kg m^2), and turn the
body with the orbit frame (omega_orb = |r x v| / |r|^2 about W, 1.3e-3 rad/s at the GTO's perigee: 2.6 N m s on 2000 kg m^2).  So the
loop carries H_eci: H_0 = C_0 I omega_orb,0 (the wheels empty at the start), each step adds its torque impulse
(the step's torque held over it, in the axes of the step's start: the body turns up to 0.16 rad per 120 s step
at perigee, a first-order error in the direction of that step's impulse that averages over the orbit), and at
each step's start h_w = C^T H_eci - I omega_orb (C = ECI <- body; ``start``, then ``add``: one frame a step).  The part of eq. (8) that ``pointing`` lets
push the body off its pointing (where it beats the wheels' torque window) is counted here as stored too: the
wheels' momentum is the integral of the whole eq. (8) torque, an upper bound where the torque window is beaten
(``run.metrics``' ``torque_overpowered_days``).

Unloading.  (a) Attitude thrusters: when a wheel passes ``rcs_dump_fraction`` of its capacity at a step's start,
a thruster couple empties the wheels at once (H_eci -= C h_w); its propellant is |h_w| / (L Isp g0), the couple's
arm and specific impulse of ``pointing.attitude_propellant_kg``.  (b) The boom (``dump_angle_max_deg`` > 0, the
boom layout only): during a firing step the thrust line is tilted about the nozzle, u' = cos(delta) u + s, s
perpendicular to u, |s| = sin(delta) <= sin(delta_max).  The wrist sits at r = r_W0 + l_0 from the centre of mass
(eq. (8)'s lever), which the shipped mounting puts on the thrust line at the nominal pose (r = rho u, rho = r . u
= 0.5 m, the link d1; 0.74 m with a miss of 0.16 m at theta3 = 15 deg), so the tilt's torque is r x F s = rho F
(u x s) (plus a part along u from the miss, second order): any torque perpendicular to the line, up to about
|rho| F sin(delta_max).  The law asks the torque that takes the wheels'
momentum perpendicular to the line toward zero at the rate k_dump over the step's firing time T, as its exact
zero-order hold, tau* = -(1 - exp(-k_dump T)) h_perp / T (``states.momentum``'s law with the one-burn
allocation: the boom's line turns with the orbit frame, so every direction is reachable within an orbit), and
s = (tau* x u) / (rho F).  The joints fly that line: the angles that point the thrust along u' (``tilted_pose``,
the inverse of eq. (9) at theta2 = 90 deg), clipped to their ranges (Table 1: a tilt beyond joint 3's +-15 deg
stop is flown only up to it; the guidance often holds joint 3 at its stop near apogee, where the plane change
asks more elevation than it reaches).  The torque that enters the wheels is eq. (8) of that pose (its lever
moves with the joints), not the law's wish.  The cost is real: the thrust along the guidance's wish falls to cos(delta) and the
part across it perturbs the orbit; the guidance, which sees the orbit flown, makes it up (the paired transfer
without dumping measures the days and xenon).  The joints' MPC tracks the guidance's pose; the dumping offset is flown
on top of it within the step (the drive's 0.5 deg/s covers 60 deg in a 120 s step), a marked simplification.

Capacity: ``wheel_capacity_nms`` per wheel (a marked choice of the scenario); a wheel above it at a step's end
sets ``wheels_saturated`` (kept and reported, the transfer goes on: a real wheel would stop absorbing).  The
records and ``h_body_nms`` hold the momentum at a step's start, after its unloading.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.physics.attitude import dumping_fraction, gravity_gradient_torque_body, wheel_momentum_body_nms


class WheelParams(NamedTuple):
    """The wheels and their unloading; every leaf an array (SI), so a batch vmaps over any of them."""

    capacity_nms: jnp.ndarray  # per wheel
    rcs_dump_fraction: jnp.ndarray  # the attitude thrusters empty the wheels when one passes this of the capacity
    dump_angle_max_rad: jnp.ndarray  # the boom's tilt limit delta_max (0: no dumping by the boom)
    dump_gain_per_s: jnp.ndarray  # k_dump


class Wheels(NamedTuple):
    """The carried state and its running totals (frozen once the transfer is done)."""

    h_total_eci_nms: jnp.ndarray  # [3] H = I omega + h_w, ECI
    h_body_nms: jnp.ndarray  # [3] h_w at the latest step's start (after its unloading), body axes
    torque_eci_nms: jnp.ndarray  # [3] the integral of the external torques, ECI (what the wheels would hold undumped)
    max_abs_nms: jnp.ndarray  # [3] the largest |h_w| per wheel at the step starts so far (before unloading)
    rcs_dumped_nms: jnp.ndarray  # [] the momentum the attitude thrusters emptied
    rcs_dumps: jnp.ndarray  # [] how many times
    tilt_impulse_nms: jnp.ndarray  # [] the integral of |eq. (8) of the tilted pose - of the untilted|
    tilt_cross_mps: jnp.ndarray  # [] the Delta-V the tilts put across the line flown


def rodrigues(axis, angle_rad):
    """The rotation [3, 3] by ``angle_rad`` about the unit ``axis`` [3]."""
    k = axis
    cross = jnp.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return jnp.cos(angle_rad) * jnp.eye(3) + jnp.sin(angle_rad) * cross + (1.0 - jnp.cos(angle_rad)) * jnp.outer(k, k)


def body_to_rsw(body_rad, theta1_rad):
    """C_RSW<-body [3, 3]: Rz(azimuth offset) then the elevation offset about k = (cos theta1, sin theta1, 0)."""
    az, el = body_rad[0], body_rad[1]
    c, s = jnp.cos(az), jnp.sin(az)
    rz = jnp.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return rz @ rodrigues(jnp.stack([jnp.cos(theta1_rad), jnp.sin(theta1_rad), 0.0]), el)


def rsw_to_eci(r_eci_m, v_eci_mps):
    """C_ECI<-RSW [3, 3] (columns R, S, W) and the orbit frame's rate |r x v| / |r|^2 (rad/s, about W)."""
    h = jnp.cross(r_eci_m, v_eci_mps)
    radial = r_eci_m / jnp.linalg.norm(r_eci_m)
    normal = h / jnp.linalg.norm(h)
    return jnp.stack([radial, jnp.cross(normal, radial), normal], axis=1), jnp.linalg.norm(h) / jnp.dot(r_eci_m, r_eci_m)


def body_to_eci(r_eci_m, v_eci_mps, body_rad, theta1_rad):
    """C_ECI<-body [3, 3] and the orbit-frame rate in body axes omega_orb [3] (rad/s)."""
    rsw, rate = rsw_to_eci(r_eci_m, v_eci_mps)
    to_rsw = body_to_rsw(body_rad, theta1_rad)
    return rsw @ to_rsw, rate * to_rsw[2]  # W in body axes: the last row of C_RSW<-body


def initial(r_eci_m, v_eci_mps, body_rad, theta1_rad, inertia_kg_m2) -> Wheels:
    """Empty wheels at the start: H_0 = C_0 I omega_orb,0."""
    c, omega = body_to_eci(r_eci_m, v_eci_mps, body_rad, theta1_rad)
    zero, none = jnp.zeros(()), jnp.zeros(3)
    return Wheels(c @ (inertia_kg_m2 * omega), none, none, none, zero, zero, zero, zero)


def dump_tilt(h_body_nms, u_body, lever_body_m, force_n, firing_s, params: WheelParams):
    """(s [3], cos(delta)): the boom's tilt of the thrust line ``u_body`` (unit, body axes) for a step firing
    ``force_n`` for ``firing_s`` seconds, from the wrist's position ``lever_body_m`` (module docstring); no tilt
    (s = 0, cos = 1 exactly) without firing, a lever along the line or a limit of 0."""
    rho = jnp.dot(lever_body_m, u_body)
    live = (firing_s > 0) & (force_n > 0) & (jnp.abs(rho) > 1e-9) & (params.dump_angle_max_rad > 0)
    h_perp = h_body_nms - jnp.dot(h_body_nms, u_body) * u_body
    fraction = dumping_fraction(params.dump_gain_per_s, firing_s)
    wanted = -fraction * h_perp / jnp.where(live, firing_s, 1.0)
    tilt = jnp.cross(wanted, u_body) / jnp.where(live, rho * force_n, 1.0)
    length = jnp.linalg.norm(tilt)
    sin_max = jnp.sin(params.dump_angle_max_rad)
    tilt = jnp.where(live, tilt * jnp.where(length > sin_max, sin_max / jnp.where(length > 0, length, 1.0), 1.0), 0.0)
    return tilt, jnp.sqrt(1.0 - jnp.dot(tilt, tilt))


def tilted_pose(theta_rad, u_body, tilt, limits):
    """The joint angles [3] that point the boom's thrust along u' = cos(delta) u + s (``dump_tilt``), within the
    joints' ranges (``limits``: ``boom.JointLimits``): the inverse of ``boom.thrust_direction_body`` at theta2 = 90
    deg, u = (-s1 c3, c1 c3, s3), so theta1 = atan2(-u_x, u_y) and theta3 = asin(u_z), clipped to their stops (a
    tilt beyond a stop is flown only up to it)."""
    u = jnp.sqrt(1.0 - jnp.dot(tilt, tilt)) * u_body + tilt
    theta = jnp.stack([jnp.arctan2(-u[0], u[1]), theta_rad[1], jnp.arcsin(jnp.clip(u[2], -1.0, 1.0))])
    return jnp.clip(theta, limits.lower_rad, limits.upper_rad)


def start(state: Wheels, frame, inertia_kg_m2, params: WheelParams, moving):
    """At a step's start (``frame``: (r_eci_m, v_eci_mps, body_rad, theta1_rad) there): the wheels' momentum h_w =
    C^T H_eci - I omega_orb, its per-wheel extremes, and the attitude thrusters' unloading where a wheel passed its
    threshold (H_eci -= C h_w).  Returns (state, C_ECI<-body) for ``add``.  Frozen where not ``moving``."""
    c, omega = body_to_eci(*frame)
    h_body = wheel_momentum_body_nms(state.h_total_eci_nms, c.T, inertia_kg_m2 * omega)
    unload = moving & (jnp.max(jnp.abs(h_body)) > params.rcs_dump_fraction * params.capacity_nms)
    return state._replace(
        h_total_eci_nms=state.h_total_eci_nms - jnp.where(unload, c @ h_body, 0.0),
        h_body_nms=jnp.where(moving, jnp.where(unload, 0.0, h_body), state.h_body_nms),
        max_abs_nms=jnp.where(moving, jnp.maximum(state.max_abs_nms, jnp.abs(h_body)), state.max_abs_nms),
        rcs_dumped_nms=state.rcs_dumped_nms + jnp.where(unload, jnp.linalg.norm(h_body), 0.0),
        rcs_dumps=state.rcs_dumps + unload), c


def add(state: Wheels, c, r_eci_m, torque_body_nm, tilt_torque_nm, cross_accel_mps2, inertia_kg_m2, mu_m3_s2,
        step_s, moving):
    """The step's torques (eq. (8) of the line flown, ``torque_body_nm``, mean over the step, and the gravity
    gradient at its start, ``r_eci_m``) held in the start's axes ``c`` (from ``start``), added to H_eci, and the
    running totals.  Frozen where not ``moving``."""
    gravity = gravity_gradient_torque_body(c.T @ r_eci_m, jnp.diag(inertia_kg_m2), mu_m3_s2)
    impulse = jnp.where(moving, step_s * (c @ (torque_body_nm + gravity)), 0.0)
    return state._replace(
        h_total_eci_nms=state.h_total_eci_nms + impulse, torque_eci_nms=state.torque_eci_nms + impulse,
        tilt_impulse_nms=state.tilt_impulse_nms + jnp.where(moving, step_s * jnp.linalg.norm(tilt_torque_nm), 0.0),
        tilt_cross_mps=state.tilt_cross_mps + jnp.where(moving, step_s * cross_accel_mps2, 0.0))
