"""Orbit determination in the loop, a part selected by ``navigation.model = "ekf"``: an extended Kalman filter on
ground-station tracking (or a GNSS-in-GEO receiver) and the burns' execution errors.

The controller plans from the filter's estimate, and every burn is flown with drawn errors the filter knows only
statistically. This module is the part: its hooks on the loop (``init``, ``cycle``, ``thrust``, ``step``,
``estimate``), its records, metrics, columns and descriptions, and its ``PART``; the filter's pure pieces are
``geojax.navigation`` (``state``, ``leaves``, ``execution``, ``prediction``, ``updates``, ``ekf``). The model and
its equations: docs/navigation.md ("The filter")."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from geojax.navigation import ekf
from geojax.navigation.execution import execution_prior, reset_execution
from geojax.physics.execution import truth_of
from geojax.navigation.keys import FIELDS as KEYS, check_with
from geojax.navigation.leaves import bias_sigmas, initial_cartesian, layout_of, leaves_of, n_biases
from geojax.navigation.prediction import elements_of, error_state_prediction, transition
from geojax.navigation.schedule import station_schedules, tracking_weight
from geojax.navigation.state import N_STATE, Layout, Navigation, NavigationCycle, n_estimated
from geojax.navigation.updates import measurement_updates, tracking_weights
from geojax.physics.dynamics import Thrust
from geojax.physics.frames import rsw_basis
from geojax.physics.fusion import skipped_where_idle
from geojax.reductions import mean_over_cycles, percentile_over_cycles, sum_in_order, sum_over_cycles
from geojax.states.base import NAVIGATION_STREAM, STATION_PASSES, Part, StateModel

NAME = "navigation"
# ``fold_in`` constants of the model's draws from its cycle key (the step's draws fold the step index into
# MEASUREMENT_KEY first).
INITIAL_KEY, BIAS_KEY, MEASUREMENT_KEY = 0, 1, 2


def init(layout: Layout, params, r_eci_m, v_eci_mps, env, fm) -> Navigation:
    """The filter at the run's start: the true elements (``cycle`` adds the initial error at cycle 0) and the
    initial covariance diag(sigma_r^2 I, sigma_v^2 I); no burn."""
    nav = params.states[NAME]
    n_b = n_biases(layout)
    p = jnp.zeros((N_STATE + n_b, N_STATE + n_b)).at[:6, :6].set(initial_cartesian(nav))
    if n_b:  # the estimated biases' prior: the sigmas they are drawn with, uncorrelated
        p = p.at[N_STATE:, N_STATE:].set(jnp.diag(bias_sigmas(nav, layout) ** 2))
    zero = jnp.zeros_like(r_eci_m[0])
    return Navigation(jnp.concatenate([r_eci_m, v_eci_mps]), jnp.zeros(4), p, jax.random.key(0), jnp.asarray(0),
                      jnp.zeros(bias_sigmas(nav, layout).shape[0]), jnp.zeros(4), jnp.asarray(False), jnp.zeros(3),
                      zero, zero, zero, jnp.zeros(6), jnp.zeros(6), zero, zero, zero, zero,
                      **({"bias_estimate": jnp.zeros(n_b), "bias_error": jnp.zeros(n_b), "bias_sigma": jnp.zeros(n_b)}
                         if n_b else {}))


def cycle(layout: Layout, params, state: Navigation, start) -> Navigation:
    """At a cycle start: the cycle's key; at cycle 0 the initial estimate error (Gaussian, the initial
    covariance) and the sample's biases; the estimation error, 1-sigma and NEES at this decision time; the
    cycle's sums reset."""
    nav = params.states[NAME]
    first = start.index == 0
    truth = jnp.concatenate([start.r_eci_m, start.v_eci_mps])
    drawn = truth + jnp.sqrt(jnp.diag(initial_cartesian(nav))) * jax.random.normal(
        jax.random.fold_in(start.key, INITIAL_KEY), (6,))
    x = jnp.where(first, drawn, state.x)
    bias = jnp.where(first, bias_sigmas(nav, layout) * jax.random.normal(
        jax.random.fold_in(start.key, BIAS_KEY), state.bias.shape), state.bias)
    cov = state.p[:6, :6]
    basis = rsw_basis(start.r_eci_m, start.v_eci_mps)  # rows R, S, W
    rot = jnp.zeros((6, 6)).at[:3, :3].set(basis).at[3:, 3:].set(basis)
    error = x - truth
    zero = jnp.zeros_like(state.nees)
    state = state._replace(x=x, key=start.key, step_index=jnp.zeros_like(state.step_index), bias=bias,
                           error_rsw=rot @ error, sigma_rsw=jnp.sqrt(jnp.diag(rot @ cov @ rot.T)),
                           nees=ekf.nees(error, cov), nis_sum=zero, nis_dof=zero, measurements=zero)
    if n_estimated(state):
        state = state._replace(bias_error=state.bias_estimate - bias,
                               bias_sigma=jnp.sqrt(jnp.diag(state.p)[N_STATE:]))
    return state


def thrust(layout: Layout, params, state: Navigation, flown: Thrust, ctx):
    """The thrust flown (no burn while a station tracks where ``burns_during_passes`` is 0) and the state noting
    the plan for ``step``: the planned thrust the controller says it flew with the truth's execution errors
    (``Thrust.planned_direction_rsw``; none said: flown as planned), those errors read back from the two
    (``physics.execution.truth_of``), and at each burn's start the filter's estimate of them reset to its prior."""
    nav = params.states[NAME]
    if layout.stations:  # burns forbidden while a station's schedule is on (where ``burns_during_passes`` is 0)
        in_pass = jnp.any(jax.vmap(tracking_weight, in_axes=(None, 0))(ctx.t_s, station_schedules(nav)) > 0)
        allowed = jnp.where(in_pass, nav["burns_during_passes"], 1.0)
        flown = flown._replace(on_fraction=flown.on_fraction * allowed)
    planned_rsw = flown.direction_rsw if flown.planned_direction_rsw is None else flown.planned_direction_rsw
    planned_n = flown.thrust_n if flown.planned_thrust_n is None else flown.planned_thrust_n
    firing = (flown.on_fraction > 0) & (planned_n > 0)
    new_burn = firing & ~state.firing
    eps, phi = truth_of(planned_rsw, planned_n, flown.direction_rsw, flown.thrust_n)
    truth = jnp.where(firing, jnp.concatenate([eps[None], phi]), state.truth_execution)
    prior = reset_execution(state.p, execution_prior(nav["burn_magnitude_sigma"], nav["burn_pointing_sigma_rad"],
                                                     planned_rsw))
    state = state._replace(p=jnp.where(new_burn, prior, state.p),
                           execution=jnp.where(new_burn, 0.0, state.execution), truth_execution=truth, firing=firing,
                           planned_direction_rsw=planned_rsw, planned_thrust_n=planned_n,
                           planned_on_fraction=flown.on_fraction, isp_s=flown.isp_s)
    return state, flown


def step(layout: Layout, params, state: Navigation, ctx):
    """One integration step: the time update (planned thrust, SNC) and the measurement updates at the step's end
    (skipped for a whole batch where no sample tracks: most steps of a pass schedule)."""
    nav, fm = params.states[NAME], ctx.force_model
    mu = fm.mu_m3_s2
    n_b = n_estimated(state)
    start = jnp.concatenate([ctx.r_eci_m, ctx.v_eci_mps])
    f = transition(start, ctx.mass_kg, state, ctx.step_s, mu)
    x = error_state_prediction(layout, f, state, ctx, start)
    p = f @ state.p @ f.T
    p = (0.5 * (p + p.T)).at[:6, :6].add(ekf.process_noise(ctx.step_s, nav["snc_mps2_per_rthz"]))  # symmetric
    truth = jnp.concatenate([ctx.r_end_eci_m, ctx.v_end_eci_mps])
    angle = ctx.env.earth_angle_rad[2]
    weights = tracking_weights(layout, nav, ctx.t_s + ctx.step_s, truth[:3], angle)
    key = jax.random.fold_in(jax.random.fold_in(state.key, MEASUREMENT_KEY), state.step_index)
    # the filter as one flat vector: the gate's vmap rule handles one array out
    packed = jnp.concatenate([x, state.execution, p.ravel(), jnp.stack([state.nis_sum, state.nis_dof,
                                                                       state.measurements]),
                              *([state.bias_estimate] if n_b else [])])
    args = (packed, weights, nav, truth, angle, state.bias, jax.random.key_data(key), mu)
    leaves, tree = jax.tree_util.tree_flatten(args)  # every array an argument: the gate closes over none

    def updates(*leaves):
        packed, weights, nav, truth, angle, bias, key, mu = jax.tree_util.tree_unflatten(tree, leaves)
        out = measurement_updates(layout, mu, _unpacked(packed, n_b), weights, nav, truth, angle, bias,
                       jax.random.wrap_key_data(key))
        return jnp.concatenate([out[0], out[1], out[2].ravel(), jnp.stack(out[3:6]), *([out[6]] if n_b else [])])

    packed = skipped_where_idle(updates, lambda *a: jnp.any(jax.tree_util.tree_unflatten(tree, a)[1] > 0),
                                lambda *a: a[0], *leaves)
    x, execution, p, nis_sum, nis_dof, used, bias_estimate = _unpacked(packed, n_b)
    return state._replace(x=x, execution=execution, p=p, step_index=state.step_index + 1, nis_sum=nis_sum,
                          nis_dof=nis_dof, measurements=used, bias_estimate=bias_estimate), ()


def _unpacked(packed, n_b: int = 0):
    """(x [6], execution [4], P [n, n], NIS sum, its dof, measurements, bias estimate [n_b]) of the flat vector
    ``step`` packs (n = 10 + n_b)."""
    size = N_STATE + n_b
    n = size * size
    return (packed[:6], packed[6:10], packed[10:10 + n].reshape(size, size), packed[10 + n],
            packed[11 + n], packed[12 + n], packed[13 + n:13 + n + n_b] if n_b else None)


def estimate(params, state: Navigation, told):
    """What the controller is told at a cycle start: the filter's estimate as the fix (its elements, L continuous
    with the truth's, as the Gaussian fix's is) and the covariance [6, 6] of its ECI (r, v) in
    ``states["navigation"]``."""
    fix = elements_of(state.x, told.fix_mee, params.forces.mu_m3_s2)
    nav = params.states[NAME]
    return told._replace(fix_mee=fix, states={**told.states, NAME: state.p[:6, :6],
                                              STATION_PASSES: station_schedules(nav)})


def summary(params, start: Navigation, end: Navigation, steps) -> NavigationCycle:
    """The cycle's record: the decision time's error, 1-sigma and NEES; the cycle's NIS sums and measurements."""
    return NavigationCycle(start.error_rsw, start.sigma_rsw, start.nees, end.nis_sum, end.nis_dof, end.measurements,
                           start.bias_error, start.bias_sigma)


AXES = ("radial", "along", "cross")


def metrics(params, cycles: NavigationCycle, n_steps_total: int, run_s: float):
    """({name: []}, False): the estimation error at the decision times (RMS and 95th percentile of |error| per RSW
    axis, position and velocity), NEES averaged over them, NIS averaged per degree of freedom over every update,
    the measurement components used.  The filter never fails a sample."""
    out = {}
    for k, axis in enumerate(AXES):
        for offset, unit in ((0, "m"), (3, "mps")):
            e = cycles.error_rsw[:, offset + k]
            out[f"nav_{axis}_rms_{unit}"] = jnp.sqrt(mean_over_cycles(e**2))
            out[f"nav_{axis}_p95_{unit}"] = percentile_over_cycles(jnp.abs(e), 95.0)
    out["nav_position_rms_m"] = jnp.sqrt(mean_over_cycles(sum_in_order(cycles.error_rsw[:, :3] ** 2)))
    out["nees_mean"] = mean_over_cycles(cycles.nees)
    dof = sum_over_cycles(cycles.nis_dof)
    out["nis_mean_per_dof"] = sum_over_cycles(cycles.nis_sum) / jnp.where(dof > 0, dof, 1.0)
    out["measurements_used"] = sum_over_cycles(cycles.measurements)
    return out, jnp.asarray(False)


def columns(cycles: NavigationCycle) -> dict:
    """The per-cycle series in edge units: error and 1-sigma at each decision time per RSW axis, NEES, NIS per
    degree of freedom, measurements."""
    error, sigma = cycles.error_rsw, cycles.sigma_rsw
    out = {}
    for k, axis in enumerate(AXES):  # [..., k]: one sample's records or a batch's (a sweep's, traced)
        out[f"nav_error_{axis}_m"], out[f"nav_sigma_{axis}_m"] = error[..., k], sigma[..., k]
        out[f"nav_error_{axis}_mps"], out[f"nav_sigma_{axis}_mps"] = error[..., 3 + k], sigma[..., 3 + k]
    out["nees"] = cycles.nees
    dof = cycles.nis_dof
    out["nis_per_dof"] = cycles.nis_sum / jnp.where(dof > 0, dof, 1.0)
    out["measurements"] = cycles.measurements
    for i in range(0 if cycles.bias_error is None else cycles.bias_error.shape[-1]):  # each estimated bias's
        out[f"nav_bias_error_{i}"], out[f"nav_bias_sigma_{i}"] = cycles.bias_error[..., i], cycles.bias_sigma[..., i]
    return out


@functools.lru_cache(maxsize=None)
def model(layout: Layout) -> StateModel:
    """The filter for a layout: one object per layout (a static argument of the compiled loop)."""
    n_b = n_biases(layout)  # NavigationCycle: 16 values, and each estimated bias's error and sigma
    return StateModel(NAME, functools.partial(init, layout), functools.partial(step, layout), summary, metrics,
                      cycle=functools.partial(cycle, layout), columns=columns,
                      thrust=functools.partial(thrust, layout), estimate=estimate,
                      columns_per_cycle=15 + 2 * n_b, stream=NAVIGATION_STREAM, navigates=True)


# The registry's entry (metrics and columns, which do not depend on the layout).
MODEL = model(Layout((), False, "loop"))

DESCRIBED_AXES = tuple(zip(AXES, ("radial", "along-track", "cross-track")))
DESCRIBED_UNITS = (("m", "position"), ("mps", "velocity"))
DESCRIPTIONS = {
    **{f"nav_{axis}_{stat}_{unit}": f"{what_stat} of the filter's {name} {what} error at the decision times"
       for axis, name in DESCRIBED_AXES for unit, what in DESCRIBED_UNITS
       for stat, what_stat in (("rms", "RMS"), ("p95", "95th percentile of the magnitude"))},
    "nav_position_rms_m": "RMS of the filter's position error (3-D) at the decision times",
    "nees_mean": "the filter's NEES (6 dof: position and velocity) averaged over the decision times; 6 if consistent",
    "nis_mean_per_dof": "the filter's NIS per degree of freedom over every measurement update; 1 if consistent",
    "measurements_used": "measurement components the filter processed over the run",
    **{f"nav_{kind}_{axis}_{unit}": f"the filter's {name} {what} {label} at the cycle start"
       for axis, name in DESCRIBED_AXES for unit, what in DESCRIBED_UNITS
       for kind, label in (("error", "error (estimate - truth)"), ("sigma", "1-sigma"))},
    "nees": "the filter's NEES at the cycle start (6 dof)",
    "nis_per_dof": "the filter's NIS per degree of freedom over the cycle's updates",
    "measurements": "measurement components the filter processed in the cycle",
}


PART = Part(NAME, table="navigation", fields=KEYS,
            select=lambda table: model(layout_of(table)) if table["model"] == "ekf" else None,
            leaves=leaves_of, validate=check_with, descriptions=DESCRIPTIONS, figures="geojax.plots.parts:navigation_figures",
            model=MODEL,  # its metrics and columns, which do not depend on the layout
            tells=lambda table: (STATION_PASSES,) if table["stations"] else (),
            tells_how={STATION_PASSES: 'navigation.model = "ekf" with [[navigation.stations]]'})
