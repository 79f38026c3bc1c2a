"""Flying a planned pair of burns (Li 2022, Sec. 3.2): the ``thrust`` and the records of the planners.

A planner (QFFC, FOMPC) plans two burns per cycle (``qffc.BurnPair``); this
module turns them into thrust.  Each burn is centred on its right ascension
(the orbit turns 2 pi per cycle), lasts V m / F (eq. (13)) and is not fired
when shorter than ``thrusters.min_burn_s``.  A burn that meets the Earth's
shadow is suspended and resumed until it has fired its full time (constraint
6): it runs on a clock that only advances in sunlight
(``propulsion.sunlit_clock``), with the shadow taken at the station's nominal
position (within +-0.05 deg of the satellite, a few seconds of eclipse
timing); a suspended burn that would run past the end of the cycle is cut
there.  Each burn is flown with the truth's execution errors (``physics.execution``: yaw and pitch errors added
to its planned angles, its thrust level scaled by 1 + e, drawn from the cycle's key), the burn's planned duration
kept (the plan does not know the error; the mass flow follows the thrust at the stated Isp); the thrust says what
was planned beside what is flown (``Thrust.planned_direction_rsw``) for a navigation filter.  At zero errors every
number is as without them.
Told by the faults part (``states.faults``) of the thrusters' levels, ``allocated`` picks each arm's working
thruster and ``one_arm`` flies a cycle from one arm where the other is lost (Ye 2022's one-node north-south
keeping; ``docs/contingencies.md``).
The readings the paper leaves open are switches of ``errors`` (the ablation
``studies/ablation/li_attitude_error.py`` measures each): the yaw and pitch
parts apart (``att_axes``), one draw for both burns of a
cycle (``att_shared``), and the plan knowing the error: the two magnitudes
re-fitted so that the burns flown along the perturbed directions best
reproduce the planned effect (``att_known``, ``refit_magnitudes_mps``).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control.effects import R_SYNC_M, V_SYNC_MPS, cycle_coast_s, effect_matrix
from geojax.physics.dynamics import Thrust
from geojax.physics.forces import sunlit_fraction_xyz
from geojax.physics.propulsion import (alpha_beta_bounds, arm_limits, delta_v_direction_rsw, firing_fraction,
                                      sunlit_clock)
from geojax.physics.trig import sincos, tan
from geojax.physics.execution import attitude_error_rad, magnitude_scale
from geojax.states.base import THRUSTER_LEVELS


class BurnPlan(NamedTuple):
    """A cycle's two burns as flown."""

    burns: object  # qffc.BurnPair: the planned solution
    burn_s: jnp.ndarray  # [2] firing time of each burn (0: not fired)
    clock: jnp.ndarray  # [n_steps + 1] sunlit time at every step boundary of the cycle
    clock_start: jnp.ndarray  # [2] sunlit-clock time at which each burn starts
    directions_rsw: jnp.ndarray  # [2, 3] unit velocity increments, attitude errors included
    planned_rsw: jnp.ndarray  # [2, 3] unit velocity increments as planned (no attitude error)
    prediction: jnp.ndarray  # [6] predicted mean elements at the end of the cycle, without burns
    ns_fraction: jnp.ndarray  # [] north-south correction flown, as a fraction of the QFFC's (1 for the QFFC)
    start_s: jnp.ndarray  # [2] when each burn starts firing, s from the cycle start (after the shadow it met)
    magnitude_scale: jnp.ndarray  # [2] thrust level flown over the planned (1 + the execution error)
    thrusters: jnp.ndarray | None = None  # [2] int: the thruster flying each burn (None: burn k from thruster k)


def fly(params, burns, prediction, ns_fraction, estimate, context, key, arms: int = 2) -> BurnPlan:
    """The ``BurnPlan`` of ``burns`` [qffc.BurnPair] planned at the start of the cycle of ``context``; ``arms``
    (static): Li's two arms, or 1 for one thruster (Ye 2022's manipulator: no arm to lose)."""
    thrusters = params.thrusters
    cycle_s, step_s = context.cycle_s, context.step_s
    n_steps = context.env.earth_angle_rad.shape[0]
    l_start = estimate.fix_mee[5]
    flying = None
    if THRUSTER_LEVELS in estimate.states:  # told of the thrusters' levels (``states.faults``)
        flying, level = allocated(estimate.states[THRUSTER_LEVELS], thrusters.get("count"))
        if arms == 2:  # an arm known lost: the other flies both nodes (``one_arm``)
            lost = (level <= 0) & (level[::-1] > 0)
            burns = jax.tree_util.tree_map(lambda one, two: jnp.where(jnp.any(lost), one, two),
                                           one_arm(burns, jnp.where(lost[0], 1, 0), arm_limits(thrusters)), burns)
            flying = jnp.where(lost, flying[::-1], flying)
            level = jnp.where(lost, level[::-1], level)
    t_mid = jnp.mod(burns.l_rad - l_start, 2 * jnp.pi) / (2 * jnp.pi) * cycle_s
    attitude_error = attitude_error_rad(params.errors, key)  # the truth's (``physics.execution``)
    directions = delta_v_direction_rsw(burns.alpha_rad + attitude_error[0], burns.beta_rad + attitude_error[1])
    v_mps = jnp.where(params.errors["att_known"] > 0, refit_magnitudes_mps(burns, directions, l_start), burns.v_mps)
    burn_s = v_mps * estimate.mass_kg / thrusters["thrust_n"]  # eq. (13)
    if flying is not None:
        burn_s = jnp.where(level > 0, burn_s / jnp.where(level > 0, level, 1.0), 0.0)
    burn_s = jnp.where((burn_s >= thrusters["min_burn_s"]) & burns.feasible, burn_s, 0.0)
    start = jnp.clip(t_mid - burn_s / 2, 0.0, cycle_s - burn_s)
    clock = sunlit_clock(sunlit_fraction(context.env, params.station["lon_rad"], context.force_model), step_s)
    grid = jnp.arange(n_steps + 1) * step_s
    clock_start = jnp.interp(start, grid, clock)
    return BurnPlan(burns, burn_s, clock, clock_start, directions,
                    delta_v_direction_rsw(burns.alpha_rad, burns.beta_rad), prediction, ns_fraction,
                    firing_start_s(clock, clock_start, step_s), magnitude_scale(params.errors, key), flying)


def allocated(levels, count):
    """(thruster [2] int, level [2]) flying each arm's burn: arm k carries thruster k and, where
    ``thrusters.count`` is 4, thruster k + 2; of those on board the one with the highest level as told
    (``levels`` [4], ``states.faults``), the first where they tie.  The same Delta-V costs the same propellant at
    any level (one Isp), so the least-fuel choice is any working thruster; the highest level fires the shortest
    burn, the nearest to the impulse the plan assumes."""
    on_board = jnp.arange(levels.shape[0]) < (2 if count is None else count)
    levels = jnp.where(on_board, levels, 0.0)
    primary, redundant = levels[0:2], levels[2:4]
    use_redundant = redundant > primary
    return jnp.arange(2) + 2 * use_redundant, jnp.where(use_redundant, redundant, primary)


def one_thruster(levels, count):
    """(thruster [] int, level []) a law of one thruster along any direction flies (a gimbal, Katz 2025; the
    re-acquisition law): of the ``thrusters.count`` on board (unset: one), the one with the highest level as
    told (``levels`` [4], ``states.faults``), the first where they tie; level 0 where none works."""
    levels = jnp.where(jnp.arange(levels.shape[0]) < (1 if count is None else count), levels, 0.0)
    k = jnp.argmax(levels)
    return k, levels[k]


def one_arm(burns, keeper, limits):
    """The pair ``burns`` [qffc.BurnPair] flown by arm ``keeper`` alone ([] int 0 or 1, the other lost): Ye 2022's
    one-node north-south keeping and the east-west keeping it can.

    A normal Delta-V v_n at the node l moves the inclination vector along v_n (cos l, sin l) (eq. (29)); the pair's
    burns sit half an orbit apart, south at l_1 and north at l_2 = l_1 + pi, so their effects add along one
    line and one burn of |v_n1| + |v_n2| at the keeper's node has the pair's inclination effect exactly.  The
    keeper flies that burn with its own in-plane part, and the lost arm's in-plane part (its normal part 0, the
    pitch floor beta_min where it is not 0) at the lost arm's node, half an orbit later: radial inward parts at
    opposite nodes cancel in the eccentricity vector, so the pair's in-plane effect is kept.  Where the one burn
    would pitch beyond beta_max, both burns gain the same radial inward part d (the least that brings it to
    beta_max): at opposite nodes it leaves the eccentricity vector and the drift as they were and moves the mean
    longitude, which the next cycle's plan sees.  The lost arm's yaw is clipped to the keeper's limits (eq. (1)),
    its in-plane size kept."""
    (alpha_lo, alpha_hi), _ = alpha_beta_bounds(limits)
    dv = burns.dv_rsw_mps
    own = jnp.where(keeper == 1, dv[1], dv[0])
    other = jnp.where(keeper == 1, dv[0], dv[1])
    north = jnp.where(keeper == 1, 1.0, -1.0)  # the keeper's normal sign: arm 0 fires south, arm 1 north
    v_n = north * (jnp.abs(dv[0, 2]) + jnp.abs(dv[1, 2]))
    lo, hi = jnp.where(keeper == 1, alpha_lo[1], alpha_lo[0]), jnp.where(keeper == 1, alpha_hi[1], alpha_hi[0])
    alpha_other = jnp.clip(jnp.arctan2(-other[1], -other[0]), lo, hi)
    p_other = jnp.hypot(other[0], other[1])
    x, y = p_other * jnp.cos(alpha_other), p_other * jnp.sin(alpha_other)  # eq. (1)'s x = -v_r >= 0, y = -v_t
    tan_max, tan_min = tan(limits.beta_max_rad), tan(limits.beta_min_rad)
    radial = jnp.zeros(())
    n_other = jnp.zeros(())
    # the floor's normal part and the raise d depend on each other: fixed-point steps, each shrinking the error by
    # about tan(beta_min) / tan(beta_max) (0.06 at 10 and 70 deg)
    for _ in range(8):
        n_other = tan_min * jnp.hypot(x + radial, y)
        wanted = (jnp.abs(v_n) + n_other) / jnp.maximum(tan_max, 1e-12)  # the own burn's least in-plane part
        radial = jnp.maximum(0.0, jnp.sqrt(jnp.maximum(wanted ** 2 - own[1] ** 2, 0.0)) + own[0])
    own_new = jnp.stack([own[0] - radial, own[1], v_n + north * n_other])
    other_new = jnp.stack([-(x + radial), -y, north * n_other])
    dv_new = jnp.where(keeper == 1, jnp.stack([other_new, own_new]), jnp.stack([own_new, other_new]))
    dv_new = jnp.where(jnp.any(dv != 0), dv_new, 0.0)  # no plan (an infeasible cycle): nothing to fly
    v = jnp.linalg.norm(dv_new, axis=1)
    alpha = jnp.arctan2(-dv_new[:, 1], -dv_new[:, 0])
    beta = jnp.arctan2(-dv_new[:, 2], jnp.hypot(dv_new[:, 0], dv_new[:, 1]))
    return burns._replace(dv_rsw_mps=dv_new, v_mps=v, alpha_rad=alpha, beta_rad=beta)


def firing_start_s(clock, clock_start, step_s):
    """When burns [k] that start at sunlit-clock times ``clock_start`` begin firing, s from the cycle start: the
    first time ``clock`` [n_steps + 1] (sunlit time at the step boundaries) passes ``clock_start``, linear within
    a step.  A start planned in the shadow, where the clock stands still, fires when the shadow ends: the last
    boundary at or below ``clock_start`` (``jnp.interp`` leaves a flat stretch of ``xp`` undefined)."""
    n_steps = clock.shape[0] - 1
    j = jnp.clip(jnp.searchsorted(clock, clock_start, side="right") - 1, 0, n_steps - 1)
    rise = clock[j + 1] - clock[j]
    within = jnp.where(rise > 0, (clock_start - clock[j]) / jnp.where(rise > 0, rise, 1.0), 0.0)
    return (j + jnp.clip(within, 0.0, 1.0)) * step_s


# The rows of eq. (29) in velocity terms (m/s per unit): V_RS = -V_s/2 d lambda, V_DT = -R_s/3 d lambda_dot,
# V_ET = V_s/2 de, V_N = 2 V_s di (``qffc`` module docstring), so a least-squares fit weighs them alike.
EFFECT_ROW_MPS = (V_SYNC_MPS / 2, R_SYNC_M / 3, V_SYNC_MPS / 2, V_SYNC_MPS / 2, 2 * V_SYNC_MPS, 2 * V_SYNC_MPS)


def refit_magnitudes_mps(burns, directions_rsw, l_start_rad):
    """The magnitudes [2] (>= 0) of two burns along ``directions_rsw`` [2, 3] (unit velocity increments) whose
    effect B_1 v_1 + B_2 v_2 (eq. (29), ``effects.effect_matrix``) best reproduces the planned burns' effect, in
    the velocity metric of ``EFFECT_ROW_MPS``: a 2 x 2 least-squares fit, each magnitude clipped at zero."""
    b = effect_matrix(burns.l_rad, cycle_coast_s(burns.l_rad, l_start_rad))  # [2, 6, 3]
    w = jnp.asarray(EFFECT_ROW_MPS)
    target = w * jnp.einsum("kij,kj->i", b, burns.dv_rsw_mps)
    columns = w[:, None] * jnp.einsum("kij,kj->ik", b, directions_rsw)  # [6, 2]
    gram = columns.T @ columns + 1e-30 * jnp.eye(2)
    return jnp.maximum(jnp.linalg.solve(gram, columns.T @ target), 0.0)


def thrust(params, plan: BurnPlan, t, state, environment, tilts_rsw=None) -> Thrust:
    """The thrust of one step: the burns are half a cycle apart, so a step meets at most one of them.
    ``tilts_rsw`` [2, 3] (optional): each burn's planned tilt of its line (``Thrust.tilt_rsw``)."""
    j, step_s = environment.index, environment.step_s
    fraction = firing_fraction(plan.clock[j], plan.clock[j + 1], plan.clock_start, plan.burn_s, step_s)
    direction = jnp.where(fraction[0] > 0, plan.directions_rsw[0], plan.directions_rsw[1])
    level = jnp.where(fraction[0] > 0, plan.magnitude_scale[0], plan.magnitude_scale[1])
    tilt = None if tilts_rsw is None else jnp.where(fraction[0] > 0, tilts_rsw[0], tilts_rsw[1])
    flying = jnp.arange(2) if plan.thrusters is None else plan.thrusters  # burn k from arm k (``states.faults``)
    thruster = jnp.where(fraction[0] > 0, flying[0], flying[1])
    planned = jnp.where(fraction[0] > 0, plan.planned_rsw[0], plan.planned_rsw[1])
    thrust_n = params.thrusters["thrust_n"]
    return Thrust(direction, thrust_n * level, params.thrusters["isp_s"], jnp.sum(fraction), tilt, thruster,
                  planned, thrust_n)


def record(plan: BurnPlan) -> dict:
    """Per-cycle records of a planner (read by ``loop.metrics``)."""
    fired_s = jnp.maximum(jnp.minimum(plan.burn_s, plan.clock[-1] - plan.clock_start), 0.0)
    out = {"burns": plan.burns, "fired_s": fired_s, "prediction": plan.prediction,
           "ns_fraction": plan.ns_fraction, "solved": plan.burns.feasible, "directions_rsw": plan.directions_rsw,
           "start_s": plan.start_s}
    if plan.thrusters is not None:  # allocated (``allocated``): the thruster of each burn, from 0
        out["thrusters"] = plan.thrusters
    return out


def sunlit_fraction(env_steps, station_lon_rad, fm):
    """Sunlit fraction [n_steps] at the mid-step of each step, at the station's nominal position."""
    cos_angle, sin_angle = sincos(env_steps.earth_angle_rad[:, 1] + station_lon_rad)
    x, y, z = R_SYNC_M * cos_angle, R_SYNC_M * sin_angle, jnp.zeros_like(cos_angle)
    # A batch evaluates the shadow function (an arcsine and three arccosines per step) only in cycles where
    # some sample's station meets the shadow cone (``physics.fusion.skipped_where_idle``): a few weeks
    # around each equinox; elsewhere it is exactly 1.  The Moon's shadow too, where the scenario has it.
    mid = jax.tree_util.tree_map(lambda a: a[:, 1], env_steps)
    return sunlit_fraction_xyz(x, y, z, mid, fm, boundaries=True)
