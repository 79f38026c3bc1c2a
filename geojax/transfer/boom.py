"""The triple orthogonal gimbaled thruster boom of Ma & Kong 2023: kinematics (7)-(9) and joint planning (Sec. 3).

Reading of the paper (each a marked choice, tested in ``tests/test_transfer.py``):

* Eq. (9)'s rotation block is Rz(theta1) Ry(theta2) Rz(theta3) (joint axes z, y, z of eq. (13)); its
  translation is Rz(theta1) [(0, d1, 0) + Ry(theta2) ((0, 0, d2) + Rz(theta3) (a1, 0, 0))].  The printed
  x entry, a1 (s1 s3 - c1 c2 c3) + ..., has the a1 term's sign flipped against that chain and against the
  printed y and z entries (erratum); ``wrist_pose`` uses the chain's sign.
* Eq. (7) puts the thrust along the wrist x axis; at the nominal pose (theta2 = 90 deg, theta3 = 0) that
  axis lies on joint 1's axis (gimbal lock: theta1 would not move the thrust, against the paper's Figs.
  8-11 where joint 1 steers the pitch).  We read the thruster as firing along the wrist y axis with the boom
  base axes equal to the body axes (R, S, W at zero attitude).  At theta2 = 90 deg the thrust is then
  (-s1 c3, c1 c3, s3): joint 1 turns it in the orbit plane (the pitch, azimuth 90 deg + theta1 from the
  radial, so J1 in [-90, 0] deg spans radial to along-track) and joint 3 lifts it out of the plane (the yaw,
  elevation theta3), as the paper's Remark 2 and Fig. 11 describe; joint 2 stays at 90 deg.
* The joints are planned by MPC (Sec. 3, eqs. (30)-(33)) on each joint's discrete double integrator: in free
  fall the potential term N of eq. (24) (a gravity g) is zero and the coupling C of eq. (19) is second order
  in the joint rates (deg/s), so eq. (30) decouples per joint.  The QP of eq. (33) (box on the joint
  acceleration) is solved by projected gradient with a fixed number of iterations inside the jitted loop;
  the rate and range limits are then enforced by clipping (the state set X of eq. (33)).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp


def rot_x(angle_rad):
    c, s = jnp.cos(angle_rad), jnp.sin(angle_rad)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    return jnp.array([[one, zero, zero], [zero, c, -s], [zero, s, c]])


def rot_y(angle_rad):
    c, s = jnp.cos(angle_rad), jnp.sin(angle_rad)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    return jnp.array([[c, zero, s], [zero, one, zero], [-s, zero, c]])


def rot_z(angle_rad):
    c, s = jnp.cos(angle_rad), jnp.sin(angle_rad)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    return jnp.array([[c, -s, zero], [s, c, zero], [zero, zero, one]])


def wrist_pose(theta_rad, d1_m, d2_m, a1_m):
    """Ma 2023, eq. (9): the wrist's rotation [3, 3] (columns: wrist axes in the base frame) and position [3] (m)
    for joint angles ``theta_rad`` [3]; the x entry of the position with the erratum's sign (module docstring)."""
    s1, s2, s3 = jnp.sin(theta_rad)
    c1, c2, c3 = jnp.cos(theta_rad)
    rotation = jnp.array([
        [c1 * c2 * c3 - s1 * s3, -s1 * c3 - c1 * c2 * s3, c1 * s2],
        [c1 * s3 + c2 * c3 * s1, c1 * c3 - s1 * c2 * s3, s1 * s2],
        [-s2 * c3, s2 * s3, c2],
    ])
    position = jnp.array([
        a1_m * (c1 * c2 * c3 - s1 * s3) + d2_m * c1 * s2 - d1_m * s1,
        a1_m * (c1 * s3 + c2 * c3 * s1) + d1_m * c1 + d2_m * s1 * s2,
        d2_m * c2 - a1_m * c3 * s2,
    ])
    return rotation, position


def thrust_direction_body(theta_rad):
    """Unit thrust direction [3] in the body frame (R, S, W at zero attitude): the wrist y axis, column 2 of
    eq. (9)'s rotation (eq. (7) with the reading of the module docstring)."""
    s1, s2, s3 = jnp.sin(theta_rad)
    c1, c2, c3 = jnp.cos(theta_rad)
    return jnp.array([-s1 * c3 - c1 * c2 * s3, c1 * c3 - s1 * c2 * s3, s2 * s3])


def joint_targets_rad(azimuth_rad, elevation_rad, theta2_rad=jnp.pi / 2):
    """Inverse of eq. (9) at theta2 = 90 deg: the joint angles [3] that point the thrust at ``azimuth_rad`` from
    the body x (radial) axis towards y (along-track) and ``elevation_rad`` out of the x-y plane."""
    theta1 = azimuth_rad - jnp.pi / 2
    return jnp.stack([theta1, jnp.broadcast_to(theta2_rad, jnp.shape(theta1)), elevation_rad])


def lever_m(theta_rad, d1_m, d2_m, a1_m, base_offset_m):
    """r_W0 + l_0 [3] (m, body axes): the wrist's position from the body origin (the centre of mass), eq. (8)'s
    lever."""
    _, r_w0 = wrist_pose(theta_rad, d1_m, d2_m, a1_m)
    return r_w0 + base_offset_m


def coupling_torque_nm(theta_rad, thrust_n, d1_m, d2_m, a1_m, base_offset_m):
    """Ma 2023, eq. (8): (r_W0 + l_0) x f_thrust,b [3] (N m), the boom thrust's torque about the body origin."""
    return jnp.cross(lever_m(theta_rad, d1_m, d2_m, a1_m, base_offset_m), thrust_n * thrust_direction_body(theta_rad))


class JointLimits(NamedTuple):
    """Table 1 ranges and the drive's rate and acceleration limits; each leaf [3] (rad, rad/s, rad/s^2)."""

    lower_rad: jnp.ndarray
    upper_rad: jnp.ndarray
    rate_rad_s: jnp.ndarray
    accel_rad_s2: jnp.ndarray


class MpcWeights(NamedTuple):
    """Stage cost of eq. (33): q (theta - theta_ref)^2 + q_rate (omega - omega_ref)^2 + r u^2, per joint."""

    q_per_rad2: jnp.ndarray
    q_rate_per_rad2_s2: jnp.ndarray
    r_per_rad2_s4: jnp.ndarray


def _prediction(step_s, horizon: int):
    """Eq. (31) for a double integrator: angle and rate over the horizon = Phi x0 + Gamma U; shapes
    [horizon, 2], [horizon, horizon] for each of angle and rate."""
    k = jnp.arange(1, horizon + 1, dtype=float)
    phi_angle = jnp.stack([jnp.ones(horizon), k * step_s], -1)
    phi_rate = jnp.stack([jnp.zeros(horizon), jnp.ones(horizon)], -1)
    lag = k[:, None] - jnp.arange(horizon)[None, :]  # steps since input j was applied, at prediction k
    active = lag >= 1
    gamma_angle = jnp.where(active, (lag - 0.5) * step_s**2, 0.0)
    gamma_rate = jnp.where(active, step_s, 0.0)
    return phi_angle, gamma_angle, phi_rate, gamma_rate


def mpc_acceleration(angle_rad, rate_rad_s, ref_rad, ref_rate_rad_s, accel_max_rad_s2, weights: MpcWeights,
                     step_s, horizon: int, iterations: int):
    """Eq. (33) for one joint: the first of ``horizon`` accelerations minimising the tracking cost of the
    linearly extrapolated reference (``ref_rad`` is the target one step ahead; k steps ahead it is
    ref + (k - 1) step ref_rate), |u| <= accel_max; projected gradient from the
    clipped unconstrained optimum, ``iterations`` (static) steps of 1 / trace(H)."""
    phi_a, gam_a, phi_r, gam_r = _prediction(step_s, horizon)
    x0 = jnp.stack([angle_rad, rate_rad_s])
    k = jnp.arange(1, horizon + 1, dtype=float)
    angle_error = phi_a @ x0 - (ref_rad + (k - 1) * step_s * ref_rate_rad_s)
    rate_error = phi_r @ x0 - ref_rate_rad_s
    hessian = (weights.q_per_rad2 * gam_a.T @ gam_a + weights.q_rate_per_rad2_s2 * gam_r.T @ gam_r
               + weights.r_per_rad2_s4 * jnp.eye(horizon))
    gradient0 = weights.q_per_rad2 * gam_a.T @ angle_error + weights.q_rate_per_rad2_s2 * gam_r.T @ rate_error
    u = jnp.clip(-jnp.linalg.solve(hessian, gradient0), -accel_max_rad_s2, accel_max_rad_s2)
    step = 1.0 / jnp.trace(hessian)

    def descend(u, _):
        return jnp.clip(u - step * (hessian @ u + gradient0), -accel_max_rad_s2, accel_max_rad_s2), None

    u, _ = jax.lax.scan(descend, u, None, length=iterations)
    return u[0]


def joint_step(theta_rad, omega_rad_s, ref_rad, ref_rate_rad_s, limits: JointLimits, weights: MpcWeights,
               step_s, horizon: int, iterations: int):
    """One planning step of the three joints: MPC acceleration, exact double-integrator update, then the rate
    and range limits (a joint at a stop has its rate zeroed).  Returns (theta [3], omega [3])."""
    ref = jnp.clip(ref_rad, limits.lower_rad, limits.upper_rad)
    accel = jax.vmap(mpc_acceleration, in_axes=(0, 0, 0, 0, 0, 0, None, None, None))(
        theta_rad, omega_rad_s, ref, ref_rate_rad_s, limits.accel_rad_s2, weights, step_s, horizon, iterations)
    omega = jnp.clip(omega_rad_s + accel * step_s, -limits.rate_rad_s, limits.rate_rad_s)
    theta = theta_rad + 0.5 * (omega_rad_s + omega) * step_s
    clipped = jnp.clip(theta, limits.lower_rad, limits.upper_rad)
    return clipped, jnp.where(clipped == theta, omega, 0.0)
