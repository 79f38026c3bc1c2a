"""Zone north-south station keeping with one manipulator-mounted electric thruster (Ye 2022, Secs. 2-3).

Once per cycle (one sidereal day) the planner

1. filters the mean inclination vector (eqs. (4)-(24)): the loop's one-cycle
   mean (the semi-diurnal terms removed, eq. (24)) less, by
   ``perturbation_term``, nothing ("semi_monthly"), the Moon's semi-monthly
   term of eq. (16) ("semi_annual", eq. (23)), or that and the Sun's
   semi-annual term of eq. (13) ("nutation", eq. (22));
2. forms the inclination vector for control, eq. (56): the filtered vector
   carried to the burn centre by the natural drift d of the filtered vector
   over the cycle, less the target moved back by d / 2 (Fig. 13), with the
   time to the burn centre of eq. (57);
3. classifies it into the six zones of Fig. 6 (normal and working conditions
   1-5, ``zone``) and takes the zone's control amount and burn centre
   (eqs. (45)-(55), Table 1; ``control_vector``);
4. flies one burn, centred on the burn-centre right ascension, whose duration
   removes the control amount with the arc loss of eqs. (34)-(38)
   (``burn_duration_s``), between t_min and t_max.

Conventions.  The paper's inclination vector is i (cos Omega, sin Omega) in
radians; geojax's mean elements carry MEE (h, k) = tan(i / 2) (cos, sin), so
the planner works in 2 (h, k) (equal to O(i^3), 1e-10 rad at 0.1 deg).
A north-pointing Delta-V v_n at right ascension L changes the vector by
(v_n / V_s) (cos L, sin L) (``control.effects``), so a control amount c is
removed by a burn centred at atan2(-c_y, -c_x): the quadrant of eq. (46)
(eq. (29) prints the opposite node, which is that of a south-pointing
Delta-V).  The single thruster on the manipulator fires north (Sec. 3.2,
"producing a northward thrust").

Readings of the paper (each stated where it is coded):

* The zone boundaries of Fig. 6 and Table 1 are printed inconsistently
  (eq. (45) asks delta_i_y > i_min, eq. (47) compares with i_max cos
  Delta_lambda_max, Table 1 swaps rows); ``zone`` uses the geometry of the
  figure's text: the SK sector |c_x| < c_y tan Delta_lambda_max, the circles
  C1 (radius i_min) and C2 (i_max), the horizontals through A (y = i_max cos)
  and C (y = i_min cos), the verticals through C and D (|x| = i_min sin).
  The six zones then tile the plane, and the control amount is continuous
  across every boundary but the vertical ones of working condition 3.
* Working condition 3 takes the point of C1 with the control vector's x
  (Table 1, its second row): the x deviation is removed, y gets the least.
* The natural drift d and its direction theta_ni are those of the filtered
  vector in the full force model (the uncontrolled reference of
  ``control.predictor`` over the cycle), not eq. (7): eq. (7) is the paper's
  drift model; ``tests/test_zone_nssk.py`` checks one against the other.
* t_min, t_max and Delta_lambda_max are given (Table 3), not derived from
  eqs. (42)-(44); the checks of eqs. (40)-(41) are made at load (``validate``).
  Where the loop carries the reaction wheels with a dumping tilt
  (``geojax.states.momentum``), eq. (40)'s t_dump is no longer the constant
  3207 s but what the measured momentum asks (``dump_time_s``): each cycle's
  least firing time is max(t_min, t_dump), at most t_max
  (``t_dump_from_momentum = false``: the constant alone, as the paper).

East-west keeping is outside the paper.  Here the daily burn carries it: the
thrust is tilted in-plane by at most ``tilt_max_deg`` (10 deg by default) and
the burn lengthened by 1 / cos(tilt) so that its north-south part is kept.
The tangential part sets the mean drift to -(lambda - lambda_station) / tau
(``lon_time_constant_days``) after the cycle's natural drift change
(``control.effects``: d lambda_dot = -3 v_t / R_s).  The eccentricity is not
controlled (the paper's satellite does not either); the longitude excursions
are reported by the loop's metrics.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp

from geojax.control import burn_metrics
from geojax.control import burns as burns_mod
from geojax.control.base import ARM_LIMIT_KEYS, Controller, Spec, stateless_init
from geojax.control.effects import R_SYNC_M, V_SYNC_MPS
from geojax.control.qffc import BurnPair
from geojax.physics.constants import MU_MOON_M3_S2, MU_SUN_M3_S2, OMEGA_EARTH_RAD_S, SECONDS_PER_DAY, SIDEREAL_DAY_S
from geojax.physics.elements import wrap_angle
from geojax.states.base import DUMPING, WHEEL_MOMENTUM
from geojax.params import NUMBER, REQUIRED, Field, degrees

T_DUMP_S = 3207.0  # Ye 2022, Sec. 4: the least daily firing time the momentum dumping needs
N0_RAD_S = OMEGA_EARTH_RAD_S  # n_0 of eqs. (31)-(39): the synchronous mean motion

# (Sun, Moon) weights of the long-period terms removed, by Table 3's "perturbation term" (eqs. (22)-(24)).
PERTURBATION_TERMS = {"nutation": (1.0, 1.0), "semi_annual": (0.0, 1.0), "semi_monthly": (0.0, 0.0)}
ZONE_NAMES = ("normal", "one", "two", "three", "four", "five")

# What ``geojax.scenario`` holds a scenario of this law to (``control.base``): one thruster on a manipulator,
# not Li's arms (its burns' shortest duration and attitude error are ``control.burns``' and read).
THRUSTERS = (1, "one thruster on a manipulator, Ye 2022 Sec. 3.2")
UNREAD = ARM_LIMIT_KEYS

FIELDS = {
    # Which periodic terms the mean inclination keeps (Table 3): the Sun's semi-annual and the Moon's
    # semi-monthly terms are removed for "nutation", the Moon's for "semi_annual", none for "semi_monthly".
    "perturbation_term": Field(str, "nutation", choices=tuple(PERTURBATION_TERMS), si="removed_terms",
                               to_si=lambda name: PERTURBATION_TERMS[name]),
    "t_max_s": Field(NUMBER, REQUIRED, lower=0.0, upper=SIDEREAL_DAY_S / 2, si="t_max_s"),
    "t_min_s": Field(NUMBER, REQUIRED, lower=0.0, upper=SIDEREAL_DAY_S / 2, si="t_min_s"),
    # Eq. (40): t_min > t_dump, checked at load.
    "t_dump_s": Field(NUMBER, T_DUMP_S, lower=0.0, lower_inclusive=True, upper=SIDEREAL_DAY_S / 2),
    # Where the loop carries the wheels with a dumping tilt: each cycle's least firing time is also what the
    # measured momentum asks (``dump_time_s``); false: the constant t_dump_s alone, as the paper.
    "t_dump_from_momentum": Field(bool, True, si="t_dump_from_momentum"),
    # Half-width of the SK sector around +y (Fig. 5, eq. (26)), Table 3.
    "dlambda_max_deg": Field(NUMBER, REQUIRED, lower=0.0, upper=90.0, si="dlambda_max_rad", to_si=degrees),
    # East-west (our choice, module docstring): in-plane tilt of the daily burn and the longitude time constant.
    "tilt_max_deg": Field(NUMBER, 10.0, lower=0.0, lower_inclusive=True, upper=90.0, si="tilt_max_rad",
                          to_si=degrees),
    "lon_time_constant_days": Field(NUMBER, 5.0, lower=1.0, upper=1e4, si="lon_tau_s", to_si=SECONDS_PER_DAY),
}


# --- the checks of eqs. (40)-(41), at load ------------------------------------------------------------------

def validate(config: dict) -> None:
    """t_min <= t_max, t_min >= t_dump (eq. (40)), and a t_max that beats the largest daily drift (eq. (41))."""
    ctl, thrust_n = config["controller"], config["thrusters"]["thrust_n"]
    t_min, t_max, t_dump = ctl["t_min_s"], ctl["t_max_s"], ctl["t_dump_s"]
    if t_min > t_max:
        raise ValueError(f"controller.t_min_s: must be <= controller.t_max_s = {t_max:g}, got {t_min:g}")
    if t_min < t_dump:
        raise ValueError(f"controller.t_min_s: must be >= controller.t_dump_s = {t_dump:g} (momentum dumping, "
                         f"Ye 2022 eq. (40)), got {t_min:g}")
    weights = PERTURBATION_TERMS[ctl["perturbation_term"]]
    d_max = max_daily_drift_rad(*weights)
    reach = (float(burn_inclination_rad(t_max, config["spacecraft"]["mass_kg"], thrust_n))
             * math.cos(math.radians(ctl["dlambda_max_deg"])))
    if reach <= d_max:
        raise ValueError(f"thrusters.thrust_n: {thrust_n:g} N for controller.t_max_s = {t_max:g} s moves the "
                         f"inclination {math.degrees(reach):.3g} deg/day along the drift, less than its largest "
                         f"daily drift {math.degrees(d_max):.3g} deg/day (Ye 2022 eq. (41))")


def max_daily_drift_rad(sun_removed: float, moon_removed: float) -> float:
    """d_max per solar day (rad): the largest drift of eq. (7) plus the rates of the long-period terms kept.

    Eq. (7) is at most hypot(22.79 + 2.59, 3.5) 1e-4 deg/day over the Moon's nodal cycle; a kept term of
    amplitude A and period pi / n_k (eqs. (14), (17)) adds at most 2 n_k A.
    """
    nutation = math.radians(math.hypot(22.79 + 2.59, 3.5) * 1e-4)
    sun = 2 * SUN_RATE_RAD_S * SUN_AMPLITUDE_RAD * SECONDS_PER_DAY
    moon = 2 * MOON_RATE_RAD_S * MOON_AMPLITUDE_RAD * SECONDS_PER_DAY
    return nutation + (1 - sun_removed) * sun + (1 - moon_removed) * moon


# Eqs. (14) and (17) with mean orbits: the Sun at 1 AU, 23.44 deg; the Moon at 384400 km, its largest
# equatorial inclination 23.44 + 5.14 deg.  Only ``max_daily_drift_rad`` uses them (the filter uses the ephemeris).
SUN_RATE_RAD_S = 2 * math.pi / (365.2564 * SECONDS_PER_DAY)
MOON_RATE_RAD_S = 2 * math.pi / (27.3217 * SECONDS_PER_DAY)
SUN_AMPLITUDE_RAD = 3 / 8 * SUN_RATE_RAD_S / OMEGA_EARTH_RAD_S * math.sin(math.radians(23.44))
MOON_AMPLITUDE_RAD = (3 / 8 * MU_MOON_M3_S2 / 3.844e8**3 / (OMEGA_EARTH_RAD_S * MOON_RATE_RAD_S)
                      * math.sin(math.radians(28.58)))


# --- the mean-inclination filter (eqs. (4)-(24)) ----------------------------------------------------------

def long_period_terms_rad(r_eci_m, v_eci_mps, mu_body_m3_s2):
    """The long-period oscillation (amp(i_x), amp(i_y)) [2] of a third body, eqs. (13) and (16) (rad).

    ``r_eci_m``, ``v_eci_mps`` [3]: the body's geocentric position and velocity, from which its equatorial
    orbit (i_k, Omega_k, lambda_k of eq. (3)) and rate n_k are taken; the coefficient n_k^2 of eq. (4) is
    the body's mu_k / r_k^3 (the Moon's own mass, not the Earth-Moon n_m^2).  Eq. (16) integrated with
    i_k, Omega_k and r_k constant over the period pi / n_k:

        amp(i_y) = K (-sin i sin Omega cos 2 lambda - 1/2 sin 2i cos Omega sin 2 lambda)
        amp(i_x) = K (-sin i cos Omega cos 2 lambda + 1/2 sin 2i sin Omega sin 2 lambda),
        K = 3/8 mu_k / (r_k^3 omega_e n_k);

    with Omega_s = 0 it is eq. (13).
    """
    h = jnp.cross(r_eci_m, v_eci_mps)
    r = jnp.linalg.norm(r_eci_m)
    h_norm = jnp.linalg.norm(h)
    incl = jnp.arccos(h[2] / h_norm)
    node = jnp.arctan2(h[0], -h[1])
    lam = jnp.arctan2(r_eci_m[2] / jnp.sin(incl), r_eci_m[0] * jnp.cos(node) + r_eci_m[1] * jnp.sin(node))
    rate = h_norm / r**2
    k = 3 / 8 * mu_body_m3_s2 / (r**3 * OMEGA_EARTH_RAD_S * rate)
    s, s2, c2l, s2l = jnp.sin(incl), jnp.sin(2 * incl), jnp.cos(2 * lam), jnp.sin(2 * lam)
    amp_y = k * (-s * jnp.sin(node) * c2l - 0.5 * s2 * jnp.cos(node) * s2l)
    amp_x = k * (-s * jnp.cos(node) * c2l + 0.5 * s2 * jnp.sin(node) * s2l)
    return jnp.stack([amp_x, amp_y])


def filtered_inclination_rad(hk_mean, removed_terms, r_sun_m, v_sun_mps, r_moon_m, v_moon_mps):
    """The mean inclination vector (i_x, i_y) [2] (rad, i (cos, sin Omega)) of eqs. (22)-(24).

    ``hk_mean`` [2]: the one-cycle mean MEE (h, k) (the semi-diurnal terms are gone, eq. (24));
    ``removed_terms`` [2]: weights (Sun, Moon) of the long-period terms taken out (``PERTURBATION_TERMS``).
    """
    sun = long_period_terms_rad(r_sun_m, v_sun_mps, MU_SUN_M3_S2)
    moon = long_period_terms_rad(r_moon_m, v_moon_mps, MU_MOON_M3_S2)
    return 2 * hk_mean - removed_terms[0] * sun - removed_terms[1] * moon


def drift_model_eq7_rad_per_day(t_tt_s):
    """(di_x/dt, di_y/dt) [2] of eq. (7) (rad per solar day) with Omega_sm of eq. (8) (t in TT s since J2000)."""
    t = t_tt_s / (36525.0 * SECONDS_PER_DAY)
    node = jnp.radians(125.04456 - 1934.1362 * t + 0.0020767 * t**2)
    return jnp.radians(1e-4) * jnp.stack([-3.5 * jnp.sin(node), 22.79 + 2.59 * jnp.cos(node)])


# --- zones and control amounts (eqs. (25)-(57), Fig. 6, Table 1) -------------------------------------------

def arc_efficiency(arc_rad):
    """eta = sin(theta / 2) / (theta / 2), eq. (34) (1 at theta = 0)."""
    half = 0.5 * arc_rad
    safe = jnp.where(half == 0, 1.0, half)
    return jnp.where(half == 0, 1.0, jnp.sin(safe) / safe)


def burn_duration_s(di_rad, mass_kg, thrust_n):
    """Firing time that turns the inclination vector by ``di_rad``, with the arc loss: eqs. (33)-(38).

    Without arc loss Delta t = m V_s di / F (eqs. (31)-(33)); the arc theta = n_0 Delta t fires at
    efficiency eta(theta) (eq. (34)), so it is stretched to Delta t / eta(theta) (eqs. (36)-(38)): one
    step of the fixed point t = Delta t / eta(n_0 t), short by 0.03 % at t = 5700 s and 2 % at 14400 s
    (``tests/test_zone_nssk.py`` integrates the arc).
    """
    dt = mass_kg * V_SYNC_MPS * di_rad / thrust_n
    return dt / arc_efficiency(N0_RAD_S * dt)


def burn_inclination_rad(duration_s, mass_kg, thrust_n):
    """The turn of the inclination vector by a north burn of ``duration_s`` centred on its node (eq. (34))."""
    return thrust_n * duration_s / (mass_kg * V_SYNC_MPS) * arc_efficiency(N0_RAD_S * duration_s)


def zone(delta_rad, i_min_rad, i_max_rad, dlambda_max_rad):
    """The working condition of the control vector ``delta_rad`` [2] (0 normal, 1-5 working conditions one-five).

    Fig. 6: the SK sector |x| < y tan(Delta_lambda_max) holds the normal zone (i_min <= |delta| <= i_max,
    eq. (45)) and working condition 1 (|delta| > i_max, eq. (47)); outside it, working condition 4 lies above
    y = i_max cos (eqs. (52)), 2 between that and y = i_min cos (eq. (49)), 5 below it with |x| > i_min sin
    (eq. (54)); working condition 3 is the rest (the paper's exclusion method): the strip |x| <= i_min sin
    below C1.
    """
    x, y = delta_rad[0], delta_rad[1]
    radius = jnp.hypot(x, y)
    cos_l, sin_l = jnp.cos(dlambda_max_rad), jnp.sin(dlambda_max_rad)
    in_sector = (y > 0) & (jnp.abs(x) * cos_l <= y * sin_l)
    inside = jnp.where(radius > i_max_rad, 1, jnp.where(radius >= i_min_rad, 0, 3))
    outside = jnp.where(y >= i_max_rad * cos_l, 4, jnp.where(y >= i_min_rad * cos_l, 2,
                                                             jnp.where(jnp.abs(x) > i_min_rad * sin_l, 5, 3)))
    return jnp.where(in_sector, inside, outside)


def control_vector(delta_rad, i_min_rad, i_max_rad, dlambda_max_rad):
    """(zone, control amount c [2]): the change -c the burn makes to the inclination vector (Table 1).

    normal: c = delta (eq. (46)); one: i_max along delta (eq. (48)); two: on the sector's edge, with the
    y deviation removed, |c| = delta_y / cos (eqs. (50)-(51)); three: the point of C1 with delta's x
    (Table 1); four: A or B, i_max on the edge (eq. (53)); five: C or D, i_min on the edge (eq. (55)).
    """
    x, y = delta_rad[0], delta_rad[1]
    cos_l, sin_l = jnp.cos(dlambda_max_rad), jnp.sin(dlambda_max_rad)
    w = zone(delta_rad, i_min_rad, i_max_rad, dlambda_max_rad)
    edge = jnp.stack([jnp.where(x < 0, -sin_l, sin_l), cos_l])
    radius = jnp.maximum(jnp.hypot(x, y), 1e-30)
    x3 = jnp.clip(x, -i_min_rad * sin_l, i_min_rad * sin_l)
    amounts = jnp.stack([
        delta_rad,
        i_max_rad * delta_rad / radius,
        y / cos_l * edge,
        jnp.stack([x3, jnp.sqrt(jnp.maximum(i_min_rad**2 - x3**2, 0.0))]),
        i_max_rad * edge,
        i_min_rad * edge,
    ])
    return w, amounts[w]


class ZonePlan(NamedTuple):
    """A cycle's burn as flown and what the planner saw."""

    flown: burns_mod.BurnPlan
    zone: jnp.ndarray  # [] int, 0 normal, 1-5 working conditions
    i_filtered_rad: jnp.ndarray  # [2] filtered mean inclination vector at the cycle start (paper's i vector)
    delta_rad: jnp.ndarray  # [2] inclination vector for control, eq. (56)
    control_rad: jnp.ndarray  # [2] control amount
    drift_rad: jnp.ndarray  # [2] natural drift of the filtered vector over the cycle
    burn_ns_s: jnp.ndarray  # [] north-south firing time (arc loss included, before the in-plane stretch)
    tilt_rad: jnp.ndarray  # [] in-plane tilt of the thrust (east-west)


def plan_cycle(params, estimate, context):
    """The zone planner's (ZonePlan fields but ``flown``, BurnPair) of one cycle (module docstring, steps 1-4)."""
    c = params.controller
    env, ref = context.env, context.reference
    step_s, cycle_s = context.step_s, context.cycle_s
    mass, thrust_n = estimate.mass_kg, params.thrusters["thrust_n"]

    def filtered(hk, i_step, stage):
        at = lambda r: (r[i_step, stage], (r[i_step, 2] - r[i_step, 0]) / step_s)  # noqa: E731
        return filtered_inclination_rad(hk, c["removed_terms"], *at(env.r_sun_eci_m), *at(env.r_moon_eci_m))

    i_now = filtered(estimate.mean[4:6], 0, 0)
    drift = filtered(ref[1, 5:7], -1, 2) - filtered(ref[0, 5:7], 0, 0)
    target = 2 * jnp.stack([params.station["ix"], params.station["iy"]])
    # Eq. (57): time from the cycle start to the nominal burn centre, the node opposite the drift direction.
    l_start = estimate.fix_mee[5]
    to_centre_s = jnp.mod(jnp.arctan2(-drift[1], -drift[0]) - l_start, 2 * jnp.pi) / (2 * jnp.pi) * cycle_s
    delta = i_now + to_centre_s / cycle_s * drift - (target - 0.5 * drift)  # eq. (56)

    t_min = c["t_min_s"]
    if WHEEL_MOMENTUM in estimate.states:  # a part tells the wheels (static): eq. (40)'s t_dump from the momentum
        asked = dump_time_s(estimate.states[DUMPING], estimate.states[WHEEL_MOMENTUM], thrust_n)
        t_min = jnp.where(c["t_dump_from_momentum"] > 0, jnp.minimum(jnp.maximum(t_min, asked), c["t_max_s"]), t_min)
    i_min = burn_inclination_rad(t_min, mass, thrust_n)
    i_max = burn_inclination_rad(c["t_max_s"], mass, thrust_n)
    w, amount = control_vector(delta, i_min, i_max, c["dlambda_max_rad"])
    burn_ns = jnp.clip(burn_duration_s(jnp.hypot(amount[0], amount[1]), mass, thrust_n), t_min, c["t_max_s"])

    tilt = tilt_rad(params, estimate, ref, cycle_s, thrust_n * burn_ns / mass)
    v_mps = thrust_n * burn_ns / (mass * jnp.cos(tilt))
    direction = jnp.stack([0.0, jnp.sin(tilt), jnp.cos(tilt)])  # RSW unit Delta-V: north, tilted along-track
    centre = jnp.arctan2(-amount[1], -amount[0])
    zero = jnp.zeros(())
    burns = BurnPair(jnp.stack([v_mps * direction, jnp.zeros(3)]), jnp.stack([v_mps, zero]),
                     jnp.stack([jnp.arctan2(-direction[1], -direction[0]), zero]),
                     jnp.stack([jnp.arcsin(-direction[2]), zero]), jnp.stack([centre, centre + jnp.pi]), zero,
                     jnp.asarray(True))
    return (w, i_now, delta, amount, drift, burn_ns, tilt), burns


def dump_time_s(dumping: dict, wheels_nms, thrust_n):
    """Eq. (40)'s t_dump from the momentum to unload (``wheels_nms``, and ``dumping``: how the thrust line may
    tilt, as a part tells them, ``states.base.DUMPING``): the firing time a tilt of at most delta_max about a
    nozzle L from the centre of mass needs to empty the measured momentum's part across the north-pointing burn,
    |h_xz| / (L F sin delta_max) (body x and z: the pitch wheel's axis y is the burn's own line, which no tilt
    reaches).  Its norm is kept by the body's turn about the pitch axis until the burn; what the torques add
    meanwhile is the next day's.  0 where no tilt is allowed."""
    capacity_nm = dumping["thrust_arm_m"] * thrust_n * jnp.sin(dumping["dump_angle_max_rad"])
    across = jnp.hypot(wheels_nms[0], wheels_nms[2])
    return jnp.where(capacity_nm > 0, across / jnp.where(capacity_nm > 0, capacity_nm, 1.0), 0.0)


def tilt_rad(params, estimate, ref, cycle_s, v_ns_mps):
    """In-plane tilt of the daily burn (east-west, our choice): the tangential Delta-V that sets the mean drift
    to -(lambda - lambda_station) / tau after the cycle's natural drift change, within +-tilt_max."""
    c = params.controller
    lon_error = wrap_angle(estimate.mean[0] - params.station["lon_rad"])
    drift_goal = -lon_error / c["lon_tau_s"]
    drift_next = estimate.mean[1] + (ref[1, 1] - ref[0, 1])
    v_t = -R_SYNC_M / 3 * (drift_goal - drift_next)
    limit = c["tilt_max_rad"]
    return jnp.clip(jnp.arctan2(v_t, v_ns_mps), -limit, limit)


def _plan(params, controller_state, estimate, context, key):
    seen, burns = plan_cycle(params, estimate, context)
    flown = burns_mod.fly(params, burns, jnp.zeros(6), jnp.asarray(1.0), estimate, context, key, arms=1)
    return ZonePlan(flown, *seen), controller_state


def _thrust(params, plan: ZonePlan, t, state, environment):
    return burns_mod.thrust(params, plan.flown, t, state, environment)


def _record(plan: ZonePlan) -> dict:
    return {**burns_mod.record(plan.flown), "zone": plan.zone, "i_filtered_rad": plan.i_filtered_rad,
            "delta_rad": plan.delta_rad, "control_rad": plan.control_rad, "drift_rad": plan.drift_rad,
            "burn_ns_s": plan.burn_ns_s, "tilt_rad": plan.tilt_rad}


# Reads the reference at the cycle's start and end boundaries (the drift of eq. (56)).
SPEC = Spec(FIELDS, validate, THRUSTERS, unread=UNREAD, bound_geometry="gimbal")  # the manipulator points anywhere
CONTROLLER = Controller(stateless_init, _plan, _thrust, SPEC, reference_cycles=2, record=_record,
                        metrics=burn_metrics.metrics)


def make(tables: list[dict]) -> Controller:
    return CONTROLLER

