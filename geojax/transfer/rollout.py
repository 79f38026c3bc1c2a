"""One GTO-GEO transfer as a pure function: a ``lax.scan`` over integration steps carrying a ``done`` flag.

Each step: the guidance (``steering.steer``) wishes a thrust direction; the thruster (the boom's, or the
quadrilateral's pair closest to the wish, ``quadrilateral.best_pair``) fires along the direction that body and
joints reached if the firing rule fires, the misalignment is within its bound, the
spacecraft is in sunlight (electric propulsion stops in the Earth's shadow, and in the Moon's with
``forces.moon_shadow``: the visible fraction of the solar disc, ``forces.sunlit_fraction_xyz``, scales the
thrust, as it scales the solar radiation pressure) and propellant is left.  The orbit is integrated in MEE with RK4 and the full force
model (``physics.dynamics.mee_rhs``).  Then, for the next step, the body slews towards the part of the end
state's wish that the boom cannot reach (``pointing``), with the boom's coupling torque (eq. (8), from the
joint angles and the thrust of the step) acting on it through eq. (6) (``pointing.slew_over_step``: it shifts
the wheels' acceleration window by torque / inertia; the attitude loop runs at 10 s inside the step), and the
joints' MPC tracks the rest (``boom.joint_step``, Remark 2's split).  The slews' torque is booked as attitude
propellant (``pointing.attitude_propellant_kg``).
When the end conditions hold (GEO radius, e and i below their thresholds) the state freezes; termination
is data, the status and the time reached, never a Python loop.

Scans are nested: an outer scan over records, an inner one over ``steps_per_record`` steps, so a long
transfer keeps one record per chosen interval (a day for a Monte Carlo, every step for the joint histories).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.physics.dynamics import SpacecraftState, Thrust, mee_rhs
from geojax.physics.elements import mee_to_rv_xyz
from geojax.physics.forces import Environment, ForceModel, sunlit_fraction_xyz
from geojax.physics.integrate import rk4_step
from geojax.transfer import boom, pointing, quadrilateral, steering, wheels

# 0 success, the rest failures: the meaning ``simulate``'s codes have (``loop.metrics``).
STATUS_REACHED_GEO, STATUS_TIME_LIMIT, STATUS_NO_PROPELLANT, STATUS_NONFINITE = range(4)
STATUS_MEANINGS = {STATUS_REACHED_GEO: "reached GEO (end conditions met)",
                   STATUS_TIME_LIMIT: "time limit reached first", STATUS_NO_PROPELLANT: "propellant exhausted", STATUS_NONFINITE: "state not finite"}
STATUS_TEXT = ", ".join(f"{code} {text}" for code, text in STATUS_MEANINGS.items())


class TransferParams(NamedTuple):
    """One transfer's parameters; every leaf an array (SI), so a batch vmaps over any of them."""

    initial: SpacecraftState  # MEE orbit [6], mass, delivered Delta-V
    forces: ForceModel
    dry_mass_kg: jnp.ndarray
    thrust_n: jnp.ndarray
    isp_s: jnp.ndarray
    # [4] resultant per unit thrust of the pairs along +t, -t, +l, -l (``quadrilateral.pair_axis_efficiency``);
    # the boom's one thruster: (1, 0, 0, 0)
    pair_efficiency: jnp.ndarray
    r_geo_m: jnp.ndarray  # end: |a - r_geo| < a_tol_m, e < e_end, i < i_end_rad
    a_tol_m: jnp.ndarray
    e_end: jnp.ndarray
    i_end_rad: jnp.ndarray
    deadband_m: jnp.ndarray  # firing rule, steering.steer
    efficiency: jnp.ndarray
    max_misalignment_rad: jnp.ndarray  # the thruster fires only closer than this to the wished direction
    slew_rate_rad_s: jnp.ndarray  # body slew bounds
    slew_accel_rad_s2: jnp.ndarray  # the wheels' authority: |tau_c| <= J slew_accel on each slew axis
    inertia_kg_m2: jnp.ndarray  # [3] J_body of eq. (6), principal moments along the body axes
    rcs_arm_m: jnp.ndarray  # attitude thrusters' couple arm and Isp (pointing.attitude_propellant_kg)
    rcs_isp_s: jnp.ndarray
    joints: boom.JointLimits  # [3] each; the quadrilateral: lower = upper = (0, 90, 0) deg
    weights: boom.MpcWeights  # [3] each
    d1_m: jnp.ndarray  # boom link lengths, eq. (9)
    d2_m: jnp.ndarray
    a1_m: jnp.ndarray
    base_offset_m: jnp.ndarray  # [3] l_0 of eq. (8)
    wheels: wheels.WheelParams  # the reaction wheels and their unloading (``wheels``)


class Static(NamedTuple):
    """What fixes the compiled loop's shape."""

    step_s: float
    n_records: int
    steps_per_record: int
    mpc_horizon: int
    mpc_iterations: int


class Attitude(NamedTuple):
    body_rad: jnp.ndarray  # [2] body azimuth and elevation offsets
    body_rate_rad_s: jnp.ndarray  # [2]
    theta_rad: jnp.ndarray  # [3] joint angles
    omega_rad_s: jnp.ndarray  # [3] joint rates
    ref_rad: jnp.ndarray  # [3] last joint targets (their rate feeds the MPC's extrapolation)
    body_target_rad: jnp.ndarray  # [2] last body target (its rate feeds the slew's, pointing.target_rate_rad_s)


class Stats(NamedTuple):
    """Running totals over the transfer (frozen once done)."""

    firing_s: jnp.ndarray  # integral of the on-fraction
    aligned_s: jnp.ndarray  # integral of on x pair resultant x cos(misalignment) (run.metrics: the efficiencies)
    lost_to_slew_s: jnp.ndarray  # time the rule fired in sunlight but the pointing was too far off
    track_max_rad: jnp.ndarray  # [3] largest |theta - target| (Fig. 14)
    track_sq_rad2: jnp.ndarray  # [3] sum of squares, for the RMS
    track_steps: jnp.ndarray  # [3] steps counted in the RMS
    torque_max_nm: jnp.ndarray  # largest |eq. (8)|
    torque_impulse_nms: jnp.ndarray  # integral of |eq. (8)|: the momentum the wheels must store or dump
    overpowered_s: jnp.ndarray  # time the torque beat the wheels (|torque / inertia| > slew_accel) on a slew axis
    slew_impulse_nms: jnp.ndarray  # integral of |J d(omega)/dt| over both slew axes (pointing.slew_torque_nm)


class Carry(NamedTuple):
    craft: SpacecraftState
    attitude: Attitude  # where body and joints point during the coming step
    wish: steering.Command  # eq. (1) at the current state
    stats: Stats
    done: jnp.ndarray  # bool
    status: jnp.ndarray  # int, STATUS_MEANINGS
    t_end_s: jnp.ndarray  # time the transfer ended (end conditions or propellant), else the time limit
    t_s: jnp.ndarray
    wheels: wheels.Wheels  # the reaction wheels' momentum and its unloading (``wheels``)


class Record(NamedTuple):
    """Sampled at the end of each record interval (leading axis: record)."""

    t_s: jnp.ndarray
    a_m: jnp.ndarray
    e: jnp.ndarray
    i_rad: jnp.ndarray
    mass_kg: jnp.ndarray
    dv_mps: jnp.ndarray
    on_fraction: jnp.ndarray
    misalignment_rad: jnp.ndarray
    wished_rad: jnp.ndarray  # [2] azimuth, elevation of eq. (1)
    body_rad: jnp.ndarray  # [2]
    body_rate_rad_s: jnp.ndarray  # [2]
    theta_rad: jnp.ndarray  # [3]
    target_rad: jnp.ndarray  # [3]
    omega_rad_s: jnp.ndarray  # [3]
    torque_nm: jnp.ndarray  # [3]
    pair: jnp.ndarray  # the pair that fired or would (0..3: +t, -t, +l, -l; quadrilateral.best_pair)
    wheel_nms: jnp.ndarray  # [3] the wheels' momentum, body axes (R, S, W at zero attitude; ``wheels``)


def initial_carry(params: TransferParams) -> Carry:
    """At the start the spacecraft is already pointed: the body at its share of eq. (1)'s first wish, the joints
    at their targets (the quadrilateral's joints stay at (0, 90, 0) deg)."""
    wish = _wish(params.initial.orbit, params)
    body = pointing.body_share_rad(jnp.stack([wish.azimuth_rad, wish.elevation_rad]), *_joint_reach(params))
    theta0 = _joint_targets(wish, body, params)
    zero = jnp.zeros(())
    r, v = mee_to_rv_xyz(*(params.initial.orbit[j] for j in range(6)), params.forces.mu_m3_s2)
    return Carry(
        params.initial,
        Attitude(body, jnp.zeros(2), theta0, jnp.zeros(3), theta0, body),
        wish,
        Stats(zero, zero, zero, jnp.zeros(3), jnp.zeros(3), jnp.zeros(3), zero, zero, zero, zero),
        jnp.array(False), jnp.array(STATUS_TIME_LIMIT), zero, zero,
        wheels.initial(jnp.stack(r), jnp.stack(v), body, theta0[0], params.inertia_kg_m2),
    )


def transfer(params: TransferParams, env_grid: Environment, static: Static):
    """Run one transfer over the environment grid (leaves [n_records, steps_per_record, 3, ...]).

    Returns (final ``Carry``, ``Record`` with leading axis n_records).  Pure; vmap over ``params``.
    """

    return ended(*advance(params, initial_carry(params), env_grid, static), static)


def advance(params: TransferParams, carry: Carry, env_grid: Environment, static: Static):
    """Fly the records of ``env_grid`` (any number of them, leaves [records, steps_per_record, 3, ...]) from
    ``carry``: (the carry after them, their ``Record``s).  A transfer run in blocks of records (``run``'s progress)
    is this called once per block, then ``ended``."""

    def outer(carry, env_block):
        carry, records = jax.lax.scan(lambda c, env3: _step(c, env3, params, static), carry, env_block)
        return carry, jax.tree_util.tree_map(lambda x: x[-1], records)

    return jax.lax.scan(outer, carry, env_grid)


def ended(final: Carry, records, static: Static):
    """``advance``'s result at the time limit: a transfer not done ends there (``t_end_s``)."""
    time_limit_s = static.n_records * static.steps_per_record * static.step_s
    return final._replace(t_end_s=jnp.where(final.done, final.t_end_s, time_limit_s)), records


def _wish(orbit, params: TransferParams) -> steering.Command:
    geometry = steering.orbit_geometry(orbit)
    return steering.steer(geometry, params.r_geo_m, params.deadband_m, params.i_end_rad, params.efficiency,
                          params.forces.mu_m3_s2)


def _joint_reach(params: TransferParams):
    """The (azimuth, elevation) range the joints reach: azimuth = 90 deg + theta1, elevation = theta3."""
    low = jnp.stack([params.joints.lower_rad[0] + jnp.pi / 2, params.joints.lower_rad[2]])
    high = jnp.stack([params.joints.upper_rad[0] + jnp.pi / 2, params.joints.upper_rad[2]])
    return low, high


def _joint_targets(wish: steering.Command, body_rad, params: TransferParams):
    """The inverse of eq. (9) for what the body leaves of the wish, within the joint ranges (Remark 2)."""
    residual = pointing.joint_share_rad(jnp.stack([wish.azimuth_rad, wish.elevation_rad]), body_rad,
                                        *_joint_reach(params))
    return jnp.clip(boom.joint_targets_rad(residual[0], residual[1]), params.joints.lower_rad, params.joints.upper_rad)


def _step(carry: Carry, env3: Environment, params: TransferParams, static: Static):
    """Fly one step with the pointing reached, then point body and joints at the wish of the step's end state
    (known from the step just integrated), so the pointing of the next step is not a step late."""
    step_s = static.step_s
    craft, att, wish = carry.craft, carry.attitude, carry.wish
    mu = params.forces.mu_m3_s2

    # the strong pairs' axis t (the boom's thrust) where body and joints point it, the weak pairs' l beside it in
    # the orbit plane of the thrust's azimuth; the pair closest to the wish fires (the boom: t only)
    reached = att.body_rad + jnp.stack([att.theta_rad[0] + jnp.pi / 2, att.theta_rad[2]])
    axis = steering.direction_rsw(reached[0], reached[1])
    beside = steering.direction_rsw(reached[0] + jnp.pi / 2, 0.0)
    wished_unit = steering.direction_rsw(wish.azimuth_rad, wish.elevation_rad)
    pair, resultant = quadrilateral.best_pair(axis, beside, wished_unit, params.pair_efficiency)
    efficiency = params.pair_efficiency[pair]
    # (a layout without the pair, the boom behind its wish, is measured from its thrust axis)
    off_by = pointing.misalignment_rad(jnp.where(efficiency > 0, resultant / jnp.maximum(efficiency, 1e-30), axis),
                                       wished_unit)
    (x, y, z), v0 = mee_to_rv_xyz(*(craft.orbit[j] for j in range(6)), mu)
    sunlit = sunlit_fraction_xyz(x, y, z, jax.tree_util.tree_map(lambda leaf: leaf[0], env3), params.forces)
    live = (~carry.done) & (craft.mass_kg > params.dry_mass_kg)
    wants = wish.fire * sunlit * live
    aligned = (off_by <= params.max_misalignment_rad) & (efficiency > 0)
    on = wants * aligned
    plain_torque = boom.coupling_torque_nm(att.theta_rad, params.thrust_n * on, params.d1_m, params.d2_m,
                                           params.a1_m, params.base_offset_m)
    # the boom's dumping tilt (``wheels``): the joints turn the line toward the law's tilt within their ranges, and
    # eq. (8) is that pose's; exactly the untilted pose, torque and direction without a tilt
    r0 = jnp.stack([x, y, z])
    wheel, frame = wheels.start(carry.wheels, (r0, jnp.stack(v0), att.body_rad, att.theta_rad[0]),
                                params.inertia_kg_m2, params.wheels, ~carry.done)
    u_body = boom.thrust_direction_body(att.theta_rad)
    lever = boom.lever_m(att.theta_rad, params.d1_m, params.d2_m, params.a1_m, params.base_offset_m)
    tilt, _ = wheels.dump_tilt(wheel.h_body_nms, u_body, lever, params.thrust_n, on * step_s, params.wheels)
    tilting = jnp.any(tilt != 0.0)
    theta_flown = jnp.where(tilting, wheels.tilted_pose(att.theta_rad, u_body, tilt, params.joints), att.theta_rad)
    torque = boom.coupling_torque_nm(theta_flown, params.thrust_n * on, params.d1_m, params.d2_m, params.a1_m,
                                     params.base_offset_m)
    u_flown = boom.thrust_direction_body(theta_flown)
    cos_delta = jnp.where(tilting, jnp.dot(u_flown, u_body), 1.0)
    turn_body = jnp.where(tilting, u_flown - u_body, 0.0)
    resultant = resultant + wheels.body_to_rsw(att.body_rad, att.theta_rad[0]) @ turn_body
    # the pair's two thrusters burn F / (Isp g0) and push eta F along its axis: the direction's norm is eta
    stepped = rk4_step(mee_rhs, craft, env3, params.forces, Thrust(resultant, params.thrust_n, params.isp_s, on),
                       step_s)
    finite = jnp.all(jnp.isfinite(stepped.orbit))
    craft = jax.tree_util.tree_map(lambda new, old: jnp.where(carry.done | ~finite, old, new), stepped, craft)

    # pointing for the next step: the body slews toward the share the joints cannot reach, its wheels fighting
    # the step's eq. (8) torque (eq. (6)); the joints' MPC (Sec. 3) tracks the inverse of eq. (9) for the rest
    next_wish = _wish(craft.orbit, params)
    wished = jnp.stack([next_wish.azimuth_rad, next_wish.elevation_rad])
    disturbance = pointing.slew_disturbance_rad_s2(torque, att.theta_rad[0], params.inertia_kg_m2)
    body_target = pointing.body_target_rad(wished, att.body_rad, *_joint_reach(params), params.pair_efficiency[1] > 0)
    body, body_rate, slew_impulse = pointing.slew_over_step(
        att.body_rad, att.body_rate_rad_s, body_target,
        pointing.target_rate_rad_s(body_target, att.body_target_rad, params.slew_rate_rad_s, step_s),
        params.slew_rate_rad_s, params.slew_accel_rad_s2, step_s, max(1, math.ceil(step_s / pointing.ATTITUDE_STEP_S)),
        disturbance, pointing.slew_inertia_kg_m2(att.theta_rad[0], params.inertia_kg_m2))
    target = _joint_targets(next_wish, body, params)
    theta, omega = boom.joint_step(att.theta_rad, att.omega_rad_s, target, (target - att.ref_rad) / step_s,
                                   params.joints, params.weights, step_s, static.mpc_horizon, static.mpc_iterations)
    # Fig. 14's tracking error, counted where the target moved no faster than the drive can (a target that
    # jumps, when the thrust flips between forward and backward, is a step response, not tracking)
    trackable = jnp.abs(target - att.ref_rad) <= params.joints.rate_rad_s * step_s
    track_error = jnp.where(trackable, jnp.abs(theta - target), 0.0)

    moving = ~carry.done
    attitude = jax.tree_util.tree_map(lambda new, old: jnp.where(moving, new, old),
                                      Attitude(body, body_rate, theta, omega, target, body_target), att)
    next_wish = jax.tree_util.tree_map(lambda new, old: jnp.where(moving, new, old), next_wish, wish)
    s = carry.stats
    count = moving.astype(float)
    stats = Stats(s.firing_s + on * step_s, s.aligned_s + on * efficiency * jnp.cos(off_by) * cos_delta * step_s,
                  s.lost_to_slew_s + wants * (~aligned) * step_s,
                  jnp.maximum(s.track_max_rad, count * track_error), s.track_sq_rad2 + count * track_error**2,
                  s.track_steps + count * trackable, jnp.maximum(s.torque_max_nm, count * jnp.linalg.norm(torque)),
                  s.torque_impulse_nms + count * jnp.linalg.norm(torque) * step_s,
                  s.overpowered_s + count * jnp.any(jnp.abs(disturbance) > params.slew_accel_rad_s2) * step_s,
                  s.slew_impulse_nms + count * jnp.sum(slew_impulse))

    t_s = carry.t_s + step_s
    after = steering.orbit_geometry(craft.orbit)
    arrived = ((jnp.abs(after.a_m - params.r_geo_m) < params.a_tol_m) & (after.e < params.e_end)
               & (after.i_rad < params.i_end_rad))
    empty = craft.mass_kg <= params.dry_mass_kg
    status = jnp.where(carry.done, carry.status,
                       jnp.where(~finite, STATUS_NONFINITE,
                                 jnp.where(arrived, STATUS_REACHED_GEO,
                                           jnp.where(empty, STATUS_NO_PROPELLANT, STATUS_TIME_LIMIT))))
    done = carry.done | arrived | empty | ~finite
    t_end = jnp.where(carry.done, carry.t_end_s, t_s)
    wheel = wheels.add(wheel, frame, r0, torque, torque - plain_torque,
                       params.thrust_n * on * jnp.linalg.norm(u_flown - cos_delta * u_body) / craft.mass_kg,
                       params.inertia_kg_m2, mu, step_s, moving)
    record = Record(t_s, after.a_m, after.e, after.i_rad, craft.mass_kg, craft.dv_mps, on, off_by, wished,
                    attitude.body_rad, attitude.body_rate_rad_s, attitude.theta_rad, target, attitude.omega_rad_s,
                    torque, pair, wheel.h_body_nms)
    return Carry(craft, attitude, next_wish, stats, done, status, t_end, t_s, wheel), record
