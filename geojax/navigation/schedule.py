"""When a station (or a GNSS receiver) tracks: a 0/1 weight as a pure function of time.

A schedule is passes of ``pass_s`` every ``cadence_s``, the first starting at ``phase_s``, less outages; a
continuous track is a pass as long as its cadence.  Times are seconds since the start of the run.  The weight
multiplies a measurement's gain in the filter (``ekf.measurement_update``), so a measurement outside the
schedule changes nothing and no Python branch is taken on time.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp


class Schedule(NamedTuple):
    """Leaves may carry leading axes (stations); ``outages_s`` is padded to a common count with empty windows."""

    cadence_s: jnp.ndarray  # [] time from one pass's start to the next
    pass_s: jnp.ndarray  # [] length of a pass, <= cadence_s (equal: continuous)
    phase_s: jnp.ndarray  # [] start of a pass (any one), s since the start of the run
    outages_s: jnp.ndarray  # [n, 2] windows [start, stop) without tracking; [0, 2] for none


def schedule(cadence_s, pass_s, phase_s=0.0, outages_s=()) -> Schedule:
    """A ``Schedule`` of float64 leaves; ``outages_s`` a sequence of (start, stop) pairs."""
    outages = jnp.asarray(outages_s, dtype=jnp.float64).reshape(-1, 2)
    return Schedule(jnp.asarray(cadence_s, jnp.float64), jnp.asarray(pass_s, jnp.float64),
                    jnp.asarray(phase_s, jnp.float64), outages)


def continuous(outages_s=()) -> Schedule:
    """Tracking at every time, except in the outages."""
    return schedule(1.0, 1.0, 0.0, outages_s)


def tracking_weight(t_s, plan: Schedule):
    """1.0 where ``t_s`` (any shape) falls in a pass and in no outage, else 0.0."""
    in_pass = jnp.mod(t_s - plan.phase_s, plan.cadence_s) < plan.pass_s
    t = jnp.asarray(t_s)[..., None]
    in_outage = jnp.any((t >= plan.outages_s[:, 0]) & (t < plan.outages_s[:, 1]), axis=-1)
    return jnp.where(in_pass & ~in_outage, 1.0, 0.0)


def station_schedules(nav: dict) -> Schedule:
    """The stations' schedules from ``Params.navigation``'s leaves (``states.navigation.leaves_of``), leaves
    [n_stations, ...]."""
    return Schedule(nav["station_cadence_s"], nav["station_pass_s"], nav["station_phase_s"], nav["station_outages_s"])


def time_in_passes_s(start_s, stop_s, plan: Schedule):
    """How long the window [``start_s``, ``stop_s``) spends in ``plan``'s passes (outages not counted), s; closed
    form for windows shorter than the cadence: the pass the window's start lies ``into`` (or the last one before
    it), [-into, pass - into) from the start, and the next one, [cadence - into, cadence - into + pass)."""
    length = jnp.maximum(stop_s - start_s, 0.0)
    into = jnp.mod(start_s - plan.phase_s, plan.cadence_s)
    this = jnp.clip(plan.pass_s - into, 0.0, length)
    following = jnp.clip(length - (plan.cadence_s - into), 0.0, plan.pass_s)
    return this + following


def overlaps_pass(start_s, stop_s, plan: Schedule):
    """Whether the window [``start_s``, ``stop_s``) meets a pass of ``plan`` (outages not counted: a pass in an
    outage still counts, the conservative reading); an empty window meets none.  Closed form for windows shorter
    than the cadence: the window's start lies ``into`` = (start - phase) mod cadence after a pass's start, so it
    starts inside that pass (into < pass) or reaches the next one (length > cadence - into)."""
    into = jnp.mod(start_s - plan.phase_s, plan.cadence_s)
    return (stop_s > start_s) & ((into < plan.pass_s) | (stop_s - start_s > plan.cadence_s - into))
