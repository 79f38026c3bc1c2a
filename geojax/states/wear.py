"""The thrusters' wear, a part of the loop: the firing hours and the on/off cycles the run puts on the thrusters,
against their qualified life (an electric thruster is qualified for a number of firing hours and of starts).

It counts the thrust flown at each integration step (``StepContext.thrust``, after the parts that change it): a
step that fires adds its firing time (the on-fraction of the step), and a firing step after one that did not is
a start.  A burn that an eclipse suspends is two starts, as it is for the thruster.  ``[wear] enabled = true``
turns it on; past either qualified figure the sample's status says so.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.params import NUMBER, Field
from geojax.states.base import Part, StateModel

NAME = "wear"
WORN = "thrusters past their qualified life"

FIELDS = {
    "enabled": Field(bool, False, static=True, doc="count the thrusters' firing hours and starts (on/off cycles)"),
    "qualified_hours": Field(NUMBER, 9000.0, lower=0.0, upper=1e7, si="qualified_hours", unit="h",
                             doc="firing hours the thrusters are qualified for (set your thruster's; the default "
                                 "is a placeholder); beyond them the sample's status says so"),
    "qualified_starts": Field(NUMBER, 10000.0, lower=0.0, upper=1e9, si="qualified_starts", unit="",
                              doc="starts (on/off cycles) the thrusters are qualified for"),
}


class Wear(NamedTuple):
    """The carried state, and each cycle's record (its values at the cycle's end)."""

    firing_s: jnp.ndarray  # [] firing time since the run's start
    starts: jnp.ndarray  # [] firing steps that followed a step without firing, since the run's start
    firing: jnp.ndarray  # [] bool, whether the latest step fired


def init(params, r_eci_m, v_eci_mps, env, force_model) -> Wear:
    zero = jnp.zeros_like(r_eci_m[0])
    return Wear(zero, zero, jnp.asarray(False))


def step(params, state: Wear, ctx) -> tuple[Wear, tuple]:
    """One step: its firing time added, and a start where it fires after a step that did not."""
    fires = ctx.thrust.on_fraction > 0
    return Wear(state.firing_s + ctx.thrust.on_fraction * ctx.step_s,
                state.starts + jnp.where(fires & ~state.firing, 1.0, 0.0), fires), ()


def summary(params, start: Wear, end: Wear, steps) -> Wear:
    return end


def metrics(params, cycles: Wear, n_steps_total: int, run_s: float):
    """The run's firing hours and starts, the fraction of the qualified life they use (the larger of the two);
    failed past either qualified figure."""
    limits = params.states[NAME]
    hours = cycles.firing_s[-1] / 3600.0
    used = jnp.maximum(hours / limits["qualified_hours"], cycles.starts[-1] / limits["qualified_starts"])
    return {"wear_firing_hours": hours, "wear_starts": cycles.starts[-1], "wear_life_used_fraction": used}, used > 1.0


def columns(cycles: Wear) -> dict:
    return {"wear_firing_hours": cycles.firing_s / 3600.0, "wear_starts": cycles.starts}


MODEL = StateModel(NAME, init, step, summary, metrics, status=WORN, columns=columns, columns_per_cycle=2)
DESCRIPTIONS = {
    "wear_firing_hours": "the thrusters' firing time: over the run in /metrics, since its start in /cycles",
    "wear_starts": "the thrusters' starts (a firing step after one without): over the run, or since its start",
    "wear_life_used_fraction": "the larger of firing hours / wear.qualified_hours and starts / "
                               "wear.qualified_starts",
}
PART = Part(NAME, table="wear", fields=FIELDS, select=lambda table: MODEL if table["enabled"] else None, switch="enabled",
            statuses=(WORN,), descriptions=DESCRIPTIONS, model=MODEL)
