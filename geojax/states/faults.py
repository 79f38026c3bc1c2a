"""Contingencies, a part of the loop: burns lost, a thruster out over a window, thrust degraded -- what the
thrusters deliver against what the controller commands, with what was planned and what was flown side by side.

The part acts on the thrust each step (``StateModel.thrust``): the thruster that flies it (``Thrust.thruster``,
a planner's burn ``k`` from arm ``k``'s thruster; a controller that does not say: thruster 0) delivers nothing
where its burn of the cycle was drawn missed (each planned burn lost with ``missed_burn_probability``, one
uniform draw per thruster per cycle from the part's own random stream) or where it is out (``thruster_out``,
from ``out_from_day`` for ``out_days`` days, 0: to the end), and delivers ``thrust_scale`` of its thrust
otherwise.  With ``planner_told`` (the default) the planner learns at each cycle
start what telemetry shows then (``estimate.states["faults"]``: each thruster's level; ``control.burns`` plans a
degraded thruster's burns with its delivered level and fires no burn from a thruster it knows is out); without,
it plans as if nothing were wrong, and the closed loop shows what that costs.  A "burn" is a thruster's
firing within one control cycle (a planner's burn; a feedback law's cycle of firing).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.params import NUMBER, Field
from geojax.physics.constants import SECONDS_PER_DAY
from geojax.states.base import Part, StateModel

NAME = "faults"
# The thrusters the part tracks (indices 0 .. TRACKED - 1): Li's two arms with two thrusters each.
TRACKED = 4
# ``reacquire_days`` of a sample whose run ends out of its box (a metric is finite: a NaN would read as status 4).
NOT_REACQUIRED = -1.0

FIELDS = {
    "enabled": Field(bool, False, static=True,
                     doc="carry the faults part (set by any other key of the table; give it in a sweep's base "
                         "where a grid moves a faults key from its default)"),
    "missed_burn_probability": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1.0,
                                     si="missed_burn_probability", unit="",
                                     doc="each planned burn (a thruster's firing in a cycle) is lost with this "
                                         "probability, drawn from the part's own random stream"),
    "thruster_out": Field(int, -1, lower=-1, upper=TRACKED, lower_inclusive=True, si="thruster_out", unit="",
                          doc="the thruster (from 0; a planner's burn k flies thruster k) that delivers nothing "
                              "from out_from_day for out_days; -1: none"),
    "out_from_day": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, si="out_from_s",
                          to_si=SECONDS_PER_DAY, unit="day", doc="when the thruster_out outage starts, days "
                                                                 "from the run's start"),
    "out_days": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, si="out_s", to_si=SECONDS_PER_DAY,
                      unit="day", doc="how long the outage lasts, days; 0: to the end of the run"),
    "thrust_scale": Field(NUMBER, 1.0, lower=0.0, upper=2.0, si="thrust_scale", unit="",
                          doc="the fraction of the commanded thrust every thruster delivers (degradation: < 1)"),
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


def init(params, r_eci_m, v_eci_mps, env, force_model) -> Faults:
    zero = jnp.zeros(TRACKED, r_eci_m.dtype) + 0.0 * r_eci_m[0]
    return Faults(zero > 1.0, zero, zero, zero[0])


def cycle(params, state: Faults, start) -> Faults:
    """A cycle's start: the cycle's missed burns drawn, the per-cycle sums reset."""
    p = params.states[NAME]["missed_burn_probability"]
    missed = jax.random.uniform(start.key, (TRACKED,), state.planned_s.dtype) < p
    zero = 0.0 * state.planned_s
    return Faults(missed, zero, zero, zero[0])


def health(params, thruster, t_s):
    """The fraction [] of its commanded thrust that ``thruster`` can deliver at ``t_s``: 0 while it is out, else
    ``thrust_scale`` (what telemetry shows; a burn drawn missed is not known ahead)."""
    leaves = params.states[NAME]
    start_s = leaves["out_from_s"]
    end_s = jnp.where(leaves["out_s"] > 0, start_s + leaves["out_s"], jnp.inf)
    out = (thruster == leaves["thruster_out"]) & (t_s >= start_s) & (t_s < end_s)
    return jnp.where(out, 0.0, leaves["thrust_scale"])


def delivered_level(params, state: Faults, thruster, t_s):
    """The fraction [] of its commanded thrust that ``thruster`` delivers over a step starting at ``t_s``."""
    return jnp.where(state.missed[thruster], 0.0, health(params, thruster, t_s))


def estimate(params, state: Faults, told):
    """What the planner is told at a cycle start (``estimate.states["faults"]``): each thruster's level [TRACKED]
    as telemetry shows it then (``health``), or 1 for every thruster where ``planner_told`` is false."""
    levels = jnp.stack([health(params, k, told.t_s) for k in range(TRACKED)])
    known = jnp.where(params.states[NAME]["planner_told"] > 0, levels, 1.0)
    return told._replace(states={**told.states, NAME: known})


def thrust(params, state: Faults, commanded, ctx):
    """The thrust delivered over one step, and the commanded and delivered firing noted per thruster."""
    k = jnp.asarray(0) if commanded.thruster is None else commanded.thruster
    level = delivered_level(params, state, k, ctx.t_s)
    commanded_s = commanded.on_fraction * ctx.step_s
    flown_fraction = jnp.where(level > 0, commanded.on_fraction, 0.0)
    one_hot = jnp.arange(TRACKED) == k
    state = Faults(state.missed, state.planned_s + jnp.where(one_hot, commanded_s, 0.0),
                   state.flown_s + jnp.where(one_hot, flown_fraction * ctx.step_s, 0.0),
                   state.impulse_lost_s + commanded_s * (1.0 - level))
    return state, commanded._replace(on_fraction=flown_fraction, thrust_n=commanded.thrust_n * jnp.where(
        level > 0, level, 1.0))


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


def fault_start_s(params):
    """When the faults start [] s from the run's start: the outage's start where a thruster is out, else the run's
    start (a burn may be lost or thrust degraded from the first cycle)."""
    leaves = params.states[NAME]
    return jnp.where(leaves["thruster_out"] >= 0, leaves["out_from_s"], 0.0)


def box_metrics(params, cycles: Faults, out_of_box, cycle_s: float):
    """The time out of the box and to re-acquire it, from the loop's box check per cycle (``out_of_box``
    [n_cycles] bool, ``loop.metrics.box_exits``; a cycle counts whole where any of its step starts is out):
    ``days_out_of_box`` over the run, and ``reacquire_days``, from the faults' start to the end of the last
    cycle out of the box that ends after it: 0 where the sample never left the box after the faults' start,
    ``NOT_REACQUIRED`` (-1) where the run ends out of the box."""
    n_cycles = out_of_box.shape[0]
    start_s = fault_start_s(params)
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
    """The table completed (``enabled`` where any other key is set) and checked against the thrusters on board:
    ``ValueError`` naming the key where the thruster out is not on board."""
    table = dict(config[NAME])
    if any(table[key] != field.default for key, field in FIELDS.items() if key != "enabled"):
        table["enabled"] = True
    count = config["thrusters"]["count"]
    if table["enabled"] and count is None and table["thruster_out"] > 0:  # thruster 0 is always on board
        raise ValueError(f"faults.thruster_out: thruster {table['thruster_out']} needs thrusters.count set (the "
                         f"thrusters on board), got it unset")
    if table["enabled"] and count is not None and table["thruster_out"] >= count:
        raise ValueError(f"faults.thruster_out: thruster {table['thruster_out']} is not on board (thrusters.count = "
                         f"{count}, indices from 0)")
    if table["enabled"] and count is not None and count > TRACKED:
        raise ValueError(f"thrusters.count: the faults part tracks up to {TRACKED} thrusters, got {count}")
    return table


MODEL = StateModel(NAME, init, step, summary, metrics, cycle=cycle, columns=columns, thrust=thrust, estimate=estimate,
                   box_metrics=box_metrics,
                   bytes_per_cycle=(3 * TRACKED + 1) * 8, columns_per_cycle=2 * TRACKED)
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
PART = Part(NAME, table=NAME, fields=FIELDS, select=lambda table: MODEL if table["enabled"] else None,
            validate=validate, descriptions=DESCRIPTIONS, model=MODEL)
