"""The orbit-determination filter in the closed loop (``geojax.states.navigation``).

Each test names its independent check: the state transition matrix written out against ``jax.jacfwd`` of the
filter's own MEE step (a second method), the filter's covariance in the loop against a batch least-squares
information matrix over the same measurements on a Kepler propagator (the Cramer-Rao bound), the burns'
execution errors against their drawn statistics, and the command line's contract for bad input.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import cli, scenario
from geojax.runner import rollout
from geojax.runner.setup import prepare
from geojax.loop.simulate import position_velocity
from geojax.navigation.measurements import MODELS
from geojax.physics.constants import OMEGA_EARTH_RAD_S
from geojax.physics.frames import rsw_basis
from geojax.navigation import leaves, prediction, updates
from geojax.navigation.execution import reset_execution
from geojax.physics.execution import executed
from geojax.states import navigation as nav

from test_navigation import _kepler

UNPERTURBED = {"forces.j2": False, "forces.sun": False, "forces.moon": False, "forces.srp": False}
NO_EXECUTION = {"errors.sigma3_dv_pct": 0.0, "errors.sigma3_att_deg": 0.0}


class Burning(NamedTuple):
    """The filter of li2022-qffc-ranging (uncontrolled) at the run's start, a burn planned over step 5."""

    sc: object
    step_s: float
    params: object
    env3: object
    truth: jnp.ndarray  # [6] the true r, v
    state: object  # ``states.navigation.Navigation``


@functools.lru_cache(maxsize=None)
def _burning() -> Burning:
    sc = scenario.load("li2022-qffc-ranging", {"duration.days": 1, "controller.kind": "none"})
    setup = prepare([sc])
    params = jax.tree_util.tree_map(lambda x: x[0], setup.params)
    fm, mu = params.forces, params.forces.mu_m3_s2
    env3 = jax.tree_util.tree_map(lambda x: x[0, 5], setup.shared.env)
    r0, v0 = position_velocity(setup.dynamics, params.initial.orbit, mu)
    state = setup.states[-1].init(params, r0, v0, jax.tree_util.tree_map(lambda x: x[0], env3), fm)
    direction = jnp.array([0.3, 0.9, -0.3]) / jnp.linalg.norm(jnp.array([0.3, 0.9, -0.3]))
    state = state._replace(planned_direction_rsw=direction, planned_thrust_n=jnp.asarray(0.5),
                           planned_on_fraction=jnp.asarray(0.7), isp_s=jnp.asarray(2250.0))
    return Burning(sc, setup.step_s, params, env3, jnp.concatenate([r0, v0]), state)


def _predicted(b: Burning, rv, execution, state):
    """r, v [6] one step on by the filter's direct prediction (RK4 of the MEE equations, the loop's forces)."""
    mu = b.params.forces.mu_m3_s2
    x = prediction.elements_of(rv, b.params.initial.orbit, mu)
    return prediction.rv_of(prediction.predict(x, execution, 5000.0, state, b.env3, b.params.forces, b.step_s), mu)


@pytest.mark.slow  # the suite's budget: the error-state test below checks the matrix's effect in the default tier
def test_transition_matrix_against_jacfwd_of_the_filter_step():
    """Second method: the written-out transition of (r, v, eps, phi) over a 900 s step while a burn fires,
    against jax.jacfwd of the filter's own step taken through the elements (r, v -> MEE -> RK4 with the loop's
    full force model -> r, v).  The terms the written-out one leaves out (J2's, the Sun's and the Moon's
    gradients, the thrust frame's turning) are below 1e-3 of each block's largest entry."""
    b = _burning()
    expected = jax.jacfwd(lambda y: jnp.concatenate([_predicted(b, y[:6], y[6:], b.state), y[6:]]))(
        jnp.concatenate([b.truth, jnp.zeros(4)]))
    got = prediction.transition(b.truth, 5000.0, b.state, b.step_s, b.params.forces.mu_m3_s2)
    for rows, cols in ((slice(0, 3), slice(0, 3)), (slice(0, 3), slice(3, 6)), (slice(3, 6), slice(0, 3)),
                       (slice(3, 6), slice(3, 6)), (slice(0, 6), slice(6, 10))):
        block, want = np.asarray(got[rows, cols]), np.asarray(expected[rows, cols])
        assert np.max(np.abs(block - want)) < 1e-3 * np.max(np.abs(want)), (rows, cols)
    assert np.array_equal(np.asarray(got[6:]), np.eye(10)[6:])


def test_error_state_prediction_is_the_direct_prediction():
    """Second method: the filter's prediction as the loop makes it (the truth's step plus the transition of the
    estimate's deviation) against the direct one (the estimate itself through RK4 of the loop's MEE equations
    with the planned thrust executed by its estimated errors), for an estimate 1 km and 0.1 m/s off the truth (tens
    of the scenario's sigmas) and execution errors a sigma apart (2 %, 0.1 deg per axis), a burn firing: within 5 mm
    and 5 um/s, below a thousandth of the scenario's sigmas (the remainder is second order: the terms the transition
    leaves out times the deviations, and the deviations' products)."""
    from geojax.physics.dynamics import Thrust
    from geojax.states.base import StepContext

    b = _burning()
    truth_e = jnp.array([0.02, 1e-3, -2e-3, 5e-4])
    estimate_e = truth_e + jnp.array([0.02, np.radians(0.1), -np.radians(0.1), np.radians(0.1)])
    state = b.state._replace(truth_execution=truth_e, execution=estimate_e)
    estimate = b.truth + jnp.array([600.0, -700.0, 387.3, 0.06, 0.05, -0.058])
    truth_end = _predicted(b, b.truth, truth_e, state)
    direct = _predicted(b, estimate, estimate_e, state)
    direction_flown, thrust_flown = executed(state.planned_direction_rsw, 0.5, truth_e[0], truth_e[1:])
    ctx = StepContext(jnp.asarray(0.0), b.step_s, b.env3, b.truth[:3], b.truth[3:], truth_end[:3], truth_end[3:],
                      jnp.asarray(5000.0), Thrust(direction_flown, thrust_flown, 2250.0, 0.7), b.params.forces)
    f = prediction.transition(b.truth, 5000.0, state, b.step_s, b.params.forces.mu_m3_s2)
    got = prediction.error_state_prediction(leaves.layout_of(b.sc.config["navigation"]), f,
                                            state._replace(x=estimate), ctx, b.truth)
    assert np.max(np.abs(np.asarray(got - direct)[:3])) < 5e-3
    assert np.max(np.abs(np.asarray(got - direct)[3:])) < 5e-6


@pytest.mark.slow
def test_filter_in_the_loop_reaches_the_cramer_rao_bound():
    """Independent method: an uncontrolled satellite under point-mass gravity, ranged by
    li2022-qffc-ranging's two stations at every step end for three days (continuous passes, 5 m), no execution
    errors or process noise.  The filter's 1-sigma in R, S, W at the fourth cycle start (recorded by the loop)
    against the batch least-squares bound of the same measurements: the information P0^-1 + sum (H_k Phi_k)^T
    R^-1 (H_k Phi_k) at the truth, Phi_k by jax.jacfwd of a Kepler (f and g) propagator, H_k of the range with
    light time, mapped to that epoch; every sigma within 10 %."""
    days = 4
    overrides = {"controller.kind": "none", "duration.days": days, "navigation.snc_mps2_per_rthz": 0.0,
                 **UNPERTURBED, **NO_EXECUTION}
    for i in range(2):
        overrides[f"navigation.stations[{i}].pass_s"] = 43200.0  # continuous
    sc = scenario.load("li2022-qffc-ranging", overrides)
    result = rollout.simulate(sc, 3)
    record = result.records.cycles.states["navigation"]
    assert float(np.asarray(record.measurements)[:3].sum()) == 3 * 2 * 96  # every step end, both stations

    setup = prepare([sc])
    params = jax.tree_util.tree_map(lambda x: x[0], setup.params)
    mu = params.forces.mu_m3_s2
    r0, v0 = position_velocity(setup.dynamics, params.initial.orbit, mu)
    x0 = jnp.concatenate([r0, v0])
    angle0 = float(setup.shared.env.earth_angle_rad[0, 0, 0])
    step_s = setup.step_s
    times = step_s * jnp.arange(1, 3 * 96 + 1)
    stations = leaves.stations_of(params.states[nav.NAME])

    def ranges(x, t):
        angle = angle0 + OMEGA_EARTH_RAD_S * t
        return jax.vmap(lambda st: MODELS["range"].h(x, st, angle)[0])(stations)

    def observed_from_start(x_start, t):
        return ranges(_kepler(x_start, t), t)

    rows = jax.vmap(lambda t: jax.jacfwd(observed_from_start)(x0, t))(times).reshape(-1, 6)
    p0 = np.diag([100.0**2] * 3 + [0.01**2] * 3)
    info = np.linalg.inv(p0) + np.asarray(rows).T @ np.asarray(rows) / 5.0**2
    t_end = times[-1]
    phi = np.asarray(jax.jacfwd(_kepler)(x0, t_end))
    p_end = phi @ np.linalg.solve(info, phi.T)
    x_end = _kepler(x0, t_end)
    basis = np.asarray(rsw_basis(x_end[:3], x_end[3:]))
    rot = np.zeros((6, 6))
    rot[:3, :3], rot[3:, 3:] = basis, basis
    bound = np.sqrt(np.diag(rot @ p_end @ rot.T))
    sigma = np.asarray(record.sigma_rsw)[3]
    assert np.all(np.abs(sigma / bound - 1.0) < 0.10), (sigma, bound)
    # the prior no longer matters: the bound is far below it along every axis
    assert np.all(bound[:3] < 30.0)


@pytest.mark.slow
def test_execution_errors_and_the_filter_over_a_week():
    """li2022-qffc-ranging for 8 days: the burns are flown off the plan by drawn errors (the Delta-V delivered
    differs from the same run without them), the filter holds the box and its decision-time errors stay within
    4 of its own sigmas; the NIS per degree of freedom over the run is near 1 (chi^2 mean: 1 +- 0.25 for the
    ~500 range residuals)."""
    sc = scenario.load("li2022-qffc-ranging", {"duration.days": 8})
    plain = scenario.load("li2022-qffc-ranging", {"duration.days": 8, **NO_EXECUTION})
    result = rollout.simulate_batch([sc, plain], seeds=[5, 5])
    assert np.asarray(result.status).tolist() == [0, 0]
    dv = np.asarray(result.metrics["dv_per_year_mps"])
    assert dv[0] != dv[1]
    record = jax.tree_util.tree_map(lambda x: np.asarray(x)[0], result.records.cycles.states["navigation"])
    assert np.all(np.abs(record.error_rsw[:8]) < 4 * record.sigma_rsw[:8])
    metrics = {k: float(np.asarray(v)[0]) for k, v in result.metrics.items()}
    assert metrics["measurements_used"] == 8 * 2 * 2 * 8  # 8 days, 2 stations, 2 passes of 8 step ends
    assert abs(metrics["nis_mean_per_dof"] - 1.0) < 0.25


def test_the_scenario_written_back_as_toml_loads_as_itself():
    """What a results file keeps (``config_toml``) and a tuning writes: the stations (a list of tables) and the
    receiver (a sub-table) as TOML inline tables, read back to the same validated scenario."""
    from geojax.scenario import from_dict, to_toml, tomllib

    for overrides in ({}, {"navigation.gnss": {"sigma_m": 10.0, "outages_s": [[0.0, 3600.0]]}}):
        sc = scenario.load("li2022-qffc-ranging", overrides)
        assert from_dict(tomllib.loads(to_toml(sc.config))).config == sc.config


@pytest.mark.parametrize("edit, message", [
    ("lat_deg = 28.25", "navigation.stations[0].lat_deg: must be >= -90 and < 90, got -95.0"),
    ("range_sigma_m = 5.0", "navigation.stations[0].range_sigma_m: must be >= 0"),
    ("pass_s = 7200.0", "navigation.stations[0].pass_s: must be <= cadence_s (43200), got 50000.0"),
    ("mask_deg = 5.0", "navigation.stations[0].mask_deg: must be >= -90 and < 90, got 95.0"),
    ('measurements = ["range"]', "navigation.stations[0].measurements[0]: must be one of 'range', 'range_rate', "
                                 "'angles', got 'lidar'"),
])
def test_bad_navigation_input_exits_2_with_one_line_and_writes_nothing(edit, message, tmp_path, capsys):
    """The command line's contract for bad navigation input: the shipped scenario with one key of its first
    station broken; exit 2, one line naming the key, nothing written."""
    assert cli.main(["scenarios", "--show", "li2022-qffc-ranging"]) == 0
    text = capsys.readouterr().out
    bad = {"lat_deg = 28.25": "lat_deg = -95.0", "range_sigma_m = 5.0": "range_sigma_m = -1.0",
           "pass_s = 7200.0": "pass_s = 50000.0", "mask_deg = 5.0": "mask_deg = 95.0",
           'measurements = ["range"]': 'measurements = ["lidar"]'}[edit]
    assert edit in text
    (tmp_path / "bad.toml").write_text(text.replace(edit, bad, 1))
    out = tmp_path / "out"
    assert cli.main(["simulate", str(tmp_path / "bad.toml"), "--days", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("overrides, message", [
    ({"navigation.snc_mps2_per_rthz": 1e-9},
     'navigation.snc_mps2_per_rthz: read only where navigation.model = "ekf", got 1e-09'),
    ({"navigation.model": "ekf"}, "navigation.stations: the filter needs a station or [navigation.gnss]"),
])
def test_keys_without_the_filter_are_refused(overrides, message):
    with pytest.raises(ValueError) as caught:
        scenario.load("li2022-qffc", overrides)
    assert str(caught.value).startswith(message)


@pytest.mark.parametrize("key, value", [("errors.h_rv", 1.0), ("errors.sigma3_r_m", 0.3), ("errors.sigma3_v_mps", 1e-4)])
def test_the_gaussian_fixs_error_is_refused_with_the_filter(key, value):
    with pytest.raises(ValueError, match=rf'^{key}: must be 0 with navigation.model = "ekf"'):
        scenario.load("li2022-qffc-ranging", {key: value})


def test_an_estimated_bias_is_updated_as_the_scalar_kalman_filter_says():
    """Closed form (the scalar Kalman update): with the orbit and the burn's errors known exactly (their
    covariance zero), a station's range is the orbit's range plus a constant bias of prior variance B measured with
    noise variance R, so one update leaves the bias's variance B R / (B + R) and moves its estimate by
    B / (B + R) times the innovation (whose size the NIS gives: nu^2 = NIS (B + R)); the other station, not
    measuring (weight 0), keeps its prior.  And the filter's layout: the biases' block of the covariance starts
    at diag(sigma_b^2), the transition carries them unchanged, and a burn's start resets the execution errors
    only (the orbit's and the biases' covariance and their correlation kept)."""
    b = _burning()
    sigma_b, sigma_r = 20.0, 5.0
    sc = scenario.load("li2022-qffc-ranging", {"duration.days": 1, "controller.kind": "none",
                                               "navigation.estimate_biases": True,
                                               **{f"navigation.stations[{i}].range_bias_sigma_m": sigma_b
                                                  for i in range(2)}})
    layout = leaves.layout_of(sc.config["navigation"])
    assert leaves.n_biases(layout) == 2
    params = jax.tree_util.tree_map(lambda x: x[0], prepare([sc]).params)
    mu = params.forces.mu_m3_s2
    state = nav.init(layout, params, b.truth[:3], b.truth[3:], None, params.forces)
    assert state.p.shape == (12, 12)
    np.testing.assert_array_equal(np.asarray(state.p[10:, 10:]), np.diag([sigma_b**2] * 2))
    f = prediction.transition(b.truth, 5000.0, state._replace(**{k: getattr(b.state, k) for k in (
        "planned_direction_rsw", "planned_thrust_n", "planned_on_fraction", "isp_s")}), b.step_s, mu)
    np.testing.assert_array_equal(np.asarray(f[10:]), np.eye(12)[10:])
    np.testing.assert_array_equal(np.asarray(f[:10, 10:]), np.zeros((10, 2)))
    correlated = state.p.at[0, 10].set(30.0).at[10, 0].set(30.0).at[6, 0].set(1.0).at[0, 6].set(1.0)
    reset = np.asarray(reset_execution(correlated, jnp.diag(jnp.full(4, 0.1**2))))
    assert reset[0, 10] == reset[10, 0] == 30.0 and reset[6, 0] == reset[0, 6] == 0.0 and reset[6, 6] == 0.1**2

    p = jnp.zeros((12, 12)).at[10:, 10:].set(jnp.diag(jnp.full(2, sigma_b**2)))  # only the biases unknown
    filtered = (b.truth, jnp.zeros(4), p, jnp.asarray(0.0), jnp.asarray(0.0), jnp.asarray(0.0), jnp.zeros(2))
    bias = jnp.array([17.0, -9.0])
    out = updates.measurement_updates(layout, mu, filtered, jnp.array([1.0, 0.0]), params.states[nav.NAME],
                                      b.truth, b.env3.earth_angle_rad[2], bias, jax.random.key(4))
    _, _, p_after, nis_sum, _, used, estimate = (np.asarray(v) for v in out)
    big_b, big_r = sigma_b**2, sigma_r**2
    assert used == 1.0
    np.testing.assert_allclose(p_after[10, 10], big_b * big_r / (big_b + big_r), rtol=1e-12)
    assert p_after[11, 11] == big_b and estimate[1] == 0.0
    np.testing.assert_allclose(abs(estimate[0]), big_b / (big_b + big_r) * np.sqrt(nis_sum * (big_b + big_r)),
                               rtol=1e-9)
    assert abs(estimate[0] - 17.0) < 3 * np.sqrt(p_after[10, 10])  # one 5 m measurement of a 17 m bias


@pytest.mark.slow
def test_estimating_the_biases_makes_the_filter_consistent_under_them():
    """Both stations' ranging biased (sigma 20 m, drawn per sample, 4x the noise): without their estimation the
    filter is knowingly inconsistent (averaged NEES far above the chi^2(6) interval of 8 draws); with it
    (``navigation.estimate_biases``) the NEES averaged per draw, their mean over 8 draws of 8 days, is inside
    that interval, the NIS per degree of freedom over every update inside its own, and every bias's error at the
    last decision time within 3 of the filter's sigmas of it, which have fallen from 20 m."""
    from geojax.navigation.ekf import chi2_bounds

    base = {"duration.days": 8, **{f"navigation.stations[{i}].range_bias_sigma_m": 20.0 for i in range(2)}}
    low, high = chi2_bounds(6, 8)
    for estimated in (False, True):
        sc = scenario.load("li2022-qffc-ranging", {**base, "navigation.estimate_biases": estimated})
        result = rollout.simulate_batch(sc, rollout.prepare_params(sc, 8), seeds=np.arange(8))
        assert np.all(np.asarray(result.status) == 0)
        nees = float(np.mean(result.metrics["nees_mean"]))
        record = result.records.cycles.states["navigation"]
        if not estimated:
            assert nees > 5 * high, nees
            assert record.bias_error is None
            continue
        assert low <= nees <= high, (nees, low, high)
        dof = float(np.asarray(record.nis_dof).sum())
        nis_low, nis_high = chi2_bounds(1, int(dof))
        assert nis_low <= float(np.asarray(record.nis_sum).sum()) / dof <= nis_high
        error, sigma = np.asarray(record.bias_error)[:, -1], np.asarray(record.bias_sigma)[:, -1]
        assert np.all(np.abs(error) < 3 * sigma) and np.all(sigma < 10.0), (error, sigma)


@pytest.mark.slow
def test_a_year_holds_the_box_and_64_samples_are_consistent():
    """li2022-qffc-ranging for a year, 64 draws: every draw holds the box; the NEES averaged
    over the decision times, its mean over the draws, inside the 95 % interval of 64 chi^2(6) values (a time
    average varies less than one value: the looser test); the NIS per degree of freedom over every update of every
    draw inside the 95 % interval of chi^2 with their summed degrees of freedom (the innovations of a consistent
    filter are white)."""
    from geojax.navigation.ekf import chi2_bounds

    sc = scenario.load("li2022-qffc-ranging")
    result = rollout.simulate_batch([sc] * 64, seeds=np.arange(64))
    assert np.all(np.asarray(result.status) == 0)
    nees = np.asarray(result.metrics["nees_mean"])
    low, high = chi2_bounds(6, 64)
    assert low <= nees.mean() <= high, (nees.mean(), low, high)
    record = result.records.cycles.states["navigation"]
    dof = float(np.asarray(record.nis_dof).sum())
    nis = float(np.asarray(record.nis_sum).sum()) / dof
    low, high = chi2_bounds(1, int(dof))
    assert low <= nis <= high, (nis, low, high)


@pytest.mark.slow
def test_gradients_flow_through_the_filter():
    """Second method: d(Delta-V)/d(thrust) through a 3-day li2022-qffc-ranging rollout (the filter, its gated
    updates and the execution errors in the loop) by reverse mode, against a central difference (h = 1e-4 N)."""
    from geojax.runner.rollout import rollout_fn

    setup = prepare([scenario.load("li2022-qffc-ranging", {"duration.days": 3})])
    one = rollout_fn(setup)
    params = jax.tree_util.tree_map(lambda x: x[0], setup.params)
    key = jax.random.key(0)

    def dv(thrust_n):
        return one(params._replace(thrusters={**params.thrusters, "thrust_n": thrust_n}), key)[0].dv_mps

    thrust = params.thrusters["thrust_n"]
    grad = float(jax.grad(dv)(thrust))
    central = float((dv(thrust + 1e-4) - dv(thrust - 1e-4)) / 2e-4)
    assert np.isfinite(grad) and grad == pytest.approx(central, rel=1e-5)


@pytest.mark.slow
def test_a_sweep_keeps_the_filters_per_cycle_columns(tmp_path):
    """``cycles = true`` on a scenario with the filter keeps its columns beside the orbit's (second method: the
    same samples through ``simulate_batch`` with the sweep's keys, ``fold_in(key(seed), j)``, and their
    ``/cycles`` table), for every controller of the sweep."""
    from geojax import store, sweep
    from geojax.loop.metrics import cycle_table

    (tmp_path / "nav.toml").write_text('name = "nav-cycles"\nscenario = "li2022-qffc-ranging"\n'
                                       'controllers = ["qffc"]\nrepetitions = 2\nseed = 3\ncycles = true\nlanes = 8\n'
                                       '[set]\n"duration.days" = 2\n[grid]\n"thrusters.beta_max_deg" = [70.0]\n')
    groups, _ = store.read_h5(sweep.run_sweep(sweep.load(tmp_path / "nav.toml"), tmp_path / "nav.h5",
                                              progress=False))
    cycles = groups["cycles"]
    sc = scenario.load("li2022-qffc-ranging", {"duration.days": 2})
    keys = jnp.stack([jax.random.fold_in(jax.random.key(3), j) for j in range(2)])
    result = rollout.simulate_batch([sc, sc], keys=keys)
    for j in range(2):
        table = cycle_table(jax.tree_util.tree_map(lambda x: x[j], result.records))
        for name in ("nav_error_along_m", "nav_sigma_radial_m", "nees", "nis_per_dof", "measurements", "lon_deg"):
            np.testing.assert_allclose(cycles[name][0, 0, j], table[name], rtol=1e-9, atol=1e-9, err_msg=name)
