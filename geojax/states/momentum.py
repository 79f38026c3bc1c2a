"""The reaction wheels' momentum of a nadir-pointing body, a part of the loop (``attitude.wheels = true``).

The solar-pressure, gravity-gradient and thruster torques drive it, and the station-keeping burns unload it, each
tilting its thrust line off the centre of mass (the two-burn dumping law, ``thrust``).  The loop carries the total
angular momentum in ECI and turns it into the wheels' body axes at every step's end, so the gyroscopic term is
exact.  The equation, its integration, the torques, the dumping law and the defaults' sources: docs/momentum.md
("The derivation")."""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.physics.attitude import (array_frame, body_rate_rad_s, dumping_fraction, gravity_gradient_torque_body,
                                     inertia_matrix, nadir_frame, srp_force_eci_n, wheel_momentum_body_nms)
from geojax.physics.constants import SECONDS_PER_DAY
from geojax.physics.dynamics import Thrust
from geojax.params import LOG, NUMBER, Field, degrees
from geojax.states.base import DUMPING, WHEEL_MOMENTUM, Constraint, Part, StateModel, StepContext, ThrustContext

NAME = "wheels"
# (Ixx, Iyy, Izz, Ixy, Ixz, Iyz), kg m^2: an estimate for Li 2022's class (docs/momentum.md, "The defaults").
DEFAULT_INERTIA_KG_M2 = (85866.7, 7925.0, 83566.7, 0.0, 0.0, 0.0)
DEFAULT_CAPACITY_NMS = 50.0
DEFAULT_THRUST_ARM_M = 2.5
DEFAULT_DUMP_GAIN_PER_S = 0.01
DEFAULT_TRANSIENT_FRACTION = 0.75
# ``time_above_80pct_capacity_fraction`` counts the step starts where a wheel holds more than this of its capacity.
HIGH_FRACTION = 0.8
SATURATED = "wheels saturated"

# The ``[attitude]`` table: carried only where ``wheels = true`` (the other keys are refused otherwise); every
# torque's default is none.
FIELDS = {
    "wheels": Field(bool, False, static=True,
                    doc="carry the reaction wheels' momentum (a nadir-pointing body, three wheels on its axes)"),
    "wheel_capacity_nms": Field(NUMBER, DEFAULT_CAPACITY_NMS, lower=0.0, upper=1e6, si="wheel_capacity_nms",
                                symbol="h_max", unit="N m s",
                                doc="momentum each wheel stores at most; beyond it: status 6, wheels saturated"),
    "initial_momentum_nms": Field(list, [0.0, 0.0, 0.0], length=3, si="initial_momentum_nms", unit="N m s",
                                  doc="the wheels' momentum at the start, body axes (x along-track, y "
                                      "anti-normal, z nadir)"),
    "inertia_kg_m2": Field(list, list(DEFAULT_INERTIA_KG_M2), length=6, si="inertia_kg_m2", unit="kg m²",
                           doc="inertia tensor (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) in body axes: the gravity-"
                               "gradient torque; default an estimate for Li 2022's 5000 kg class, principal"),
    "srp_offset_body_m": Field(list, [0.0, 0.0, 0.0], length=3, si="srp_offset_body_m", unit="m",
                               doc="centre of pressure less centre of mass, body axes: SRP torque"),
    "srp_offset_array_m": Field(list, [0.0, 0.0, 0.0], length=3, si="srp_offset_array_m", unit="m",
                                doc="centre of pressure less centre of mass along the solar array's axis (the "
                                    "orbit normal), across it, along its Sun-facing normal: SRP torque"),
    "thrust_arm_m": Field(NUMBER, DEFAULT_THRUST_ARM_M, lower=0.0, lower_inclusive=True, upper=100.0,
                          si="thrust_arm_m", symbol="L_thr", unit="m",
                          doc="distance from the centre of mass to each thruster's nozzle (the gimbal a "
                              "dumping tilt turns about): the tilt's moment arm"),
    "thrust_reach_m": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=100.0, si="thrust_reach_m",
                            symbol="ρ_arm", unit="m",
                            doc="each arm's reach from its base to the nozzle: with it the nozzle distance is "
                                "where the arm puts the nozzle on the line through the centre of mass, burn by "
                                "burn (states.momentum.nozzle_distance_m); 0: thrust_arm_m for every burn"),
    "thrust_base_north_m": Field(list, [0.0, 0.0, 0.0], length=3, si="thrust_base_north_m", unit="m",
                                 doc="base of the arm on the north side, body axes (it flies the burns that push "
                                     "south: Li 2022's thruster 1); read where thrust_reach_m > 0"),
    "thrust_base_south_m": Field(list, [0.0, 0.0, 0.0], length=3, si="thrust_base_south_m", unit="m",
                                 doc="base of the arm on the south side, body axes (the burns that push north); "
                                     "a single manipulator (Ye 2022): both bases its platform"),
    "dump_angle_max_deg": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=90.0,
                                si="dump_angle_max_rad", to_si=degrees, symbol="δ_max",
                                doc="largest tilt of a thrust line off the centre of mass to unload the "
                                    "wheels during burns; 0: no dumping"),
    "dump_gain_per_s": Field(NUMBER, DEFAULT_DUMP_GAIN_PER_S, lower=0.0, upper=1e3,
                             si="dump_gain_per_s", symbol="k_dump", unit="1/s", transform=LOG,
                             doc="the dumping law's gain: the torque asked of a tilt is -k_dump times the "
                                 "measured wheel momentum"),
    "dump_transient_fraction": Field(NUMBER, DEFAULT_TRANSIENT_FRACTION, lower=0.0, lower_inclusive=True,
                                     upper=1.0, si="dump_transient_fraction", symbol="f_tr", unit="",
                                     doc="the most momentum, as a fraction of a wheel's capacity, a burn may "
                                         "leave for the next burn to empty (the rest: margin for the torques "
                                         "meanwhile)"),
    "tank_offset_body_m": Field(list, [0.0, 0.0, 0.0], length=3, si="tank_offset_body_m", unit="m",
                                doc="the propellant's centre less the starting centre of mass, body axes: the "
                                    "centre of mass moves as propellant is used (thrust and SRP torques)"),
    "wheel_momentum_sigma_nms": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6,
                                      si="wheel_momentum_sigma_nms", symbol="σ_h", unit="N m s",
                                      doc="1-sigma error per axis of the measured wheel momentum the dumping "
                                          "law reads (one draw per cycle)"),
}


class Wheels(NamedTuple):
    """The carried state."""

    h_total_eci_nms: jnp.ndarray  # [3] total angular momentum I omega + h_w, ECI axes, N m s
    h_body_nms: jnp.ndarray  # [3] the wheels' momentum h_w at the latest step end, body axes, N m s
    srp_impulse_nms: jnp.ndarray  # [] integral of |tau_srp| dt since the start of the run, N m s
    gravity_gradient_impulse_nms: jnp.ndarray  # [] integral of |tau_gg| dt since the start, N m s
    steps_above: jnp.ndarray  # [] step starts so far with a wheel above HIGH_FRACTION of its capacity
    thrust_impulse_nms: jnp.ndarray  # [] integral of |tau_thrust| dt since the start, N m s
    cross_dv_mps: jnp.ndarray  # [] the Delta-V the dumping tilts put across the planned directions, m/s
    error_nms: jnp.ndarray  # [3] this cycle's error of the measured wheel momentum, body axes
    thrust_torque_body_nm: jnp.ndarray  # [3] the thrust's torque over the current step (``thrust``), body axes
    cross_force_n: jnp.ndarray  # [] the thrust across the planned direction over the current step (mean), N
    srp_eci_nm: jnp.ndarray  # [3] the SRP torque at the latest step end, ECI (the next step's start)
    gravity_gradient_eci_nm: jnp.ndarray  # [3] the gravity-gradient torque there
    thrust_start_eci_nm: jnp.ndarray  # [3] the thrust's torque over the current step, ECI axes at its start
    line_eci: jnp.ndarray  # [3] the unit thrust direction of the latest firing step, ECI (0: none yet)
    other_line_eci: jnp.ndarray  # [3] that of the burn before the latest (more than 90 deg from it), ECI
    external_eci_nms: jnp.ndarray  # [3] integral of the external torques (SRP, gravity gradient) since the start, ECI


class WheelStep(NamedTuple):
    """Per step (kept with ``keep_steps``)."""

    h_nms: jnp.ndarray  # [3] the wheels' momentum at the step start, body axes


class WheelCycle(NamedTuple):
    """Per cycle (always kept)."""

    max_abs_nms: jnp.ndarray  # [3] the largest |h_w| per wheel over the cycle's step starts and its end
    start_nms: jnp.ndarray  # [3] h_w at the cycle start
    end_nms: jnp.ndarray  # [3] h_w at the cycle end
    srp_impulse_nms: jnp.ndarray  # [] integral of |tau_srp| dt from the run's start to the cycle end
    gravity_gradient_impulse_nms: jnp.ndarray  # [] the same of the gravity gradient
    steps_above: jnp.ndarray  # [] step starts from the run's start with a wheel above HIGH_FRACTION of capacity
    thrust_impulse_nms: jnp.ndarray  # [] integral of |tau_thrust| dt from the run's start to the cycle end
    cross_dv_mps: jnp.ndarray  # [] the dumping tilts' Delta-V across the plan from the run's start to the cycle end
    external_eci_nms: jnp.ndarray  # [3] integral of the SRP and gravity-gradient torques from the run's start, ECI


def init(params, r_eci_m, v_eci_mps, env, fm) -> Wheels:
    """The wheels at the run's start: ``attitude.initial_momentum_nms`` (body axes), and the torques there."""
    a = params.states[NAME]
    h0 = a["initial_momentum_nms"]
    inertia = inertia_matrix(a["inertia_kg_m2"])
    srp, gg, c = torques(a, inertia, r_eci_m, v_eci_mps, env, fm)
    zero = jnp.zeros_like(h0[0])
    none = jnp.zeros_like(h0)
    return Wheels(c.T @ (inertia @ body_rate_rad_s(r_eci_m, v_eci_mps) + h0), h0, zero, zero, zero, zero, zero,
                  none, none, zero, srp, gg, none, none, none, none)


def cycle(params, state: Wheels, start) -> Wheels:
    """At a cycle start: this cycle's error of the measured wheel momentum (Gaussian, 1-sigma
    ``attitude.wheel_momentum_sigma_nms`` per axis, from the model's own key)."""
    sigma = params.states[NAME]["wheel_momentum_sigma_nms"]
    return state._replace(error_nms=sigma * jax.random.normal(start.key, (3,), state.error_nms.dtype))


def thrust(params, state: Wheels, flown: Thrust, ctx: ThrustContext):
    """The dumping law on the thrust flown over a step (docs/momentum.md, "The derivation"): ``(state, thrust)``,
    the thrust with its line tilted within ``attitude.dump_angle_max_deg`` and the state noting the thrust's torque
    (tilt and centre-of-mass shift, body axes) and the force across the plan for ``step``.  No tilt at a 0 deg
    limit, the direction then exactly the controller's."""
    a = params.states[NAME]
    d = flown.direction_rsw
    u_b = jnp.stack([d[1], -d[2], -d[0]])  # body = (S, -W, -R)
    size = jnp.linalg.norm(u_b)  # 1, or less for a mean of time-shared directions
    force_n = flown.thrust_n * size  # while firing
    firing = (flown.on_fraction > 0) & (force_n > 0)
    u_hat = u_b / jnp.where(size > 0, size, 1.0)
    c = nadir_frame(ctx.r_eci_m, ctx.v_eci_mps)
    u_eci = c.T @ u_hat
    # the other burn's line: the latest line of the burn before this one (a burn starts where the direction
    # turns more than 90 deg from the last one fired)
    new_burn = firing & (jnp.dot(u_eci, state.line_eci) < 0)
    other_eci = jnp.where(new_burn, state.line_eci, state.other_line_eci)
    arm_m = nozzle_distance_m(a, u_hat, d[2])
    lever = arm_m * force_n
    if flown.tilt_rsw is None:  # the dumping law
        tilt = law_tilt(a, state, u_hat, c @ other_eci, flown.on_fraction * ctx.step_s, lever)
    else:  # the controller's planned tilt (control.mpc_momentum), perpendicular to the line
        planned = jnp.stack([flown.tilt_rsw[1], -flown.tilt_rsw[2], -flown.tilt_rsw[0]])
        tilt = planned - jnp.dot(planned, u_hat) * u_hat
    length = jnp.linalg.norm(tilt)
    sin_max = jnp.sin(a["dump_angle_max_rad"])
    tilt = tilt * jnp.where(length > sin_max, sin_max / jnp.where(length > 0, length, 1.0), 1.0)
    tilt = jnp.where(firing & (lever > 0), tilt, 0.0)
    cos = jnp.sqrt(1.0 - jnp.sum(tilt * tilt))
    u_new_b = u_b + size * ((cos - 1.0) * u_hat + tilt)  # exactly u_b without a tilt
    shift = com_shift_body_m(params, ctx.mass_kg)
    torque = flown.on_fraction * (-arm_m * force_n * jnp.cross(u_hat, tilt)
                                  - jnp.cross(shift, flown.thrust_n * u_new_b))
    cross_n = flown.on_fraction * force_n * jnp.linalg.norm(tilt)
    direction = jnp.stack([-u_new_b[2], u_new_b[0], -u_new_b[1]])
    state = state._replace(thrust_torque_body_nm=torque, thrust_start_eci_nm=c.T @ torque, cross_force_n=cross_n,
                           line_eci=jnp.where(firing, u_eci, state.line_eci), other_line_eci=other_eci)
    planned = flown.planned_direction_rsw  # the tilt is planned: a filter is told it (``Thrust``)
    planned = None if planned is None else planned + (direction - d)
    return state, flown._replace(direction_rsw=direction, tilt_rsw=None, planned_direction_rsw=planned)


def nozzle_distance_m(attitude: dict, u_hat, w_component):
    """L (m): the nozzle's distance behind the centre of mass on the thrust line along ``u_hat`` (body axes).  Without
    an arm's reach (``attitude.thrust_reach_m`` = 0) the common ``attitude.thrust_arm_m``.  With it, the arm whose
    base b is on the side the burn pushes away from (north for a burn that pushes south, ``w_component`` < 0:
    Li 2022's thruster 1) puts its nozzle r_n = -L u_hat at its reach rho from b: |-L u_hat - b| = rho, so
    L = -(u_hat . b) + sqrt((u_hat . b)^2 - |b|^2 + rho^2), the root farther out (the nozzle beyond the base, away
    from the body); where the line passes farther than rho from b (no root) the nearest point, L = -(u_hat . b), a
    marked simplification (the arm cannot put that line through the centre of mass)."""
    reach = attitude["thrust_reach_m"]
    base = jnp.where(w_component < 0, attitude["thrust_base_north_m"], attitude["thrust_base_south_m"])
    along = jnp.dot(u_hat, base)
    room = along * along - jnp.dot(base, base) + reach * reach
    reached = room > 0  # (the double where keeps a derivative through the unused branch finite)
    mounted = -along + jnp.where(reached, jnp.sqrt(jnp.where(reached, room, 1.0)), 0.0)
    return jnp.where(reach > 0, mounted, attitude["thrust_arm_m"])


def law_tilt(attitude: dict, state: Wheels, u_hat, u_other_body, firing_s, lever_nm):
    """[3] the dumping law's tilt s of a line along ``u_hat`` (body axes; docs/momentum.md, "The derivation"),
    before the limit: the torque that takes the measured momentum toward the two-burn remainder over the step's
    firing time ``firing_s``, divided by the lever L F (``lever_nm``)."""
    h_m = state.h_body_nms + state.error_nms
    left = remainder_nms(h_m, u_hat, u_other_body, attitude["dump_transient_fraction"] * attitude["wheel_capacity_nms"])
    fraction = dumping_fraction(attitude["dump_gain_per_s"], firing_s)  # over the firing time, toward ``left``
    wanted = -fraction * (h_m - left) / jnp.where(firing_s > 0, firing_s, 1.0)  # torque while firing, _|_ u_hat
    return jnp.cross(u_hat, wanted) / jnp.where(lever_nm > 0, lever_nm, 1.0)


def remainder_nms(h, u_hat, u_other, bound_nms):
    """[3] the momentum a burn along ``u_hat`` leaves in the wheels under the two-burn allocation: a tilt's torque
    is perpendicular to u_hat, so what is left has h's component along u_hat; of those, the least that the next
    burn (along the line ``u_other``, the burn before this one: the planners fire the same thruster at the same
    node each orbit) can then empty, r . u_other = 0, is r_2 = (h . u) (u - c u_o) / (1 - c^2), c = u . u_o (the
    least-norm solution of r . u = h . u, r . u_o = 0).  Its norm is |h . u| / sin(theta), theta the angle between
    the lines: where it would exceed ``bound_nms`` (``attitude.dump_transient_fraction`` of the capacity) the
    remainder goes only part of the way from the one-burn least squares r_1 = (h . u) u (both have
    r . u = h . u; r_2 - r_1 is perpendicular to u, so |r|^2 = |r_1|^2 + lambda^2 |r_2 - r_1|^2 fixes lambda);
    with no other line yet, or lines within 3 deg of parallel, r_1."""
    along = jnp.dot(h, u_hat)
    one = along * u_hat
    c = jnp.dot(u_hat, u_other)
    sin2 = 1.0 - c * c
    usable = (jnp.dot(u_other, u_other) > 0.5) & (sin2 > np.sin(np.radians(3.0)) ** 2)
    two = along * (u_hat - c * u_other) / jnp.where(usable, sin2, 1.0)
    step_to = two - one
    room = jnp.sqrt(jnp.maximum(bound_nms ** 2 - jnp.dot(one, one), 0.0))
    span = jnp.linalg.norm(step_to)
    lam = jnp.clip(room / jnp.where(span > 0, span, 1.0), 0.0, 1.0)
    return jnp.where(usable, one + lam * step_to, one)


def estimate(params, state: Wheels, told):
    """What the controller is told at a cycle start: ``told.states[WHEEL_MOMENTUM]``, the measured wheel momentum
    [3] (N m s, body axes: h_w plus this cycle's error, as the dumping law reads it), and ``told.states[DUMPING]``,
    how the thrust line may tilt to unload them (``states.base``)."""
    a = params.states[NAME]
    dumping = {key: a[key] for key in ("thrust_arm_m", "dump_angle_max_rad", "wheel_capacity_nms")}
    return told._replace(states={**told.states, WHEEL_MOMENTUM: state.h_body_nms + state.error_nms,
                                 DUMPING: dumping})


def tells(table: dict) -> tuple[str, ...]:
    """The wheels' momentum always, and a tilt to unload them where ``dump_angle_max_deg`` allows one."""
    return (WHEEL_MOMENTUM, DUMPING) if table["dump_angle_max_deg"] > 0 else (WHEEL_MOMENTUM,)


def com_shift_body_m(params, mass_kg):
    """dc [3]: the centre of mass less the run's starting one, body axes, with the propellant used (m0 - m) gone
    from ``attitude.tank_offset_body_m``."""
    m0 = params.initial.mass_kg
    return -(m0 - mass_kg) / mass_kg * params.states[NAME]["tank_offset_body_m"]


def step(params, state: Wheels, ctx: StepContext):
    """One integration step: the torques at the step's start (carried from the step before) and end, their
    impulse (trapezoid rule; the thrust's, held in body axes over the step, turned with the body) added to
    H_eci, the wheels' momentum in body axes at the end."""
    a, fm = params.states[NAME], ctx.force_model
    inertia = inertia_matrix(a["inertia_kg_m2"])
    end_env = jax.tree_util.tree_map(lambda x: x[2], ctx.env)
    srp1, gg1, c1 = torques(a, inertia, ctx.r_end_eci_m, ctx.v_end_eci_mps, end_env, fm,
                            com_shift_body_m(params, ctx.mass_kg))
    srp0, gg0 = state.srp_eci_nm, state.gravity_gradient_eci_nm
    half = ctx.step_s / 2
    external = half * ((srp0 + gg0) + (srp1 + gg1))
    h_total = state.h_total_eci_nms + external + half * (state.thrust_start_eci_nm + c1.T @ state.thrust_torque_body_nm)
    h_end = wheel_momentum_body_nms(h_total, c1, inertia @ body_rate_rad_s(ctx.r_end_eci_m, ctx.v_end_eci_mps))
    above = jnp.max(jnp.abs(state.h_body_nms)) > HIGH_FRACTION * a["wheel_capacity_nms"]
    new = state._replace(
        h_total_eci_nms=h_total, h_body_nms=h_end, srp_eci_nm=srp1, gravity_gradient_eci_nm=gg1,
        srp_impulse_nms=state.srp_impulse_nms + half * (jnp.linalg.norm(srp0) + jnp.linalg.norm(srp1)),
        gravity_gradient_impulse_nms=state.gravity_gradient_impulse_nms
        + half * (jnp.linalg.norm(gg0) + jnp.linalg.norm(gg1)),
        steps_above=state.steps_above + above,
        thrust_impulse_nms=state.thrust_impulse_nms + ctx.step_s * jnp.linalg.norm(state.thrust_torque_body_nm),
        cross_dv_mps=state.cross_dv_mps + ctx.step_s * state.cross_force_n / ctx.mass_kg,
        external_eci_nms=state.external_eci_nms + external)
    return new, WheelStep(state.h_body_nms)


def torques(attitude: dict, inertia, r_eci_m, v_eci_mps, env, fm, com_shift_body_m=0.0):
    """(tau_srp, tau_gg) [3] each, ECI axes, N m, at one instant (``env``), and the ECI -> body rotation [3, 3];
    the centre of pressure's offset taken from the centre of mass moved by ``com_shift_body_m``."""
    c = nadir_frame(r_eci_m, v_eci_mps)
    offset = c.T @ (attitude["srp_offset_body_m"] - com_shift_body_m) + \
        array_frame(r_eci_m, v_eci_mps, env.r_sun_eci_m).T @ attitude["srp_offset_array_m"]
    srp = jnp.cross(offset, srp_force_eci_n(r_eci_m, env, fm))
    gg = c.T @ gravity_gradient_torque_body(c @ r_eci_m, inertia, fm.mu_m3_s2)
    return srp, gg, c


def summary(params, start: Wheels, end: Wheels, steps: WheelStep) -> WheelCycle:
    """The cycle's record: per-wheel extremes over its step starts and its end, the running totals."""
    h = jnp.concatenate([steps.h_nms, end.h_body_nms[None]])
    return WheelCycle(jnp.max(jnp.abs(h), axis=0), start.h_body_nms, end.h_body_nms, end.srp_impulse_nms,
                      end.gravity_gradient_impulse_nms, end.steps_above, end.thrust_impulse_nms, end.cross_dv_mps,
                      end.external_eci_nms)


def metrics(params, cycles: WheelCycle, n_steps_total: int, run_s: float):
    """({name: []}, saturated): the largest wheel momentum over the run and over its last year (365.25 days of
    cycles, the whole run when shorter: what a mission of several years holds once the first year's transient has
    passed; the per-cycle records give any year's), two rates per day (``DESCRIPTIONS``), the torque impulse per
    source (SRP, gravity gradient, thrust: the dumped momentum and the centre of mass's shift), the Delta-V the
    dumping tilts put across the plan, the fraction of step starts above 80 % of capacity; saturated where a wheel
    exceeded its capacity (``attitude.wheel_capacity_nms``) at any step start or cycle end.

    The rates are per cycle, one orbit each, so the orbit-periodic part of the momentum drops out of both; the net
    change over the whole run would not do (it cancels as the Sun goes round: 0.005 N m s a day over a year whose
    wheels saturated on day 8).  The external torques' rate is their net impulse over each cycle (ECI), its norm
    averaged over the cycles: what the wheels would store a day without dumping.  The wheels' growth is the
    largest net change of h_w over one cycle (body axes, one orbit apart): what they stored on their worst day,
    dumping included."""
    peak = jnp.max(cycles.max_abs_nms)
    n_cycles = cycles.max_abs_nms.shape[0]
    cycle_s = run_s / n_cycles
    year = min(n_cycles, int(np.ceil(365.25 * SECONDS_PER_DAY * n_cycles / run_s - 1e-9)))  # the last year's cycles
    external = jnp.diff(cycles.external_eci_nms, axis=0, prepend=jnp.zeros_like(cycles.external_eci_nms[:1]))
    out = {
        "max_wheel_momentum_nms": peak,
        "max_wheel_momentum_last_year_nms": jnp.max(cycles.max_abs_nms[n_cycles - year:]),
        "external_momentum_per_day_nms": jnp.sum(jnp.linalg.norm(external, axis=-1)) * SECONDS_PER_DAY / run_s,
        "max_wheel_growth_per_day_nms": jnp.max(jnp.linalg.norm(cycles.end_nms - cycles.start_nms, axis=-1))
        * SECONDS_PER_DAY / cycle_s,
        "srp_torque_impulse_nms": cycles.srp_impulse_nms[-1],
        "gravity_gradient_impulse_nms": cycles.gravity_gradient_impulse_nms[-1],
        "time_above_80pct_capacity_fraction": cycles.steps_above[-1] / n_steps_total,
        "thrust_torque_impulse_nms": cycles.thrust_impulse_nms[-1],
        "dump_cross_dv_mps": cycles.cross_dv_mps[-1],
    }
    return out, peak > params.states[NAME]["wheel_capacity_nms"]


def columns(cycles: WheelCycle) -> dict:
    """The per-cycle series in edge units: h_w at each cycle end and the largest |h_w| per wheel (N m s)."""
    out = {}
    for k, axis in enumerate("xyz"):  # [..., k]: one sample's records or a batch's (a sweep's, traced)
        out[f"wheel_{axis}_nms"] = cycles.end_nms[..., k]
        out[f"wheel_max_abs_{axis}_nms"] = cycles.max_abs_nms[..., k]
    return out


MODEL = StateModel(NAME, init, step, summary, metrics, cycle=cycle, status=SATURATED, columns=columns,
                   thrust=thrust, estimate=estimate, columns_per_cycle=6)

DESCRIPTIONS = {
    "max_wheel_momentum_nms": "largest |momentum| of any reaction wheel at any step start (body axes)",
    "max_wheel_momentum_last_year_nms": "the same over the run's last 365.25 days (the whole run when shorter)",
    "external_momentum_per_day_nms": "secular rate of the external torques (SRP at its offset, gravity gradient): "
                                     "the norm of their net impulse over each cycle (ECI), averaged over the "
                                     "cycles, per day: what the wheels store a day without dumping",
    "max_wheel_growth_per_day_nms": "largest net change of the wheels' momentum over any one cycle, |h(end) - "
                                    "h(start)| (body axes, one orbit apart), per day: their worst day, dumping "
                                    "included",
    "srp_torque_impulse_nms": "integral of |SRP torque| over the run (centre-of-pressure offset)",
    "gravity_gradient_impulse_nms": "integral of |gravity-gradient torque| over the run",
    "time_above_80pct_capacity_fraction": "fraction of the step starts with a wheel above 80 % of its capacity",
    "thrust_torque_impulse_nms": "integral of |thrust torque| over the run (dumping tilts, the centre of mass's "
                                 "shift): the momentum the thrusters moved",
    "dump_cross_dv_mps": "Delta-V the dumping tilts put across the planned thrust directions over the run",
    **{f"wheel_{axis}_nms": f"the {axis} wheel's momentum at the cycle end, body axes" for axis in "xyz"},
    **{f"wheel_max_abs_{axis}_nms": f"largest |momentum| of the {axis} wheel within the cycle" for axis in "xyz"},
}


def within_capacity(params, metrics: dict):
    """The tuner's constraint of the wheels: (largest |h| / capacity)^2 - 1, <= 0 within the capacity."""
    return (metrics["max_wheel_momentum_nms"] / params.states[NAME]["wheel_capacity_nms"]) ** 2 - 1.0


def validate(config: dict) -> None:
    """Checks across the ``[attitude]`` table at load (``ValueError`` naming the key), where the wheels are
    carried: the inertia tensor is physical (positive definite, each
    principal moment at most the sum of the other two); an SRP offset needs SRP (``forces.srp`` and
    ``spacecraft.srp_area_m2`` > 0); a dumping tilt needs a thrust arm."""
    table = config["attitude"]
    if not table["wheels"]:
        return  # every other key at its default (``Part.switch``)
    inertia = np.asarray(inertia_matrix(np.asarray(table["inertia_kg_m2"])))
    moments = np.linalg.eigvalsh(inertia)
    if moments[0] <= 0 or moments[2] > moments[0] + moments[1] * (1 + 1e-12):
        raise ValueError(f"attitude.inertia_kg_m2: not a physical inertia tensor (principal moments "
                         f"{', '.join(f'{m:g}' for m in moments)} kg m^2: each must be > 0 and at most the sum of "
                         f"the other two), got {table['inertia_kg_m2']!r}")
    if table["thrust_reach_m"] > 0 and not any(table["thrust_base_north_m"] + table["thrust_base_south_m"]):
        raise ValueError(f"attitude.thrust_reach_m: the arms' reach is measured from their bases "
                         f"(attitude.thrust_base_north_m, thrust_base_south_m), none given; got reach "
                         f"{table['thrust_reach_m']:g} m")
    if table["dump_angle_max_deg"] > 0 and table["thrust_arm_m"] == 0 and table["thrust_reach_m"] == 0:
        raise ValueError(f"attitude.thrust_arm_m: a dumping tilt (attitude.dump_angle_max_deg = "
                         f"{table['dump_angle_max_deg']:g}) needs a thrust arm > 0, got 0")
    has_srp = config["forces"]["srp"] and config["spacecraft"]["srp_area_m2"] > 0
    for key in ("srp_offset_body_m", "srp_offset_array_m"):
        if any(table[key]) and not has_srp:
            raise ValueError(f"attitude.{key}: an SRP torque needs SRP (forces.srp = true and "
                             f"spacecraft.srp_area_m2 > 0), got {table[key]!r}")


PART = Part(NAME, table="attitude", fields=FIELDS, select=lambda table: MODEL if table["wheels"] else None,
            switch="wheels",
            validate=validate, statuses=(SATURATED,), descriptions=DESCRIPTIONS, constraints=(Constraint("wheels", within_capacity, SATURATED),),
            figures="geojax.plots.parts:wheel_figures", model=MODEL, tells=tells,
            tells_how={WHEEL_MOMENTUM: "attitude.wheels = true",
                       DUMPING: "attitude.wheels = true with attitude.dump_angle_max_deg > 0"})
