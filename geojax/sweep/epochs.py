"""The epoch as a sweep axis: one slot flown from many dates (the lifetime budgets of `studies/lifetime/`).

A sweep file's grid may hold the key ``"epoch.utc"`` with a list of ISO 8601 UTC dates::

    [grid]
    "epoch.utc" = ["2027-01-01T12:00:00", "2028-01-01T12:00:00", ...]

Each date moves the sweep's base scenario in time as ``scenario.started_at`` does: the same initial orbit
relative to the Earth (the same geographic longitude, the true longitude turned by the Earth angle between the
two epochs), the same station, the same [set] keys.  So the axis answers "what does this slot cost in year
Y", which is what a lifetime budget or the 18.6-year lunar node cycle asks; a plain ``[set] "epoch.utc"``
keeps the scenario's inertial elements, as a scenario file does.

Design: the Sun and Moon stay batch-invariant (docs/design.md, "Ephemerides are batch-invariant").  The points of
one epoch form a group that shares its environment grid (Sun, Moon, Earth angle at every RK4 stage), its
predictor reference and its Earth angle at the start (the dispersion's ECEF offsets); a compiled call never
mixes two epochs, and the one compiled program takes those arrays as arguments, so it is compiled once and
re-used for every epoch (their shapes are the same: the duration, the step and the dynamics must not vary).
Making the environment a per-sample leaf instead would carry a year of Sun and Moon per lane (tens of MB),
evaluate the force model's ephemeris inputs per sample per stage, and break the fusion of what the batch
shares; chunks and resume are unchanged because the grouping is inside a chunk's calls, not in its cut.
A call's lanes beyond an epoch's samples are padded with its last sample, so an epoch with fewer samples than
the width (the CPU's ``Sizing.lanes_cpu`` per device) wastes the rest: set ``lanes`` to about the samples of
one epoch per device (a sample's numbers do not depend on the width).
Everything here is host-side orchestration; the engine does not know about the axis.
"""

from __future__ import annotations

import datetime as dt

import numpy as np

KEY = "epoch.utc"
# What depends on the epoch and so may differ between the groups, though not within one (runner.setup.STATIC_KEYS).
STATIC_KEYS = ("epoch.utc", "epoch.ut1_minus_utc_s")


def check_values(values: list) -> None:
    """The dates of an epoch axis: ISO 8601 strings, distinct (``ValueError`` naming ``grid.epoch.utc``; each
    date's range against the ephemeris is checked when its scenario is loaded)."""
    from geojax.physics.time import parse_utc

    for value in values:
        if not isinstance(value, str):
            raise ValueError(f"grid.{KEY}: must be a list of ISO 8601 UTC dates such as \"2027-01-01T12:00:00\", "
                             f"got {value!r}")
        try:
            parse_utc(value)
        except ValueError as err:
            raise ValueError(f"grid.{err}") from None
    moments = [as_utc(v) for v in values]
    if len(set(moments)) != len(moments):
        raise ValueError(f"grid.{KEY}: the dates must be distinct, got {values!r}")


def scenario_at(name_or_path, utc: str, overrides: dict, controller=None):
    """The sweep's base scenario (``name_or_path`` with ``overrides``) moved to ``utc`` at the same geographic
    longitude (``scenario.started_at``)."""
    from geojax import scenario

    return scenario.started_at(name_or_path, utc, overrides, controller)


def groups(points: list[dict]) -> list[np.ndarray]:
    """The indices of the grid points of each epoch, in the order the epochs first appear (one group, every
    point, where the grid has no epoch axis)."""
    if not points or KEY not in points[0]:
        return [np.arange(len(points))]
    epochs = [p[KEY] for p in points]
    order = list(dict.fromkeys(epochs))
    return [np.array([i for i, e in enumerate(epochs) if e == value]) for value in order]


def as_utc(value) -> dt.datetime:
    """A date of the axis as a naive UTC ``datetime`` (bytes as read from HDF5 accepted)."""
    from geojax.physics.time import parse_utc

    text = value.decode() if isinstance(value, bytes) else str(value)
    moment = parse_utc(text)
    return moment.astimezone(dt.timezone.utc).replace(tzinfo=None) if moment.tzinfo is not None else moment


def as_datetime64(values) -> np.ndarray:
    """The axis's dates as ``datetime64[s]`` (the coordinate ``geojax.open_results`` gives)."""
    return np.array([as_utc(v) for v in values], dtype="datetime64[s]")


def as_years(values) -> np.ndarray:
    """The axis's dates as decimal years (2027.0 at 2027-01-01T00:00), for a numeric plot axis."""
    out = []
    for moment in (as_utc(v) for v in values):
        start, end = dt.datetime(moment.year, 1, 1), dt.datetime(moment.year + 1, 1, 1)
        out.append(moment.year + (moment - start) / (end - start))
    return np.array(out)
