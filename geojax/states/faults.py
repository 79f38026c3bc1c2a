"""Contingencies, a part of the loop: burns lost, a thruster out over a window, thrust degraded -- what the
thrusters deliver against what the controller commands, with what was planned and what was flown side by side.

The part acts on the thrust each step (``StateModel.thrust``): the thruster that flies it (``Thrust.thruster``,
a planner's burn ``k`` from arm ``k``'s thruster; a controller that does not say: thruster 0) delivers nothing
where its burn of the cycle was drawn missed (each planned burn lost with ``missed_burn_probability``, one
uniform draw per thruster per cycle from the part's own random stream) or where it is out (``thruster_out``,
one or a list, from ``out_from_day`` -- or a start drawn per sample over ``out_from_spread_days`` -- for
``out_days`` days, 0: to the end), and delivers its ``thrust_scale`` (one for all, or one per thruster) of its
thrust otherwise.  With ``planner_told`` (the default) the planner learns at each cycle
start what telemetry shows then (``estimate.states[THRUSTER_LEVELS]``: each thruster's level; ``control.burns`` plans a
degraded thruster's burns with its delivered level and fires no burn from a thruster it knows is out); without,
it plans as if nothing were wrong, and the closed loop shows what that costs.  A "burn" is a thruster's
firing within one control cycle (a planner's burn; a feedback law's cycle of firing).  A stuck arm
(``stuck_arm``, over the outage's window): thruster k sits on arm k mod 2, and the arm's thrusters keep firing
what is commanded, but along the direction (body axes = RSW: the attitude is held nadir-pointing) its joints had
when the fault started -- the arm's last firing direction, or the middle of its limits (Li 2022 eq. (1)) where it
had not fired.  Told, the planner treats the stuck arm as lost (its thrusters' levels 0: the other arm flies
Ye 2022's one-node plan, ``control.burns.one_arm``); fitting the plan to the frozen direction is not done.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.params import NUMBER, Field
from geojax.physics.constants import SECONDS_PER_DAY
from geojax.physics.propulsion import alpha_beta_bounds, arm_limits, delta_v_direction_rsw
from geojax.states.base import BURN_STATUSES, THRUSTER_LEVELS, FlownBurns, Part, StateModel

NAME = "faults"
# The thrusters the part tracks (indices 0 .. TRACKED - 1): Li's two arms with two thrusters each.
TRACKED = 4
# ``reacquire_days`` of a sample whose run ends out of its box (a metric is finite: a NaN would read as status 4).
NOT_REACQUIRED = -1.0
OUTAGE_DRAW = 1  # ``fold_in`` constant of the outage start's draw from the part's key at the first cycle

FIELDS = {
    "enabled": Field(bool, False, static=True,
                     doc="carry the faults part (set by any other key of the table; give it in a sweep's base "
                         "where a grid moves a faults key from its default)"),
    "missed_burn_probability": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1.0,
                                     si="missed_burn_probability", unit="",
                                     doc="each planned burn (a thruster's firing in a cycle) is lost with this "
                                         "probability, drawn from the part's own random stream"),
    "thruster_out": Field((int, list), -1, lower=-1, upper=TRACKED, lower_inclusive=True, unit="",
                          doc="the thruster (from 0; a planner's burn k flies thruster k, its redundant one k + 2), "
                              "or a list of them, that delivers nothing from out_from_day for out_days; -1 or []: "
                              "none"),
    "out_from_day": Field((*NUMBER, str), 0.0, lower=0.0, lower_inclusive=True, upper=1e6, unit="day",
                          doc="when the thruster_out outage starts, days from the run's start; \"uniform\": drawn "
                              "per sample over the run (out_from_day 0, out_from_spread_days the run's length)"),
    "out_from_spread_days": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, unit="day",
                                  doc="the outage's start drawn per sample uniform over [out_from_day, out_from_day "
                                      "+ this) from the part's own stream; 0: out_from_day itself"),
    "out_days": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, si="out_s", to_si=SECONDS_PER_DAY,
                      unit="day", doc="how long the outage lasts, days; 0: to the end of the run"),
    "thrust_scale": Field((*NUMBER, list), 1.0, lower=0.0, upper=2.0, unit="",
                          doc=f"the fraction of the commanded thrust every thruster delivers (degradation: < 1), "
                              f"or a list of {TRACKED}, one per thruster"),
    "stuck_arm": Field(int, -1, lower=-1, lower_inclusive=True, upper=2, unit="",
                       doc="the arm (0 or 1; thruster k sits on arm k mod 2) whose joints stick at their angles when "
                           "the fault starts, from out_from_day for out_days: its thrusters fire along the direction "
                           "they then give; -1: none"),
    "planner_told": Field(bool, True, si="planner_told",
                          doc="the planner learns of an outage or a degradation at the first cycle start after it "
                              "(from telemetry) and plans with what is left; false: it plans as if nothing were "
                              "wrong"),
}


class Faults(NamedTuple):
    """The carried state (per cycle: reset at its start), and each cycle's record (its values at the end)."""

    missed: jnp.ndarray  # [TRACKED] bool: this cycle's burn of each thruster is lost
    planned_s: jnp.ndarray  # [TRACKED] firing time the controller commanded this cycle, per thruster
    flown_s: jnp.ndarray  # [TRACKED] firing time delivered this cycle, per thruster
    impulse_lost_s: jnp.ndarray  # [] commanded firing time x (1 - the level delivered), summed: thrust lost
    out_from_s: jnp.ndarray  # [] when the outage starts, s from the run's start (drawn at the first cycle start)
    pointing_rsw: jnp.ndarray  # [2, 3] each arm's last firing direction (unit, RSW); a stuck arm's is frozen
    flown_dv_rsw: jnp.ndarray  # [TRACKED, 3] Delta-V delivered this cycle per thruster, m/s, RSW (signed)
    flown_dv_abs_rsw: jnp.ndarray  # [TRACKED, 3] the same summed per step as |component|: the per-axis budget


def init(params, r_eci_m, v_eci_mps, env, force_model) -> Faults:
    zero = jnp.zeros(TRACKED, r_eci_m.dtype) + 0.0 * r_eci_m[0]
    dv = jnp.zeros((TRACKED, 3)) + zero[:, None]
    return Faults(zero > 1.0, zero, zero, zero[0], zero[0] + params.states[NAME]["out_from_s"],
                  rest_pointing_rsw(params.thrusters) + zero[0], dv, dv)


def rest_pointing_rsw(thrusters):
    """[2, 3] each arm's direction before it has fired: the middle of its limits (Li 2022 eq. (1), (14))."""
    (alpha_lo, alpha_hi), (beta_lo, beta_hi) = alpha_beta_bounds(arm_limits(thrusters))
    return delta_v_direction_rsw((alpha_lo + alpha_hi) / 2, (beta_lo + beta_hi) / 2)


def cycle(params, state: Faults, start) -> Faults:
    """A cycle's start: the cycle's missed burns drawn, the per-cycle sums reset; at the first, the outage's
    start drawn (``out_from_spread_days``: uniform from ``fold_in(key, OUTAGE_DRAW)``, apart from the missed
    burns' draws)."""
    leaves = params.states[NAME]
    missed = jax.random.uniform(start.key, (TRACKED,), state.planned_s.dtype) < leaves["missed_burn_probability"]
    drawn_s = leaves["out_from_s"] + leaves["out_spread_s"] * jax.random.uniform(
        jax.random.fold_in(start.key, OUTAGE_DRAW), (), state.planned_s.dtype)
    zero = 0.0 * state.planned_s
    return Faults(missed, zero, zero, zero[0], jnp.where(start.index == 0, drawn_s, state.out_from_s),
                  state.pointing_rsw, 0.0 * state.flown_dv_rsw, 0.0 * state.flown_dv_rsw)


def in_window(params, state: Faults, t_s):
    """Whether ``t_s`` lies in the outage's window [] (from its start, as drawn, for ``out_days``; 0: to the end)."""
    leaves = params.states[NAME]
    end_s = jnp.where(leaves["out_s"] > 0, state.out_from_s + leaves["out_s"], jnp.inf)
    return (t_s >= state.out_from_s) & (t_s < end_s)


def health(params, state: Faults, thruster, t_s):
    """The fraction [] of its commanded thrust that ``thruster`` can deliver at ``t_s``: 0 while it is out, else
    its ``thrust_scale`` (what telemetry shows; a burn drawn missed is not known ahead)."""
    leaves = params.states[NAME]
    out = (leaves["out_mask"][thruster] > 0) & in_window(params, state, t_s)
    return jnp.where(out, 0.0, leaves["thrust_scale"][thruster])


def stuck(params, state: Faults, thruster, t_s):
    """Whether ``thruster``'s arm (``thruster`` mod 2) is stuck at ``t_s`` []."""
    return (params.states[NAME]["stuck_mask"][thruster % 2] > 0) & in_window(params, state, t_s)


def delivered_level(params, state: Faults, thruster, t_s):
    """The fraction [] of its commanded thrust that ``thruster`` delivers over a step starting at ``t_s``."""
    return jnp.where(state.missed[thruster], 0.0, health(params, state, thruster, t_s))


def estimate(params, state: Faults, told):
    """What the planner is told at a cycle start (``estimate.states[states.base.THRUSTER_LEVELS]``): each thruster's level [TRACKED]
    as telemetry shows it then (``health``; 0 on a stuck arm: the planner treats it as lost), or 1 for every
    thruster where ``planner_told`` is false."""
    levels = jnp.stack([jnp.where(stuck(params, state, k, told.t_s), 0.0, health(params, state, k, told.t_s))
                        for k in range(TRACKED)])
    known = jnp.where(params.states[NAME]["planner_told"] > 0, levels, 1.0)
    return told._replace(states={**told.states, THRUSTER_LEVELS: known})


def thrust(params, state: Faults, commanded, ctx):
    """The thrust delivered over one step (a stuck arm's along its frozen direction), and the commanded and
    delivered firing and the Delta-V delivered noted per thruster."""
    k = jnp.asarray(0) if commanded.thruster is None else commanded.thruster
    level = delivered_level(params, state, k, ctx.t_s)
    commanded_s = commanded.on_fraction * ctx.step_s
    flown_fraction = jnp.where(level > 0, commanded.on_fraction, 0.0)
    one_hot = jnp.arange(TRACKED) == k
    frozen = stuck(params, state, k, ctx.t_s)
    arm = (jnp.arange(2) == k % 2)[:, None]
    direction = jnp.where(frozen, state.pointing_rsw[k % 2], commanded.direction_rsw)
    # a free arm's joints follow what it fires (a time-shared direction of norm < 1 is not a pointing)
    moved = arm & ~frozen & (commanded.on_fraction > 0) & (jnp.linalg.norm(commanded.direction_rsw) > 0.5)
    pointing = jnp.where(moved, commanded.direction_rsw / jnp.maximum(jnp.linalg.norm(commanded.direction_rsw),
                                                                       1e-300), state.pointing_rsw)
    thrust_n = commanded.thrust_n * jnp.where(level > 0, level, 1.0)
    dv_rsw = (flown_fraction * ctx.step_s * thrust_n / ctx.mass_kg) * direction
    state = Faults(state.missed, state.planned_s + jnp.where(one_hot, commanded_s, 0.0),
                   state.flown_s + jnp.where(one_hot, flown_fraction * ctx.step_s, 0.0),
                   state.impulse_lost_s + commanded_s * (1.0 - level), state.out_from_s, pointing,
                   state.flown_dv_rsw + jnp.where(one_hot[:, None], dv_rsw, 0.0),
                   state.flown_dv_abs_rsw + jnp.where(one_hot[:, None], jnp.abs(dv_rsw), 0.0))
    return state, commanded._replace(on_fraction=flown_fraction, thrust_n=thrust_n, direction_rsw=direction)


def step(params, state: Faults, ctx):
    return state, ()


def summary(params, start: Faults, end: Faults, steps) -> Faults:
    return end


def metrics(params, cycles: Faults, n_steps_total: int, run_s: float):
    """Burns planned, lost and flown (a burn: a thruster's firing in a cycle), firing time per thruster as
    commanded and as delivered, and the thrust lost to the faults as firing time at full thrust."""
    planned = cycles.planned_s > 0
    flown = cycles.flown_s > 0
    out = {
        "burns_total": jnp.sum(flown).astype(float),  # as flown: in place of the controller's count of its plan
        "burns_planned": jnp.sum(planned).astype(float),
        "burns_flown": jnp.sum(flown).astype(float),
        "burns_missed": jnp.sum(planned & ~flown).astype(float),
        "burns_drawn_missed": jnp.sum(planned & cycles.missed).astype(float),
        "fault_lost_firing_s": jnp.sum(cycles.impulse_lost_s),
    }
    for k in range(TRACKED):
        out[f"on_time_t{k}_s"] = jnp.sum(cycles.flown_s[:, k])
        out[f"burns_t{k}"] = jnp.sum(flown[:, k]).astype(float)
    return out, jnp.asarray(False)


def fault_start_s(params, cycles: Faults):
    """When the faults start [] s from the run's start: the outage's start (as drawn) where a thruster is out or
    an arm stuck, else the run's start (a burn may be lost or thrust degraded from the first cycle)."""
    leaves = params.states[NAME]
    windowed = jnp.any(leaves["out_mask"] > 0) | jnp.any(leaves["stuck_mask"] > 0)
    return jnp.where(windowed, cycles.out_from_s[0], 0.0)


def box_metrics(params, cycles: Faults, out_of_box, cycle_s: float):
    """The time out of the box and to re-acquire it, from the loop's box check per cycle (``out_of_box``
    [n_cycles] bool, ``loop.metrics.box_exits``; a cycle counts whole where any of its step starts is out):
    ``days_out_of_box`` over the run, and ``reacquire_days``, from the faults' start to the end of the last
    cycle out of the box that ends after it: 0 where the sample never left the box after the faults' start,
    ``NOT_REACQUIRED`` (-1) where the run ends out of the box."""
    n_cycles = out_of_box.shape[0]
    start_s = fault_start_s(params, cycles)
    end_s = (jnp.arange(n_cycles) + 1.0) * cycle_s
    after = out_of_box & (end_s > start_s)
    last_end_s = jnp.max(jnp.where(after, end_s, 0.0))
    reacquire_days = jnp.where(~jnp.any(after), 0.0,
                               jnp.where(out_of_box[-1], NOT_REACQUIRED, (last_end_s - start_s) / SECONDS_PER_DAY))
    return {"days_out_of_box": jnp.sum(out_of_box) * (cycle_s / SECONDS_PER_DAY), "reacquire_days": reacquire_days}


def columns(cycles: Faults) -> dict:
    out = {}
    for k in range(TRACKED):
        out[f"fired_s_t{k}"] = cycles.flown_s[:, k]
        out[f"planned_s_t{k}"] = cycles.planned_s[:, k]
    return out


def validate(config: dict) -> dict:
    """The table completed (``enabled`` where any other key is set; ``out_from_day = "uniform"`` as its start 0
    and spread the run's length) and checked: ``ValueError`` naming the key where a thruster out is not on board,
    a list is malformed or a scale is not a number in (0, 2)."""
    table = dict(config[NAME])
    if any(table[key] != field.default for key, field in FIELDS.items() if key != "enabled"):
        table["enabled"] = True
    start = table["out_from_day"]
    if isinstance(start, str):
        if start != "uniform":
            raise ValueError(f"faults.out_from_day: must be a number of days >= 0 or \"uniform\", got {start!r}")
        table["out_from_day"], table["out_from_spread_days"] = 0.0, float(config["duration"]["days"])
    count = config["thrusters"]["count"]
    if table["enabled"] and count is not None and count > TRACKED:
        raise ValueError(f"thrusters.count: the faults part tracks up to {TRACKED} thrusters, got {count}")
    for k in thrusters_out(table["thruster_out"]):
        if count is None and k > 0:  # thruster 0 is always on board
            raise ValueError(f"faults.thruster_out: thruster {k} needs thrusters.count set (the thrusters on "
                             f"board), got it unset")
        if count is not None and k >= count:
            raise ValueError(f"faults.thruster_out: thruster {k} is not on board (thrusters.count = {count}, "
                             f"indices from 0)")
    arm = table["stuck_arm"]
    if arm == 1 and (count or 2) < 2:  # thruster k on arm k mod 2: arm 1 needs two thrusters on board
        raise ValueError(f"faults.stuck_arm: arm 1 is not on board (thrusters.count = {count}: arm 0 only)")
    if arm == 1 and count is None:
        raise ValueError("faults.stuck_arm: arm 1 needs thrusters.count set (the thrusters on board), got it unset")
    scale = table["thrust_scale"]
    if isinstance(scale, list) and (len(scale) != TRACKED or not all(
            isinstance(x, NUMBER) and not isinstance(x, bool) and 0.0 < x < 2.0 for x in scale)):
        raise ValueError(f"faults.thrust_scale: must be a number > 0 and < 2 or a list of {TRACKED} of them (one "
                         f"per thruster), got {scale!r}")
    return table


def thrusters_out(value) -> list[int]:
    """The thrusters ``faults.thruster_out`` names (-1: none; an index; a list of indices, from 0), or
    ``ValueError`` naming the key."""
    listed = value if isinstance(value, list) else ([] if value == -1 else [value])
    if not all(isinstance(k, int) and not isinstance(k, bool) and 0 <= k < TRACKED for k in listed):
        raise ValueError(f"faults.thruster_out: must be -1, a thruster index from 0 to {TRACKED - 1} or a list of "
                         f"them, got {value!r}")
    return listed


def leaves(table: dict) -> dict:
    """``Params.states["faults"]``: SI leaves, the thrusters out as a mask and the scales per thruster
    ([TRACKED] each), so that every sample of a sweep has leaves of one shape."""
    mask = np.zeros(TRACKED)
    mask[thrusters_out(table["thruster_out"])] = 1.0
    stuck_mask = np.zeros(2)
    if table["stuck_arm"] >= 0:
        stuck_mask[table["stuck_arm"]] = 1.0
    return {"missed_burn_probability": jnp.asarray(float(table["missed_burn_probability"])),
            "out_mask": jnp.asarray(mask),
            "stuck_mask": jnp.asarray(stuck_mask),
            "out_from_s": jnp.asarray(float(table["out_from_day"]) * SECONDS_PER_DAY),
            "out_spread_s": jnp.asarray(float(table["out_from_spread_days"]) * SECONDS_PER_DAY),
            "out_s": jnp.asarray(float(table["out_days"]) * SECONDS_PER_DAY),
            "thrust_scale": jnp.asarray(np.broadcast_to(np.asarray(table["thrust_scale"], float), (TRACKED,))),
            "planner_told": jnp.asarray(float(table["planner_told"]))}


MODEL = StateModel(NAME, init, step, summary, metrics, cycle=cycle, columns=columns, thrust=thrust, estimate=estimate,
                   box_metrics=box_metrics, columns_per_cycle=2 * TRACKED)
DESCRIPTIONS = {
    "burns_total": "burns flown (with the faults part: as flown; burns_planned beside it)",
    "burns_planned": "burns the controller commanded (a burn: a thruster's firing within one cycle)",
    "burns_flown": "burns that fired (the faults let some of their commanded time through)",
    "burns_missed": "burns commanded but not flown at all (drawn missed, or their thruster out)",
    "burns_drawn_missed": "burns lost to faults.missed_burn_probability (its own random stream)",
    "fault_lost_firing_s": "the thrust the faults took away, as firing time at full thrust, s",
    "days_out_of_box": "days in cycles with a step start out of the box (the status' check, per cycle)",
    "reacquire_days": "days from the faults' start to the end of the last cycle out of the box; 0: never left "
                      "after it, -1: the run ends out of the box",
    **{f"on_time_t{k}_s": f"thruster {k}'s firing time as delivered, s" for k in range(TRACKED)},
    **{f"burns_t{k}": f"thruster {k}'s burns flown" for k in range(TRACKED)},
    **{f"fired_s_t{k}": f"thruster {k}'s firing time delivered in the cycle, s (/cycles)" for k in range(TRACKED)},
    **{f"planned_s_t{k}": f"thruster {k}'s firing time commanded in the cycle, s (/cycles)" for k in range(TRACKED)},
}
def flown_burns(run, fired_s, directions_rsw, thrusters) -> FlownBurns:
    """The planner's burns [cycles, burns] (firing times, directions, the thruster of each) as this part let them
    fly: each by its thruster's delivered firing time, along the direction flown (a stuck arm's frozen one), at the
    level delivered; its status missed (nothing flown), cut (less than commanded), degraded (a level below 1) or
    flown."""
    records = run.records.cycles.states[NAME]
    commanded_s = np.take_along_axis(np.asarray(records.planned_s, float), thrusters, axis=1)
    flown_s = np.take_along_axis(np.asarray(records.flown_s, float), thrusters, axis=1)
    scale = np.broadcast_to(np.asarray(run.params.states[NAME]["thrust_scale"], float), (TRACKED,))
    level = np.where(flown_s > 0, scale[thrusters], 0.0)
    status = np.select([flown_s <= 0, flown_s < commanded_s, level != 1.0], BURN_STATUSES[1:], BURN_STATUSES[0])
    flown_dv = np.take_along_axis(np.asarray(records.flown_dv_rsw, float), thrusters[..., None], axis=1)
    size = np.linalg.norm(flown_dv, axis=-1, keepdims=True)
    directions_rsw = np.where(size > 0, flown_dv / np.where(size > 0, size, 1.0), directions_rsw)
    return FlownBurns(np.where(fired_s > 0, flown_s, 0.0), directions_rsw, level, status, commanded_s)


PART = Part(NAME, table=NAME, fields=FIELDS, select=lambda table: MODEL if table["enabled"] else None,
            leaves=leaves, validate=validate, descriptions=DESCRIPTIONS, model=MODEL, flown_burns=flown_burns,
            tells=lambda table: (THRUSTER_LEVELS,), tells_how={THRUSTER_LEVELS: "faults.enabled = true"})
