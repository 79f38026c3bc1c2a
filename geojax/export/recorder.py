"""A single run's ephemeris at every integration step, recorded only when asked (``simulate(..., ephemeris=True)``).

It rides the loop's extension point for further states (``states.base``), for the run's CCSDS files.
The loop keeps no Cartesian state per step.  Asked for an ephemeris, the loop carries one more model,
``TRUTH``, with no state, whose step record is the true ECI position and velocity at the step's start and the
thrust held over the step (``THRUST_COLUMNS``: a feedback law's burns, ``export.trajectory.step_burns``), and its
navigation filter (where it has one) is replaced by the same filter whose step record adds the filter's estimate
and the covariance of its ECI (r, v) at the step's start.  Their cycle records are those step records stacked
(``summary`` is given them), so they come back without ``keep_steps``; ``split`` takes them out of the records
before the metrics and the result see them, so every other number is the run's without them: the models change no
state (the filter's functions are its own), and each part draws from its own named stream (``states.base``).  ``tests/test_ccsds.py`` compares a run with and without, bit for bit.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax.numpy as jnp

from geojax.states import navigation
from geojax.states.base import StateModel

NAME = "ephemeris"


class Ephemeris(NamedTuple):
    """A run's ephemeris at every step start (leading axes [n_cycles, n_steps]), ECI, m and m/s."""

    truth: object  # [..., 6] true (r, v)
    estimate: object | None  # [..., 6] the filter's estimate of (r, v) (None without a filter)
    covariance: object | None  # [..., 6, 6] the filter's covariance of its (r, v), m^2, m^2/s, m^2/s^2
    thrust: object  # [..., 6] the thrust held over the step, THRUST_COLUMNS


# The columns of ``Ephemeris.thrust``: the thrust held over a step as the loop flew it (``StepContext.thrust``),
# its level as a fraction of full thrust along R, S, W (on-fraction x unit direction), the full thrust, the
# specific impulse and the mass at the step start.
THRUST_COLUMNS = ("fraction_r", "fraction_s", "fraction_w", "thrust_n", "isp_s", "mass_kg")


def _no_state(params, r_eci_m, v_eci_mps, env, force_model):
    return ()


def _truth_step(params, state, ctx):
    thrust = ctx.thrust
    held = jnp.concatenate([thrust.on_fraction * thrust.direction_rsw,
                            jnp.stack([thrust.thrust_n, thrust.isp_s, ctx.mass_kg]).astype(ctx.r_eci_m.dtype)])
    return state, (jnp.concatenate([ctx.r_eci_m, ctx.v_eci_mps]), held)


def _stacked(params, start, end, steps):
    return steps


def _no_metrics(params, cycles, n_steps_total, run_s):
    return {}, jnp.asarray(False)


TRUTH = StateModel(NAME, _no_state, _truth_step, _stacked, _no_metrics)


def _filter_step(inner, params, state, ctx):
    new, record = inner(params, state, ctx)
    return new, (record, (state.x, state.p[:6, :6]))


def _filter_summary(inner, params, start, end, steps):
    return inner(params, start, end, steps[0]), steps[1]


@functools.lru_cache(maxsize=None)
def recording(model: StateModel) -> StateModel:
    """``model`` (a navigation filter's) whose step record adds (estimate [6], covariance [6, 6]) at the step's
    start and whose cycle record is (its own, those stacked); one object per model (a static argument)."""
    return model._replace(step=functools.partial(_filter_step, model.step),
                          summary=functools.partial(_filter_summary, model.summary))


def with_recording(states: tuple[StateModel, ...]) -> tuple[StateModel, ...]:
    """The loop's further states that record the ephemeris: the filter recording, ``TRUTH`` appended."""
    return tuple(recording(m) if m.name == navigation.NAME else m for m in states) + (TRUTH,)


def split(records):
    """(``records`` as without the recording, ``Ephemeris``) of records made ``with_recording`` (arrays or their
    shapes; leading axes as the records')."""
    states = dict(records.cycles.states)
    truth, thrust = states.pop(NAME)
    estimate = covariance = None
    if navigation.NAME in states:
        states[navigation.NAME], (estimate, covariance) = states[navigation.NAME]
    return records._replace(cycles=records.cycles._replace(states=states)), Ephemeris(truth, estimate, covariance, thrust)
