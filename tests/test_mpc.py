"""The minimum-fuel MPC (``control.mpc``) and its LP solver (``control.lp``): HiGHS as the second method,
the QFFC's burn effect as the model's check, closed loop, sweep, bad input."""

import h5py
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize

from geojax import scenario, sweep
from geojax.control import lp, mpc, qffc
from geojax.control.qffc import BurnPair
from geojax.control.effects import V_SYNC_MPS
from geojax.loop.metrics import SECONDS_PER_YEAR, STATUS_OK
from geojax.runner.report import reference_and_target
from geojax.runner.rollout import simulate
from geojax.runner.setup import prepare
from geojax.params import station_target
from geojax.physics.propulsion import arm_limits

DAYS = 20.0


def highs(c, a, lower, upper, penalty):
    """The same program by HiGHS: soft rows get slacks s >= 0 of cost penalty (lower - s <= a x <= upper + s)."""
    soft = np.isfinite(penalty)
    n, k = a.shape[1], int(soft.sum())
    slack = np.zeros((a.shape[0], k))
    slack[np.flatnonzero(soft), np.arange(k)] = 1.0
    rows, bounds = [], []
    for sign, bound in ((1.0, upper), (-1.0, -lower)):
        finite = np.isfinite(bound)
        rows.append(np.hstack([sign * a[finite], -slack[finite]]))
        bounds.append(bound[finite])
    result = scipy.optimize.linprog(np.concatenate([c, penalty[soft]]), A_ub=np.vstack(rows),
                                    b_ub=np.concatenate(bounds), bounds=[(None, None)] * n + [(0, None)] * k,
                                    method="highs")
    assert result.status == 0, result.message
    return result.fun


def random_program(rng, n=12, m=10):
    """A feasible, bounded program: 0 <= x <= 2, two-sided rows about a feasible point (some one-sided), a
    third of the rows soft; the cost of any sign."""
    a = rng.normal(size=(m, n))
    ax = a @ rng.uniform(0, 1, n)
    lower, upper = ax - rng.uniform(0.1, 1, m), ax + rng.uniform(0.1, 1, m)
    lower[rng.uniform(size=m) < 0.3] = -np.inf
    penalty = np.where(rng.uniform(size=m) < 0.3, rng.uniform(0.5, 5, m), np.inf)
    big = np.vstack([np.eye(n), a])
    return (rng.normal(size=n), big, np.concatenate([np.zeros(n), lower]), np.concatenate([np.full(n, 2.0), upper]),
            np.concatenate([np.full(n, np.inf), penalty]))


def test_lp_solver_matches_highs_on_random_programs():
    """Second method: HiGHS on the same programs (soft rows as penalised slacks), 40 random ones, batched."""
    rng = np.random.default_rng(0)
    programs = [random_program(rng) for _ in range(40)]
    c, a, lower, upper, penalty = (jnp.asarray(np.stack(x)) for x in zip(*programs))
    solve = jax.jit(jax.vmap(lambda *args: lp.solve(args[0], lp.dense_operator(args[1]), *args[2:], tolerance=1e-7)))
    solutions = solve(c, a, lower, upper, penalty)
    assert bool(jnp.all(solutions.converged))
    for i, program in enumerate(programs):
        assert float(solutions.objective[i]) == pytest.approx(highs(*program), rel=1e-4, abs=1e-9)


@pytest.fixture(scope="module")
def planning():
    """A planning problem of li2022-mpc: the reference's means from cycle 40 on, a start off the targets."""
    return planning_of("li2022-mpc")


def planning_of(name: str) -> dict:
    """A planning problem of scenario ``name`` (an MPC's): the reference's means from cycle 40 on, a start off the
    targets, and the sample's ``params``."""
    sc = scenario.load(name, {"duration.days": 45})
    batch = prepare([sc])
    params = jax.tree_util.tree_map(lambda x: x[0], batch.params)
    target = station_target(params.station)
    x0 = target + jnp.array([1e-4, 3e-10, 5e-5, -8e-5, 1.5e-4, -1e-4])
    return dict(x0=x0, target=target, ref=batch.shared.reference.window[40], limits=arm_limits(params.thrusters),
                accel=params.thrusters["thrust_n"] / params.initial.mass_kg, cycle_s=batch.step_s * 96,
                leaves=params.controller, station=params.station, params=params)


def build(planning, shape, **leaves):
    return mpc.build(planning["x0"], planning["target"], planning["ref"][:shape.n_max + 1], 0.3, planning["limits"],
                     planning["accel"], planning["cycle_s"], {**planning["leaves"], **leaves}, planning["station"],
                     shape)


def dense(operator, n):
    return np.asarray(jax.vmap(operator.matvec, in_axes=1, out_axes=1)(jnp.eye(n)))


@pytest.mark.slow
def test_planning_program_matches_highs(planning):
    """Second method: HiGHS on the program's explicit matrix; the operator's transpose and normal-matrix solve
    against the dense matrix (adjoint identity, a dense solve).  An 8-cycle horizon (the paper's 20 in the
    closed-loop tests): the same program, built and checked in a third of the time.  Slow tier (71 s): the
    default tier checks the same interior-point solver (``control.lp``) against HiGHS on the momentum MPC's
    program (``tests/test_mpc_momentum.py``)."""
    shape = mpc.Shape(n_max=8)
    horizon = {"horizon": planning["leaves"]["horizon"] * 0 + 8}
    model = build(planning, shape, **horizon)
    operator = mpc.operator(model, shape)
    c, lower, upper, penalty = (np.asarray(v) for v in mpc.program(model, {**planning["leaves"], **horizon}, shape))
    a = dense(operator, c.size)
    rng = np.random.default_rng(1)
    y = rng.normal(size=a.shape[0])
    np.testing.assert_allclose(operator.rmatvec(jnp.asarray(y)), a.T @ y, rtol=1e-10, atol=1e-10 * np.abs(a).max())
    rho, sigma, rhs = 10 ** rng.uniform(-4, 4, a.shape[0]), np.full(c.size, 1e-6), rng.normal(size=c.size)
    normal = np.diag(sigma) + a.T @ (rho[:, None] * a)
    solved = np.asarray(operator.factor(jnp.asarray(rho), jnp.asarray(sigma))(jnp.asarray(rhs)))
    assert np.abs(normal @ solved - rhs).max() < 1e-8 * np.abs(normal).max() * np.abs(solved).max()
    solution = jax.jit(lambda: lp.solve(jnp.asarray(c), operator, jnp.asarray(lower), jnp.asarray(upper),
                                        jnp.asarray(penalty), tolerance=1e-7))()
    assert bool(solution.converged) and int(solution.iterations) <= mpc.FIELDS["iterations"].default
    assert float(solution.objective) == pytest.approx(highs(c, a, lower, upper, penalty), rel=1e-4)


@pytest.mark.slow
def test_rows_follow_the_qffc_burn_effect_and_the_drift(planning):
    """Independent model check: one cycle's burns change the first boundary's state by B_1 v_1 + B_2 v_2 as
    ``qffc.effect`` computes it (eq. (29)), and each later boundary adds the new drift times the cycle to the
    longitude (x_{j+1} = Phi x_j)."""
    shape = mpc.Shape(n_max=4)
    model = build(planning, shape)
    rng = np.random.default_rng(2)
    w = np.zeros((4, 2, shape.generators))
    w[0] = rng.uniform(0, 0.05, (2, shape.generators))
    rows = mpc.operator(model, shape).matvec(jnp.asarray(w.ravel()))[-4 * shape.rows_per_boundary:]
    dv = np.einsum("bg,bgv->bv", w[0], model.directions)
    burns = BurnPair(jnp.asarray(dv), None, None, None, model.l_rad, None, None)
    first = np.asarray(qffc.effect(burns, 0.3))
    expected = np.stack([first + np.array([k * planning["cycle_s"] * first[1], 0, 0, 0, 0, 0]) for k in range(4)])
    np.testing.assert_allclose(rows.reshape(4, -1), np.einsum("jrs,js->jr", model.rows, expected), rtol=1e-9,
                               atol=1e-12)


@pytest.mark.slow
def test_padding_the_horizon_changes_nothing(planning):
    """A horizon of 6 padded to 10 cycles plans what a program of exactly 6 cycles plans (the mask)."""
    plans = {}
    plan = jax.jit(mpc.plan, static_argnames="shape")  # one compiled program per horizon, as in the loop
    for n_max in (6, 10):
        shape = mpc.Shape(n_max=n_max)
        burns, solution, _ = plan(planning["x0"], planning["target"], planning["ref"][:n_max + 1], 0.3,
                                  planning["limits"], planning["accel"], planning["cycle_s"],
                                  {**planning["leaves"], "horizon": jnp.asarray(6)}, planning["station"], shape=shape)
        plans[n_max] = (float(solution.objective), np.asarray(burns.dv_rsw_mps))
    # both certified to the solver's duality gap, tolerance x (1 + |objective|) (``lp.certify``)
    gap = planning["leaves"]["tolerance"] * (1 + abs(plans[6][0]))
    assert plans[10][0] == pytest.approx(plans[6][0], abs=2 * float(gap))
    np.testing.assert_allclose(plans[10][1], plans[6][1], atol=1e-6 * np.abs(plans[6][1]).max())


@pytest.mark.slow
def test_twenty_days_hold_the_box_between_the_inclination_floor_and_the_qffc():
    """Closed loop on 20 days: status 0, every plan certified, flown within the arms' pitch limit.  Its Delta-V
    lies between the QFFC's on the same days (which corrects the full deviation every cycle) and a closed-form
    floor: a run that ends with |i - i_T| <= Delta i_max must have flown at least 2 V_s (|i_free - i_T| -
    Delta i_max) north-south (eq. (30); i_free the uncontrolled reference's inclination at the end)."""
    sc = scenario.load("li2022-mpc", {"duration.days": DAYS})
    mpc_run = simulate(sc)
    qffc_run = simulate(scenario.load("li2022-qffc", {"duration.days": DAYS}))
    assert int(mpc_run.status) == STATUS_OK and int(qffc_run.status) == STATUS_OK
    rec = mpc_run.records.cycles.controller
    assert np.all(rec["certified"]) and np.all(rec["solved"])
    assert np.max(np.abs(rec["burns"].beta_rad)) <= np.radians(70.0) + 1e-12
    batch = prepare([sc])
    n = batch.n_cycles
    reference, _ = reference_and_target(sc, n)
    target = np.array([sc.config["station"]["ix"], sc.config["station"]["iy"]])
    di_max = sc.config["controller"]["di_max"]
    assert mpc_run.metrics["max_abs_di"] < 1.1 * di_max
    floor_mps = 2 * V_SYNC_MPS * (np.hypot(reference["ix"][n] - target[0], reference["iy"][n] - target[1]) - di_max)
    to_run = n * batch.step_s * 96 / SECONDS_PER_YEAR
    dv_mps = mpc_run.metrics["dv_per_year_mps"] * to_run
    assert floor_mps > 0.1
    assert floor_mps < dv_mps < qffc_run.metrics["dv_per_year_mps"] * to_run


@pytest.mark.slow
def test_a_sweep_over_the_horizon_compiles_once(tmp_path, monkeypatch):
    """Two horizons in one sweep: the plan is traced once (one compiled rollout), both points hold the box."""
    traced = []
    real_plan = mpc.plan
    monkeypatch.setattr(mpc, "plan", lambda *args, **kw: traced.append(1) or real_plan(*args, **kw))
    path = tmp_path / "h.toml"
    path.write_text('scenario = "li2022-mpc"\ncontrollers = ["mpc"]\n[set]\n"duration.days" = 3.0\n'
                    '[grid]\n"controller.horizon" = [4, 8]\n')
    with h5py.File(sweep.run_sweep(sweep.load(path), tmp_path / "h.h5", progress=False)) as f:
        status, dv = f["status/code"][()], f["metrics/dv_per_year_mps"][()]
    assert len(traced) == 1
    assert np.all(status == STATUS_OK) and np.all(dv > 0)


@pytest.mark.parametrize("overrides, message", [
    ({"controller.iterations": -1}, "controller.iterations: must be >= 1"),
    ({"controller.horizon": 0}, "controller.horizon: must be >= 1"),
    ({"controller.horizon": 31}, "controller.horizon: must be >= 1 and < 31"),
    ({"controller.facets": 7}, "controller.facets: must be even"),
    ({"controller.e_max": 4e-4}, "controller.e_max: the daily libration"),
])
def test_bad_input_is_one_line(overrides, message):
    with pytest.raises(ValueError, match=message) as error:
        scenario.load("li2022-mpc", overrides)
    assert "\n" not in str(error.value)


@pytest.mark.slow
def test_tune_differentiates_through_the_interior_point():
    """The MPC runs in ``tune`` (forward-mode derivatives through the solver's loop).  Physics as the check:
    a wider inclination window absorbs more of the natural drift, so the descent step widens Delta i_max."""
    from geojax import tune

    raw = {"scenario": "li2022-mpc", "parameters": ["controller.di_max"], "starts": 1, "iterations": 1,
           "days": 2.0, "method": "adam"}
    history = tune.tune(tune.from_dict(raw), verbose=False).history
    theta = history["theta"].ravel()
    assert np.all(np.isfinite(history["dv_per_year_mps"]))
    assert theta[1] > theta[0]
