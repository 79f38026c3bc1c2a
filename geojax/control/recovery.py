"""Re-acquisition after a failure: an opt-in wrapper around a station-keeping controller (``controller.recovery``).

A planner that meets a cycle without a solution flies nothing that cycle, and a sample that has left its box
is not brought back by laws that assume it is inside (an operator's QFFC runs with a weak thruster drifted
5-27 deg off station).  With ``controller.recovery = true`` the loop keeps the controller and adds a stated
re-acquisition law that takes over while the satellite is out:

* **When.**  At each cycle start, from the estimate (never the truth; ``view``): the longitude offset from
  the station dlon, the drift D and the latitude amplitude i = 2 atan |(h, k)| -- the mean elements of the
  predictor's estimate for a controller that has them, else the fix's osculating values (dlon = L - theta -
  lon_station, the MEE true longitude less the Earth angle).  Recovery starts in a cycle whose estimate is outside
  the box (|dlon| or i > ``station.box_half_width_deg``) or whose plan has no solution (the controller's
  ``"solved"`` record); it ends at the first cycle start that is settled: |dlon| < half the box, the drift
  moves the longitude by less than a quarter of the box per cycle, and i < half the box (the hysteresis keeps
  the controller from being handed a satellite on the box edge).
* **What.**  Longitude: a first-order return, target drift D* = -clip(dlon / ``TAU_CYCLES`` cycles,
  +-``DRIFT_MAX_DEG_DAY``), and the along-track Delta-V that sets it, dv_t = -a (D* - D) / 3 (dD = -3/2 n
  da / a, and vis-viva for a near-circular orbit: da / a = 2 dv / v), spread evenly over the cycle (an even spread leaves the eccentricity vector unchanged to first order).
  Latitude: while i is above a quarter of the box, out-of-plane thrust against the inclination vector in the
  90-deg arcs about its nodes (where |cos(L - Omega)| >= cos 45 deg), sized so that the cycle delivers
  dv_n = i v / ``ARC_EFFICIENCY`` (the mean |cos| over the arcs, 2 sqrt(2) / pi); the station's target
  inclination vector is the aim.  The true longitude within the cycle is the fix's advanced at the fix's
  mean motion.  The eccentricity vector is not acted on (the controller takes it back after hand-over).
* **How it flies.**  One thruster (``thrusters.thrust_n``, ``thrusters.isp_s``) pointed along the commanded
  RSW direction: a gimbal's freedom, the arms' limits of Li 2022 eq. (1) are not enforced (an operator's
  contingency manoeuvre, not the controller's), the two commanded parts scaled together where their sum
  exceeds the thrust.

What it leaves in the results: a recovered sample keeps the status of its failure (left the box, or cycles
without a solution: ``loop.metrics``), its records mark the cycles flown by recovery (``"recovering"``), in
which the controller's own burn records are zero (its burn metrics, duty and north-south split count its own
burns only), and ``recovery_cycles`` and ``dv_recovery_mps`` (the Delta-V delivered in those cycles) report
the recovery apart; ``dv_per_year_mps`` is everything flown.

The key is static (one compiled loop with recovery, one without): off, the controller object is the one of
``control.REGISTRY``, the same program and numbers as before the key existed.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control.base import Controller, Estimate
from geojax.control.burns import allocated, one_thruster
from geojax.physics.constants import J2, OMEGA_EARTH_RAD_S, R_EARTH_M, SECONDS_PER_DAY
from geojax.physics.dynamics import Thrust
from geojax.physics.elements import wrap_angle
from geojax.physics.trig import atan, sincos
from geojax.reductions import sum_over_cycles
from geojax.params import Field
from geojax.states.base import THRUSTER_LEVELS

# The re-acquisition law's stated constants (see the module docstring).
TAU_CYCLES = 4.0  # the longitude offset's time constant, cycles
DRIFT_MAX_DEG_DAY = 0.5  # the fastest return drift
ARC_EFFICIENCY = 2 * math.sqrt(2) / math.pi  # mean |cos| over the +-45 deg arcs about a node
ARC_COS = math.cos(math.radians(45.0))

# The ``controller.recovery`` key (``geojax.scenario`` joins it to the ``[controller]`` table): static, one
# compiled loop with it and one without, for any kind.
FIELD = Field(bool, False, static=True,
              doc="fly a stated re-acquisition law back to the box while out of it or after a cycle without a "
                  "solution (status still records the failure; dv_recovery_mps reports its delta-V apart)")


class Command(NamedTuple):
    """A cycle's re-acquisition command (zeros when not recovering)."""

    recovering: jnp.ndarray  # [] bool
    on_t: jnp.ndarray  # [] signed fraction of the thrust held along-track over the whole cycle, in [-1, 1]
    on_n: jnp.ndarray  # [] fraction of the thrust held out of plane within the node arcs, in [0, 1]
    di_unit: jnp.ndarray  # [2] unit inclination-vector error (h, k) to cancel
    l0_rad: jnp.ndarray  # [] the fix's true longitude at the cycle start
    n_rad_s: jnp.ndarray  # [] the fix's mean motion


class Plan(NamedTuple):
    inner: object  # the controller's own plan
    command: Command
    levels: jnp.ndarray | None = None  # [4] the thrusters' levels as told (``states.faults``); None: not told


def view(estimate: Estimate, earth_angle_rad, station: dict, mu, use_mean: bool):
    """(dlon rad, drift rad/s, a m, i rad) the law reads: the longitude offset from the station, the drift,
    the semi-major axis and the inclination (the latitude amplitude).

    ``use_mean`` (a controller with the predictor's reference): the mean longitude, drift and inclination of
    the estimate (Li 2022 eqs. (24)-(27)), which the natural forces' short-period terms do not move.  Else the
    fix's osculating values, the drift with J2's secular rate of the mean longitude, n (1 + 3/2 J2 (R / a)^2)
    - omega_E (for an equatorial circular orbit; without it a zero Keplerian drift is 0.013 deg/day east)."""
    p, f, g, h, k, l_rad = (estimate.fix_mee[j] for j in range(6))
    a = p / (1.0 - f * f - g * g)
    if use_mean:
        mean = estimate.mean
        return wrap_angle(mean[0] - station["lon_rad"]), mean[1], a, 2.0 * atan(jnp.hypot(mean[4], mean[5]))
    n = jnp.sqrt(mu / a ** 3) * (1.0 + 1.5 * J2 * (R_EARTH_M / a) ** 2)
    dlon = wrap_angle(l_rad - earth_angle_rad - station["lon_rad"])
    return dlon, n - OMEGA_EARTH_RAD_S, a, 2.0 * atan(jnp.hypot(h, k))


def along_track_dv_mps(a_m, drift_rad_s, drift_goal_rad_s):
    """The along-track Delta-V that moves a near-circular orbit of semi-major axis ``a_m`` from the drift
    ``drift_rad_s`` to ``drift_goal_rad_s``: dD = -3/2 n da / a and da / a = 2 dv / v (vis-viva), so
    dv = -a dD / 3."""
    return -a_m * (drift_goal_rad_s - drift_rad_s) / 3.0


def command(params, estimate: Estimate, context, recovering, use_mean: bool, level=1.0) -> Command:
    """The cycle's re-acquisition command (``recovering``: whether it is flown; ``use_mean``: see ``view``;
    ``level``: the fraction of ``thrusters.thrust_n`` its thrusters deliver, as told)."""
    mu = context.force_model.mu_m3_s2
    station = params.station
    dlon, drift, a, _ = view(estimate, context.env.earth_angle_rad[0, 0], station, mu, use_mean)
    cycle_s = context.cycle_s
    drift_max = math.radians(DRIFT_MAX_DEG_DAY) / SECONDS_PER_DAY
    goal = -jnp.clip(dlon / (TAU_CYCLES * cycle_s), -drift_max, drift_max)
    accel = params.thrusters["thrust_n"] * level / estimate.mass_kg
    on_t = jnp.clip(along_track_dv_mps(a, drift, goal) / (accel * cycle_s), -1.0, 1.0)
    h, k = estimate.fix_mee[3] - station["ix"], estimate.fix_mee[4] - station["iy"]
    di = 2.0 * atan(jnp.hypot(h, k))
    v = jnp.sqrt(mu / a)
    wanted = di > station["box_half_width_rad"] / 4
    on_n = jnp.where(wanted, jnp.clip(di * v / ARC_EFFICIENCY / (accel * cycle_s / 2), 0.0, 1.0), 0.0)
    norm = jnp.maximum(jnp.hypot(h, k), 1e-300)
    off = jnp.zeros(())
    return Command(recovering, jnp.where(recovering, on_t, off), jnp.where(recovering, on_n, off),
                   jnp.stack([h, k]) / norm, estimate.fix_mee[5], jnp.sqrt(mu / a ** 3))


def settled(params, estimate: Estimate, context, use_mean: bool):
    """Whether the estimate is well inside the box (hand-over), and whether it is outside it (take-over)."""
    mu = context.force_model.mu_m3_s2
    box = params.station["box_half_width_rad"]
    dlon, drift, _, i = view(estimate, context.env.earth_angle_rad[0, 0], params.station, mu, use_mean)
    inside = (jnp.abs(dlon) < box / 2) & (jnp.abs(drift) * context.cycle_s < box / 4) & (i < box / 2)
    outside = (jnp.abs(dlon) > box) | (i > box)
    return inside, outside


def thrust_of(params, c: Command, t_s, t0_s) -> Thrust:
    """The thrust of a re-acquisition command over the step starting at ``t_s`` (cycle start ``t0_s``)."""
    l_rad = c.l0_rad + c.n_rad_s * (t_s - t0_s)
    cos_l, sin_l = sincos(l_rad)
    along_node = c.di_unit[0] * cos_l + c.di_unit[1] * sin_l  # cos(L - Omega) of the inclination error
    u_n = jnp.where(jnp.abs(along_node) >= ARC_COS, -jnp.sign(along_node) * c.on_n, 0.0)
    u = jnp.stack([jnp.zeros(()), c.on_t, u_n])
    size = jnp.linalg.norm(u)
    return Thrust(u / jnp.maximum(size, 1e-300), params.thrusters["thrust_n"], params.thrusters["isp_s"],
                  jnp.minimum(size, 1.0))


def on_working_arm(back: Thrust, flying, level) -> Thrust:
    """The re-acquisition thrust ``back`` (its arm chosen by the side of its push, ``Thrust.thruster`` 0 or 1)
    flown by the thruster of that arm that works (``flying`` [2], ``level`` [2]: ``burns.allocated`` as told);
    where that arm has none, the other arm flies the along-track part alone (either arm pushes along-track: the
    law leaves the arms' limits aside) and the push to the lost arm's side is dropped; nothing where neither
    works."""
    arm = back.thruster
    lost, other = level[arm] <= 0, 1 - arm
    along = back.on_fraction * jnp.stack([back.direction_rsw[0], back.direction_rsw[1], jnp.zeros(())])
    size = jnp.linalg.norm(along)
    return back._replace(
        direction_rsw=jnp.where(lost & (size > 0), along / jnp.maximum(size, 1e-300), back.direction_rsw),
        on_fraction=jnp.where(lost, jnp.where(level[other] > 0, size, 0.0), back.on_fraction),
        thruster=jnp.where(lost, flying[other], flying[arm]))


def _masked(record: dict, recovering) -> dict:
    """The controller's records with everything but ``"solved"`` zero in a recovery cycle (its burns were not
    flown)."""
    return {name: value if name == "solved" else
            jax.tree_util.tree_map(lambda x: jnp.where(recovering, jnp.zeros_like(x), x), value)
            for name, value in record.items()}


@functools.cache  # the same wrapped object for the same controller: its compiled programs are reused
def with_recovery(controller: Controller) -> Controller:
    """``controller`` with the re-acquisition law of this module (its ``fields`` gain ``recovery``)."""
    use_mean = controller.reference_cycles > 0
    arms = controller.spec.bound_geometry == "arms"  # Li's two arms (QFFC, FOMPC, MPC), else one thruster
    solved_of = (lambda plan: controller.record(plan).get("solved", jnp.asarray(True))) \
        if controller.record is not None else (lambda plan: jnp.asarray(True))

    def init(params, context):
        return controller.init(params, context), jnp.asarray(False)

    def plan(params, state, estimate, context, key):
        inner_state, was_recovering = state
        inner, inner_state = controller.plan(params, inner_state, estimate, context, key)
        inside, outside = settled(params, estimate, context, use_mean)
        recovering = jnp.where(was_recovering, ~inside, outside | ~solved_of(inner))
        levels = estimate.states.get(THRUSTER_LEVELS)
        # told of the thrusters' levels: sized for the best working one (1 where none works: nothing is flown)
        level = 1.0 if levels is None else jnp.where(jnp.max(levels) > 0, jnp.max(levels), 1.0)
        return (Plan(inner, command(params, estimate, context, recovering, use_mean, level), levels),
                (inner_state, recovering))

    def thrust(params, plan: Plan, t, state, environment):
        own = controller.thrust(params, plan.inner, t, state, environment)
        t0 = t - environment.index * environment.step_s
        back = thrust_of(params, plan.command, t, t0)
        count = params.thrusters.get("count")
        if arms and own.thruster is not None:  # a planner's arms: a push south (dv along -W) from arm 0, north from 1
            back = back._replace(thruster=jnp.where(back.direction_rsw[2] > 0, 1, 0))
            if plan.levels is not None:
                back = on_working_arm(back, *allocated(plan.levels, count))
        elif plan.levels is not None:  # one thruster along any direction: the best working one
            k, level = one_thruster(plan.levels, count)
            back = back._replace(on_fraction=jnp.where(level > 0, back.on_fraction, 0.0), thruster=k)
        elif own.thruster is not None:  # a manipulator's one thruster (zone NSSK)
            back = back._replace(thruster=jnp.zeros_like(own.thruster))
        if own.planned_direction_rsw is not None:  # the law flies as planned (no execution-error model)
            back = back._replace(planned_direction_rsw=back.direction_rsw, planned_thrust_n=back.thrust_n)
        if own.thruster is None and back.thruster is not None:  # one structure for the choice below: None is 0
            own = own._replace(thruster=jnp.zeros_like(back.thruster))
        return jax.tree_util.tree_map(lambda r, o: jnp.where(plan.command.recovering, r, o), back, own)

    def record(plan: Plan) -> dict:
        own = {} if controller.record is None else controller.record(plan.inner)
        return {**_masked(own, plan.command.recovering), "recovering": plan.command.recovering}

    def metrics(params, cycles, run_s, own) -> dict:  # the controller's own over its cycles, then the law's
        recovering = cycles.controller["recovering"]
        inner = {} if controller.metrics is None else controller.metrics(params, cycles, run_s, own & ~recovering)
        return {**inner, **recovery_metrics(cycles.controller, cycles.dv_mps)}

    surrogate = None if controller.surrogate is None else with_recovery(controller.surrogate)
    return dataclasses.replace(controller, init=init, plan=plan, thrust=thrust, record=record, surrogate=surrogate,
                               metrics=metrics,
                               spec=dataclasses.replace(controller.spec,
                                                        fields={**controller.spec.fields, "recovery": FIELD}))


def recovery_metrics(rec: dict, dv_mps) -> dict:
    """``recovery_cycles`` (cycles flown by recovery) and ``dv_recovery_mps`` (their Delta-V) of a run's records."""
    recovering = rec["recovering"]
    return {"recovery_cycles": jnp.sum(recovering).astype(float),
            "dv_recovery_mps": sum_over_cycles(jnp.where(recovering, dv_mps, 0.0))}
