"""geojax tune: input checks, per-iteration records in HDF5, and a diverging run that keeps its best point."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import geojax
from geojax import cli, scenario, store, tune


@pytest.mark.parametrize("key, value, message", [
    ("controller.k_h_per_km2_s", 0.0, "controller.k_h_per_km2_s: must be > 0"),
    ("controller.k_e_km2_per_s3", -1e-6, "controller.k_e_km2_per_s3: must be > 0"),
    ("controller.k_lambda_km_per_rad", -1.0, "controller.k_lambda_km_per_rad: must be >= 0"),
    ("station.box_half_width_deg", 0.0, "station.box_half_width_deg: must be > 0"),
    ("controller.sigma_km_per_s2", [6.62e-10, 1.1e-9, 4.14e-9], "norm of the thresholds must equal u0"),
    ("controller.thrust_mode", "bang-bang", "controller.thrust_mode: must be one of"),
])
def test_bad_feedback_scenarios_name_the_field(key, value, message):
    with pytest.raises(ValueError, match=message):
        scenario.load("katz2025-discrete", {key: value})


def test_missing_gain_is_an_error(tmp_path):
    text = scenario.read_text("katz2025-continuous").replace("k_e_km2_per_s3 = 5.48482e-6\n", "")
    path = tmp_path / "no_ke.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match="controller.k_e_km2_per_s3: missing"):
        scenario.load(path)


@pytest.mark.parametrize("raw, message", [
    ({"scenario": "katz2025-discrete", "parameters": ["k_h", "gain"]}, "parameters: 'gain' is not tunable here; tunable: thrusters.thrust_n"),
    ({"scenario": "katz2025-continuous", "parameters": ["sigma"]}, "'controller.sigma_km_per_s2' is not set in scenario"),
    ({"scenario": "li2022-qffc", "parameters": ["controller.k_h_per_km2_s"]}, "'controller.k_h_per_km2_s' is not tunable here"),
    ({"scenario": "li2022-qffc"}, "parameters: missing, and the controller of scenario li2022-qffc declares no default"),
    ({"scenario": "katz2025-discrete", "starts": 0}, "starts: must be >= 1"),
    ({"scenario": "katz2025-discrete", "temperature_start": 0.01, "temperature_end": 0.1}, "temperature_end"),
    ({"scenario": "katz2025-discrete", "step": 3}, "step: unknown key"),
    ({"scenario": "katz2025-discrete", "method": "newton"}, "method: must be one of"),
    ({"scenario": "katz2025-discrete", "trust_radius": 0.01, "trust_radius_min": 0.1}, "trust_radius_min: must be <="),
])
def test_bad_tuning_files_name_the_field(raw, message):
    with pytest.raises(ValueError, match=message):
        tune.from_dict(raw)


def test_parameter_space_round_trip_keeps_threshold_norm():
    """The unconstrained vector maps back to the same gains, and any threshold weights give |sigma| = u0."""
    sc = scenario.load("katz2025-discrete")
    problem = tune.Problem(sc, ["k_h", "k_e", "k_lambda", "lambda_b", "sigma"])  # aliases, as in a tuning file
    params = problem.base
    theta = tune.to_theta(params, problem.entries)
    back = tune.from_theta(theta, params, problem.entries)
    for key in ("k_h_per_m2_s", "k_e_m2_per_s3", "k_lambda_m_per_rad", "lambda_b_rad"):
        assert float(back.controller[key]) == pytest.approx(float(params.controller[key]), rel=1e-12)
    np.testing.assert_allclose(back.controller["sigma_mps2"], params.controller["sigma_mps2"], rtol=1e-7)
    moved = tune.from_theta(theta + np.array([0, 0, 0, 0, 1.0, -2.0, 0.5]), params, problem.entries)
    assert float(np.linalg.norm(moved.controller["sigma_mps2"])) == pytest.approx(
        float(params.controller["u0_mps2"]), rel=1e-12)


@pytest.mark.parametrize("method", ["sqp", "adam"])
def test_diverging_run_stops_and_keeps_the_best_feasible_point(tmp_path, capsys, method):
    """A run whose derivatives are all non-finite stops after its first iteration with a message, and keeps
    the best point that the exact law found feasible (the scenario's own gains over 2 days)."""
    spec = tune.from_dict({"scenario": "katz2025-discrete", "days": 2.0, "starts": 2, "iterations": 5,
                           "spread_decades": 0.01, "method": method})
    problem = tune.Problem(spec.scenario, spec.parameters)
    problem.surrogate_grad = lambda thetas, t: (np.full(len(thetas), np.nan), None, np.full(np.shape(thetas), np.nan))
    problem.linearise = lambda thetas, t: (*(np.array(v) for v in problem.exact(thetas)),
                                           np.full((len(thetas), 3, 2), np.nan))
    result = tune.tune(spec, out=tmp_path / "t.h5", problem=problem)
    assert "every start diverged" in result.message
    assert result.best_theta is not None and np.isfinite(result.best_dv_per_year_mps)
    groups, attrs = store.read_h5(tmp_path / "t.h5")
    assert {"geojax_version", "config_toml", "created_utc", "wall_s", "device"} <= set(attrs)
    assert groups["iterations"]["dv_per_year_mps"].shape == (1, 2)
    assert groups["metrics"]["dv_per_year_mps"] == pytest.approx(result.best_dv_per_year_mps)
    assert "diverged" in capsys.readouterr().out


def test_qp_step_matches_the_closed_form_of_one_active_constraint():
    """min g.d + |d|^2/2 s.t. a.d <= b: the projection -g + lambda... in closed form (KKT by hand), and the
    multiplier the step reports is that lambda; with the constraint slack the step is the Newton step -g."""
    grad, a = np.array([-1.0, -2.0]), np.array([1.0, 1.0])
    # Constraint c + a.d <= 0 with c = -1: the unconstrained step (1, 2) violates it (a.d = 3 > 1).
    d, lam = tune.qp_step(grad, np.eye(2), np.array([-1.0, -5.0]), np.vstack([a, [0.0, 1.0]]), 10.0,
                          np.full(2, -10.0), np.full(2, 10.0))
    lam_exact = (a @ -grad - 1.0) / (a @ a)  # d = -grad - lam a on the line a.d = 1
    np.testing.assert_allclose(d, -grad - lam_exact * a, atol=1e-7)
    np.testing.assert_allclose(lam, [lam_exact, 0.0], atol=1e-6)
    free, _ = tune.qp_step(grad, np.eye(2), np.array([-10.0, -10.0]), np.vstack([a, a]), 10.0,
                           np.full(2, -10.0), np.full(2, 10.0))
    np.testing.assert_allclose(free, -grad, atol=1e-7)
    # An unreachable constraint inside the trust region: the elastic step goes as far toward it as it may.
    far, _ = tune.qp_step(np.zeros(2), np.eye(2), np.array([5.0, -1.0]), np.vstack([a, a]), 0.5,
                          np.full(2, -10.0), np.full(2, 10.0))
    np.testing.assert_allclose(far, [-0.5, -0.5], atol=1e-7)


def test_damped_bfgs_satisfies_the_secant_equation_and_stays_positive_definite():
    """BFGS: H_new s = y when s.y > 0 (secant); Powell's damping keeps H positive definite when s.y < 0."""
    rng = np.random.default_rng(0)
    s, y = rng.normal(size=3), rng.normal(size=3)
    y = y if s @ y > 0 else -y
    h = tune.damped_bfgs(np.eye(3), s, y)
    np.testing.assert_allclose(h @ s, y, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(tune.damped_bfgs(np.eye(3), s, -y)) > 0)


def test_sqp_walks_into_the_box_and_never_back_out():
    """The SQP's filter, checked with the exact law on the smooth (clipped) law over 20 days from gains that
    leave the box: while a start is outside, each iterate's violation is no larger than the last; once
    inside it stays inside with a Delta-V that never rises; and the run ends with a feasible point."""
    spec = tune.from_dict({"scenario": "katz2025-continuous", "days": 20.0, "starts": 2, "iterations": 20,
                           "parameters": ["k_h", "k_e", "lambda_b"], "spread_decades": 0.1})
    spec = dataclasses.replace(spec, scenario=scenario.load(
        "katz2025-continuous", {"duration.days": 20.0, "controller.thrust_mode": "continuous-clipped"}))
    result = tune.tune(spec, verbose=False)
    violation = np.maximum(result.history["constraint"], 0.0).sum(axis=2)  # [iteration, start]
    dv = result.history["dv_per_year_mps"]
    assert np.all(violation[0] > 0)  # both starts begin outside the box
    assert np.all(np.diff(violation, axis=0) <= 0.0)
    inside = violation[:-1] == 0
    assert np.all(np.diff(dv, axis=0)[inside] <= 0.0)
    assert result.best_theta is not None and np.max(result.best_constraint) <= 0.0
    assert result.best_dv_per_year_mps <= np.min(np.where(violation == 0, dv, np.inf))


@pytest.mark.slow
def test_cli_tune_writes_results_and_rejects_bad_files(tmp_path):
    good = tmp_path / "t.toml"
    good.write_text('scenario = "katz2025-constant"\ndays = 2.0\nstarts = 2\niterations = 0\n')
    code = cli.main(["tune", str(good), "--out", str(tmp_path / "t.h5"), "--quiet"])
    assert code in (0, 1)
    assert (tmp_path / "t-tuned.toml").is_file() == (code == 0)  # the tuned scenario, where a feasible point was found
    groups, attrs = store.read_h5(tmp_path / "t.h5")
    assert attrs["kind"] == "tune" and groups["iterations"]["theta"].shape == (1, 2, 2)
    # As labelled arrays (geojax.open_results), and its convergence figure in the format asked for.
    ds = geojax.open_results(tmp_path / "t.h5")
    assert ds.iterations__dv_per_year_mps.dims == ("iteration", "start")
    assert ds.iterations__theta.dims == ("iteration", "start", "parameter")
    assert ds.iterations__temperature.dims == ("iteration",)
    assert cli.main(["plot", str(tmp_path / "t.h5"), "--out", str(tmp_path / "fig"), "--format", "pdf", "-q"]) == 0
    assert (tmp_path / "fig" / "t-convergence.pdf").read_bytes().startswith(b"%PDF")
    bad = tmp_path / "bad.toml"
    bad.write_text('scenario = "katz2025-constant"\nparameters = ["k_x"]\n')
    assert cli.main(["tune", str(bad), "--out", str(tmp_path / "b.h5")]) == 2


def test_population_hessian_recovers_a_quadratic_and_stays_positive_definite():
    """Gradients of f = theta' H theta / 2 + b.theta at scattered starts give back H (least squares, exact for a
    quadratic); an indefinite fit is floored to positive definite; too few starts give the fallback."""
    rng = np.random.default_rng(1)
    h = np.array([[4.0, 1.0, 0.5], [1.0, 2.0, 0.0], [0.5, 0.0, 1.0]])
    theta = rng.normal(size=(16, 3))
    grad = theta @ h + np.array([1.0, -2.0, 0.3])
    np.testing.assert_allclose(tune.population_hessian(theta, grad, np.eye(3)), h, atol=1e-10)
    saddle = tune.population_hessian(theta, theta @ np.diag([1.0, -1.0, 2.0]), np.eye(3))
    assert np.all(np.linalg.eigvalsh(saddle) > 0)
    assert tune.population_hessian(theta[:3], grad[:3], np.eye(3) * 7.0)[0, 0] == 7.0


def test_a_tuned_scenario_that_fails_its_load_checks_is_named():
    """The descent keeps each tuned key within its own bounds, not the checks that tie keys together: a tuned
    thrust 100 times below ye2022-ex1's cannot beat the largest daily drift within t_max (Ye 2022 eq. (41)),
    so ``geojax simulate`` would refuse the tuned TOML; ``tuned_scenario_fault`` names why (read back from the
    TOML written), and finds nothing at the scenario's own thrust."""
    from geojax.runner.setup import prepare

    spec = tune.from_dict({"scenario": "ye2022-ex1", "parameters": ["thrusters.thrust_n"], "days": 2.0})
    base = jax.tree_util.tree_map(lambda x: x[0], prepare([spec.scenario]).params)
    entries = tune.tuned(spec.scenario, spec.controller, spec.parameters)
    theta = tune.to_theta(base, entries)
    assert tune.tuned_scenario_fault(spec, base) is None
    weak = tune.from_theta(jnp.asarray(theta - np.log(100.0)), base, entries)
    fault = tune.tuned_scenario_fault(spec, weak)
    assert fault.startswith("thrusters.thrust_n: 0.0008 N") and "Ye 2022 eq. (41)" in fault


def test_printed_constraints_are_read_back_as_excursions_in_degrees():
    """Round trip through the objective's definition, g = (excursion / box)^2 - 1 (Katz 2025 eq. (10),
    normalised): the excursions the tuner prints beside its constraints are the ones that made them."""
    from geojax.tune.write import excursion_deg

    excursions_deg, box_deg = np.array([[0.03, 0.045], [0.05, 0.0]]), 0.05
    g = (excursions_deg / box_deg) ** 2 - 1.0
    np.testing.assert_allclose(excursion_deg(g, box_deg).T, excursions_deg, rtol=1e-14, atol=1e-17)


@pytest.mark.slow
def test_the_dump_gain_is_tuned_with_the_wheels_capacity_as_a_constraint(tmp_path):
    """Where the scenario carries the wheels, the tuning has a third constraint, (max |h| / capacity)² - 1,
    the same as a plain simulation's largest wheel momentum gives (a second path: ``simulate``); the dumping law's
    gain is tunable (``attitude.dump_gain_per_s``, log scale); the file and the summary name the wheels."""
    from geojax.runner.rollout import simulate
    from geojax.tune.write import summary

    spec = tune.from_dict({"scenario": "li2022-momentum", "parameters": ["attitude.dump_gain_per_s"], "days": 3.0,
                           "starts": 2, "iterations": 1, "spread_decades": 0.5})
    problem = tune.Problem(spec.scenario, spec.parameters)
    assert problem.constraint_names == ("lon", "lat", "wheels")
    theta = np.log(np.array([[0.01], [1e-4]]))
    dv, g, ok = (np.asarray(v) for v in problem.exact(theta))
    assert g.shape == (2, 3)
    for gain, row in zip((0.01, 1e-4), g, strict=True):
        sc = scenario.load("li2022-momentum", {"duration.days": 3.0, "attitude.dump_gain_per_s": gain})
        peak = float(simulate(sc).metrics["max_wheel_momentum_nms"])
        assert row[2] == pytest.approx((peak / 50.0) ** 2 - 1.0, rel=1e-9, abs=1e-12)
    assert g[1, 2] > g[0, 2]  # a smaller gain dumps less
    result = tune.tune(spec, out=tmp_path / "t.h5", problem=problem)
    groups, attrs = store.read_h5(tmp_path / "t.h5")
    assert attrs["constraints"] == "lon,lat,wheels"
    assert "constraint_wheels" in groups["metrics"] and groups["iterations"]["constraint"].shape[-1] == 3
    assert any(line.startswith("  wheels kept: largest |h|") for line in summary(result))
