"""Metrics and status of a rollout, in JAX so a batch computes them inside ``vmap`` (docs/design.md "Contracts").

One function, ``summarize``, for every controller: units are in the names,
Delta-V per year is scaled here and nowhere else, and the status code is
computed here, inside the rollout's ``jit``:

    0 ok
    1 cycles without a solution (the controller's ``"solved"`` record was false in some cycle)
    2 left the longitude box  (|lambda - lambda_station| > station.box_half_width_deg at some step start)
    3 left the latitude box   (|geocentric latitude| > station.box_half_width_deg at some step start)
    4 non-finite or non-physical state (NaN / inf, or no mass left)
    5 propellant exhausted (the mass reached spacecraft.dry_mass_kg; the thrusters stopped there)
    6 and up: the parts' failures (``geojax.states``: each registered part's statuses in the registry's order,
      6 the wheels saturated; then a user's own parts'), ``STATUS_MEANINGS`` generated from them

in that order of precedence (4, 5, the parts', then 2, 3, 1): a part's failure (saturated wheels: the attitude
the loop assumes is lost) makes the later box checks meaningless, so the failure is what it reports; the
sample is kept, never dropped.  Each part the loop carries adds its metrics (``StateModel.metrics``).  The box is checked on the
osculating sub-satellite point at every step start of the whole run, the
acquisition included (Katz 2025 eq. (10)); a sample with status 4 gets
finite placeholders (0) for its non-finite metrics, so no NaN reaches a
neighbour's statistics.  Burn metrics (Li 2022 eqs. (45)-(46)) are added
for the planners, whose records carry ``control.burns`` records.

Runs of a year or more also get the Delta-V of each whole year (``dv_year<k>_mps``,
``YEAR_CYCLES`` cycles each, scaled to 365.25 days like ``dv_per_year_mps``),
and runs of two years or more the steady-state figure ``dv_steady_per_year_mps``:
the mean of the years after the first, whose acquisition and start it leaves
out.  Compare them only between runs over the same calendar years: the lunar
node's 18.6-year cycle moves the yearly Delta-V by several per cent.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from geojax.control.burn_metrics import ns_delta_v_mps
from geojax.physics.constants import SECONDS_PER_DAY, SECONDS_PER_YEAR, SIDEREAL_DAY_S
from geojax.physics.elements import wrap_angle
from geojax.params import station_target
from geojax.reductions import mean_over_cycles, sum_over_cycles
from geojax import states as parts

YEAR_CYCLES = round(SECONDS_PER_YEAR / SIDEREAL_DAY_S)  # 366 sidereal-day cycles: the cycles of a one-year run
(STATUS_OK, STATUS_NO_SOLUTION, STATUS_LEFT_LON_BOX, STATUS_LEFT_LAT_BOX, STATUS_NONFINITE,
 STATUS_NO_PROPELLANT) = range(len(parts.CORE_STATUSES))
STATUS_MEANINGS = parts.status_meanings()  # the loop's, then the registered parts'
STATUS_TEXT = ", ".join(f"{code} {text}" for code, text in enumerate(STATUS_MEANINGS))

# Per-cycle series a sweep may keep (``cycles = true``).
CYCLE_NAMES = ("lon_deg", "ex", "ey", "ix", "iy", "dv_mps", "ns_fraction")


def summarize(params, final, records, step_s: float, steps_per_cycle: int, states: tuple = (),
              controller_metrics=None) -> dict:
    """{name: scalar} of one rollout (``loop.simulate``'s final state and records), ``"status"`` included;
    ``states``: the models the loop carried (static; their metrics and status codes); ``controller_metrics``: the
    controller's own (``Controller.metrics``), else the thrusters' duty per axis."""
    cycles = records.cycles
    m = cycles.means
    n_cycles = m.lon_rad.shape[0]
    cycle_s = steps_per_cycle * step_s
    n_steps_total = n_cycles * steps_per_cycle
    first = 1 if n_cycles > 1 else 0  # the first cycle is acquisition for the mean-element metrics
    target = station_target(params.station)
    dlon_max, dlon_min = jnp.max(cycles.dlon_max_rad), jnp.min(cycles.dlon_min_rad)
    lat_max, lat_min = jnp.max(cycles.lat_max_rad), jnp.min(cycles.lat_min_rad)
    abs_dlon = jnp.maximum(jnp.abs(dlon_max), jnp.abs(dlon_min))
    abs_lat = jnp.maximum(jnp.abs(lat_max), jnp.abs(lat_min))
    solved = cycles.controller.get("solved", jnp.ones(n_cycles, bool))
    out = {
        "dv_per_year_mps": (final.dv_mps - params.initial.dv_mps) * SECONDS_PER_YEAR / (n_cycles * cycle_s),
        "mass_used_kg": params.initial.mass_kg - final.mass_kg,
        "max_abs_dlon_deg": jnp.degrees(abs_dlon),
        "max_abs_dlat_deg": jnp.degrees(abs_lat),
        "mean_dlon_deg": jnp.degrees(sum_over_cycles(cycles.dlon_sum_rad) / n_steps_total),
        "dlon_half_range_deg": jnp.degrees(dlon_max - dlon_min) / 2,
        "dlat_half_range_deg": jnp.degrees(lat_max - lat_min) / 2,
        "max_abs_mean_dlon_deg": jnp.max(jnp.abs(jnp.degrees(wrap_angle(m.lon_rad[first:] - target[0])))),
        "max_abs_de": jnp.max(jnp.hypot(m.ex[first:] - target[2], m.ey[first:] - target[3])),
        "max_abs_di": jnp.max(jnp.hypot(m.ix[first:] - target[4], m.iy[first:] - target[5])),
        "cycles_without_solution": jnp.sum(~solved).astype(float),
    }
    out.update(yearly_dv(cycles.dv_mps, cycle_s))
    own = {} if controller_metrics is None else controller_metrics(params, cycles, n_cycles * cycle_s,
                                                                   jnp.ones(n_cycles, bool))
    out.update(own if "duty_fraction" in own else {**duty_metrics(cycles, n_steps_total), **own})
    lon_out, lat_out = box_exits(params, cycles)
    failures = []  # (failed, code) of the parts, in their order
    meanings = parts.status_meanings(states)
    for model in _models(states, cycles.states):
        values, failed = model.metrics(params, cycles.states[model.name], n_steps_total, n_cycles * cycle_s)
        out.update(values)
        if model.status is not None:
            failures.append((failed, meanings.index(model.status)))
        if model.box_metrics is not None:
            out.update(model.box_metrics(params, cycles.states[model.name], lon_out | lat_out, cycle_s))
    finite = jnp.all(jnp.isfinite(final.orbit)) & (final.mass_kg > 0)
    for value in out.values():
        finite &= jnp.isfinite(value)
    status = jnp.where(jnp.any(lon_out), STATUS_LEFT_LON_BOX,
                       jnp.where(jnp.any(lat_out), STATUS_LEFT_LAT_BOX,
                                 jnp.where(out["cycles_without_solution"] > 0, STATUS_NO_SOLUTION, STATUS_OK)))
    for failed, code in reversed(failures):
        status = jnp.where(failed, code, status)
    status = jnp.where(~finite, STATUS_NONFINITE,
                       jnp.where(final.mass_kg <= params.spacecraft["dry_mass_kg"], STATUS_NO_PROPELLANT, status))
    out = {k: jnp.where(jnp.isfinite(v), v, 0.0) for k, v in out.items()}
    return {**out, "status": status.astype(jnp.int8)}


def box_exits(params, cycles):
    """([n_cycles] bool, [n_cycles] bool): whether some step start of each cycle has the osculating sub-satellite
    point outside the box in longitude (|lambda - lambda_station| > station.box_half_width_deg), and in latitude
    (|geocentric latitude| > the same).  The status' box check is whether any cycle does (statuses 2 and 3)."""
    box = params.station["box_half_width_rad"]
    lon_out = jnp.maximum(jnp.abs(cycles.dlon_max_rad), jnp.abs(cycles.dlon_min_rad)) > box
    lat_out = jnp.maximum(jnp.abs(cycles.lat_max_rad), jnp.abs(cycles.lat_min_rad)) > box
    return lon_out, lat_out


def yearly_dv(dv_mps, cycle_s: float) -> dict:
    """The Delta-V of each whole year of ``YEAR_CYCLES`` cycles (``dv_mps`` [n_cycles] per cycle), per 365.25
    days: ``dv_year1_mps`` ...; with two years or more, ``dv_steady_per_year_mps``, the mean of the years after
    the first.  None for a run shorter than a year."""
    n_years = dv_mps.shape[0] // YEAR_CYCLES
    if n_years == 0:
        return {}
    years = sum_over_cycles(dv_mps[:n_years * YEAR_CYCLES].reshape(n_years, YEAR_CYCLES).T)
    years = years * SECONDS_PER_YEAR / (YEAR_CYCLES * cycle_s)
    out = {f"dv_year{k + 1}_mps": years[k] for k in range(n_years)}
    if n_years >= 2:
        out["dv_steady_per_year_mps"] = mean_over_cycles(years[1:])
    return out


def duty_metrics(cycles, n_steps_total: int) -> dict:
    """How much the thrusters fire, for a controller that says nothing of its own (``Controller.metrics``; the
    planners' burns say ``duty_fraction``, ``control.burns.metrics``): ``duty_x``, ``duty_y``, ``duty_z``, the
    fraction of the steps whose delivered acceleration has an ECEF x, y, z component, Katz 2025's duty cycle of
    per-axis thrusters (its discrete law; thrust in any other direction has all three components, so the three
    are equal, its firing fraction)."""
    duty = jnp.sum(cycles.firing_steps, axis=0) / n_steps_total
    return {"duty_x": duty[0], "duty_y": duty[1], "duty_z": duty[2]}


def cycle_series(records, states: tuple = ()) -> dict:
    """The per-cycle series a sweep keeps (JAX): ``CYCLE_NAMES`` (mean longitude (deg), e and i vectors (MEE f, g,
    h, k), the Delta-V delivered in the cycle (m/s) and the north-south fraction flown, 1 without a planner), then
    the columns of every extra state the loop carries (``state_columns``: the wheels', the filter's), the same for
    every controller of a sweep (the states come from the scenario, not the controller)."""
    c = records.cycles
    m = c.means
    return {"lon_deg": jnp.degrees(m.lon_rad), "ex": m.ex, "ey": m.ey, "ix": m.ix, "iy": m.iy, "dv_mps": c.dv_mps,
            "ns_fraction": c.controller.get("ns_fraction", jnp.ones_like(c.dv_mps)), **state_columns(c.states, states)}


def state_columns(records: dict, states: tuple = ()) -> dict:
    """The per-cycle columns of the parts' records (``StateModel.columns``; ``states``: the models carried, a
    registered part found by its name where not given)."""
    table = {}
    for model in _models(states, records):
        if model.columns is not None:
            table.update(model.columns(records[model.name]))
    return table


def _models(states: tuple, records: dict) -> tuple:
    """The model of each part whose records are in ``records``: from ``states``, else the registered one."""
    given = {m.name: m for m in states}
    registered = {p.name: p for p in parts.REGISTRY}
    out = []
    for name in records:
        model = given.get(name) or getattr(registered.get(name), "model", None)
        if model is None:
            raise ValueError(f"states: records of part {name!r}, which is neither registered nor given")
        out.append(model)
    return tuple(out)


def cycle_table(records, states: tuple = ()) -> dict[str, np.ndarray]:
    """Every per-cycle record in its edge units (the ``/cycles`` datasets): mean elements, and for a planner
    its burns."""
    c = records.cycles
    m = c.means
    table = {
        "t_s": m.t_s, "lon_deg": np.degrees(m.lon_rad), "drift_deg_per_day": np.degrees(m.drift_rad_s) * SECONDS_PER_DAY,
        "ex": m.ex, "ey": m.ey, "ix": m.ix, "iy": m.iy, "a_m": m.a_m,
        "max_abs_lat_deg": np.degrees(np.maximum(np.abs(c.lat_min_rad), np.abs(c.lat_max_rad))),
        "dv_mps": c.dv_mps,
    }
    rec = c.controller
    if "fired_s" in rec:
        burns, fired = rec["burns"], rec["fired_s"] > 0
        table.update({
            "v1_mps": np.where(fired[:, 0], burns.v_mps[:, 0], 0.0),
            "v2_mps": np.where(fired[:, 1], burns.v_mps[:, 1], 0.0),
            "alpha1_deg": np.degrees(burns.alpha_rad[:, 0]), "beta1_deg": np.degrees(burns.beta_rad[:, 0]),
            "alpha2_deg": np.degrees(burns.alpha_rad[:, 1]), "beta2_deg": np.degrees(burns.beta_rad[:, 1]),
            "l1_deg": np.degrees(np.mod(burns.l_rad[:, 0], 2 * np.pi)),
            "dv_ns_mps": np.asarray(ns_delta_v_mps(rec)),
            "burn1_s": rec["fired_s"][:, 0], "burn2_s": rec["fired_s"][:, 1],
            "ns_fraction": rec["ns_fraction"],
        })
    if "zone" in rec:  # control.zone_nssk: the working condition (0 normal) and what the planner saw
        table.update({
            "zone": np.asarray(rec["zone"]).astype(np.int8),
            "i_filtered_x_deg": np.degrees(rec["i_filtered_rad"][:, 0]),
            "i_filtered_y_deg": np.degrees(rec["i_filtered_rad"][:, 1]),
            "burn_ns_s": rec["burn_ns_s"], "tilt_deg": np.degrees(rec["tilt_rad"]),
        })
    if "solved" in rec:
        table["status"] = np.where(rec["solved"], 0, 1).astype(np.int8)
    if "recovering" in rec:
        table["recovering"] = np.asarray(rec["recovering"]).astype(np.int8)
    table.update(state_columns(c.states, states))
    return {k: np.asarray(v) for k, v in table.items()}


def step_table(records, step_s: float, station_lon_rad: float) -> dict[str, np.ndarray]:
    """The per-step records of a single rollout kept with ``keep_steps`` (the ``/steps`` datasets): time since
    the start (s), longitude offset from the station and latitude (deg), delivered acceleration (ECEF, m/s^2)."""
    steps = records.steps
    u = np.asarray(steps.accel_ecef_mps2).reshape(-1, 3)
    return {"t_s": np.arange(u.shape[0]) * step_s,
            "dlon_deg": np.degrees(np.asarray(wrap_angle(np.asarray(steps.lon_rad).ravel() - station_lon_rad))),
            "lat_deg": np.degrees(np.asarray(steps.lat_rad).ravel()),
            "ux_mps2": u[:, 0], "uy_mps2": u[:, 1], "uz_mps2": u[:, 2]}
