"""The minimum-fuel bound (geojax.bound): known answers, duality, the linear model against the flight,
the bound against the controllers, bad input."""

import math
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import geojax
from geojax import cli
from geojax.bound import Infeasible, bound, program
from geojax.bound.directions import arm_direction, arms, axes, fixed4, geometry_of, gimbal
from geojax.bound.linear import SlotModel, linearize
from geojax.bound.run import _uncontrolled
from geojax.control.effects import V_SYNC_MPS
from geojax.runner.setup import prepare, unstack

V_MPS = 3074.7  # GEO speed: Delta-V per unit inclination change


def drift_model(n_slots, steps, drift_per_step, v_mps=V_MPS):
    """A 'linear drift with a box', the inclination problem in its simplest form: the latitude output
    follows one state that drifts by ``drift_per_step`` per step and moves by u_W / V for a slot Delta-V
    u (spread evenly over the slot's steps); nothing else moves."""
    t = np.arange(n_slots * steps).reshape(n_slots, steps)
    y = np.zeros((n_slots, steps, 2))
    y[..., 1] = drift_per_step * t
    phi = np.broadcast_to(np.eye(6), (n_slots, 6, 6)).copy()
    b = np.zeros((n_slots, 6, 3))
    b[:, 3, 2] = 1 / v_mps
    c = np.zeros((n_slots, steps, 2, 6))
    c[:, :, 1, 3] = 1.0
    e = np.zeros((n_slots, steps, 2, 3))
    e[:, :, 1, 2] = np.arange(steps) / steps / v_mps
    return SlotModel(np.zeros((n_slots + 1, 6)), y, phi, b, c, e)


@pytest.mark.parametrize("geometry", [gimbal(), fixed4(0.0), arms(*np.radians([70.0, 0.0, 60.0, 30.0]))],
                         ids=["gimbal", "fixed4", "arms"])
def test_linear_drift_with_a_box_costs_what_the_hand_solution_says(geometry):
    # By hand: the latitude must stay within +-box at every step start; with no terminal condition the least
    # Delta-V cancels the drift beyond the box edge at the last step start: V (d m_last - box) along -W for
    # a drift towards +lat (sum |u| >= |sum u_W| >= that, and flying it once at the start achieves it).
    # For the arms, thruster 1 pushes south only at pitch <= 70 deg: the cheapest is pure pitch 70 deg,
    # whose W part is sin(70 deg) of its Delta-V.
    n_slots, steps, drift, box = 12, 4, 2e-6, 1e-5
    model = drift_model(n_slots, steps, drift)
    cap = np.full(n_slots, 1.0)
    solution = program.solve(model, np.zeros((n_slots, 3)), cap, box, geometry, 4.2e7)
    need = V_MPS * (drift * (n_slots * steps - 1) - box)
    if geometry.name == "arms":
        need /= np.sin(np.radians(70.0))
    elif geometry.name == "fixed4":
        need /= 1.0  # cant 0: the four thrusters point straight north and south
    assert solution.fuel_mps == pytest.approx(need, rel=1e-7)
    assert solution.lower_mps <= solution.fuel_mps * (1 + 1e-9)
    # Duality: the bound meets the plan, up to the arms' pricing-grid allowance (cap |g| theta^2 per slot:
    # 12 x 1 m/s x 1.06 x 9.5e-6 = 1.2e-4 m/s here, with a capacity far above what is flown).
    assert solution.lower_mps == pytest.approx(need, rel=1e-9 if geometry.exact else 1e-3)
    assert np.all(np.abs(solution.u_mps[:, :2]) < 1e-6 * need) if geometry.name != "arms" else True


def two_axis_drift_model(n_slots, steps, drift_lon, drift_lat, v_mps=V_MPS):
    """``drift_model`` with a second output: the longitude follows state 0, which drifts by ``drift_lon`` per step
    and moves by u_S / V; the latitude as in ``drift_model``.  The radial Delta-V moves nothing."""
    model = drift_model(n_slots, steps, drift_lat, v_mps)
    t = np.arange(n_slots * steps).reshape(n_slots, steps)
    model.y[..., 0] = drift_lon * t
    model.b[:, 0, 1] = 1 / v_mps
    model.c[:, :, 0, 0] = 1.0
    model.e[:, :, 0, 1] = np.arange(steps) / steps / v_mps
    return model


@pytest.mark.parametrize("lon_deg", [0.0, 30.0, 96.0])
def test_per_axis_thrusters_pay_the_l1_norm_of_their_earth_fixed_axes(lon_deg):
    # By hand (Katz 2025, eq. (6): pairs along ECEF x, y, z): the box needs A = V (d_lon 47 - box) of along-track
    # and B = V (d_lat 47 - box) of out-of-plane Delta-V (as in the one-axis case above); the radial part is free.
    # At longitude lon the ECEF x and y axes have along-track parts -sin lon and cos lon, so the along-track
    # Delta-V costs A / max(|sin lon|, |cos lon|) (the pair best aligned, the other's radial part harmless) and
    # the normal B (z is W).  A gimbal pays the Euclidean sqrt(A^2 + B^2): never more.
    n_slots, steps, box = 12, 4, 1e-5
    model = two_axis_drift_model(n_slots, steps, 3e-6, 2e-6)
    cap, lon = np.full(n_slots, 1.0), np.radians(lon_deg)
    a_mps, b_mps = V_MPS * (3e-6 * (n_slots * steps - 1) - box), V_MPS * (2e-6 * (n_slots * steps - 1) - box)
    need = a_mps / max(abs(np.sin(lon)), abs(np.cos(lon))) + b_mps
    solution = program.solve(model, np.zeros((n_slots, 3)), cap, box, axes(lon), 4.2e7)
    assert solution.fuel_mps == pytest.approx(need, rel=1e-7)
    assert solution.lower_mps == pytest.approx(need, rel=1e-7)
    gimballed = program.solve(model, np.zeros((n_slots, 3)), cap, box, gimbal(), 4.2e7)
    assert gimballed.lower_mps <= solution.fuel_mps
    assert gimballed.fuel_mps == pytest.approx(math.hypot(a_mps, b_mps), rel=1e-3)


def test_per_axis_shares_cap_each_pair_apart():
    # The normal pair's budget is its share of F / m per slot: B ~ 0.26 m/s over 12 slots fits a share of 1
    # (12 m/s) and of 0.05 (0.6 m/s), not of 0.01 (0.12 m/s); the other pairs' shares do not help it.
    n_slots, steps, box = 12, 4, 1e-5
    model = drift_model(n_slots, steps, 2e-6)
    cap = np.full(n_slots, 1.0)
    need = V_MPS * (2e-6 * (n_slots * steps - 1) - box)
    for share in (1.0, 0.05):
        got = program.solve(model, np.zeros((n_slots, 3)), cap, box, axes(0.3, (1.0, 1.0, share)), 4.2e7)
        assert got.fuel_mps == pytest.approx(need, rel=1e-7)
    with pytest.raises(Infeasible):
        program.solve(model, np.zeros((n_slots, 3)), cap, box, axes(0.3, (1.0, 1.0, 0.01)), 4.2e7)


def test_katz_discrete_scenario_takes_the_per_axis_pairs_with_its_thresholds():
    config = geojax.load_scenario("katz2025-discrete").config
    geometry = geometry_of(config)
    assert geometry.name == "axes"
    ctl = config["controller"]
    assert geometry.shares == pytest.approx([s / ctl["u0_km_per_s2"] for s in ctl["sigma_km_per_s2"]], rel=1e-12)
    # |sigma| = u0 (thrust_laws.check_thresholds): the shares are a unit vector.
    assert math.hypot(*geometry.shares) == pytest.approx(1.0, rel=1e-6)
    assert geometry_of(geojax.load_scenario("katz2025-continuous").config).name == "gimbal"


def test_an_impossible_box_is_infeasible_not_a_number():
    # Also through the command line: test_cli_bound_writes_results_and_refuses_an_impossible_box.
    n_slots, steps, drift, box = 12, 4, 2e-6, 1e-5
    model = drift_model(n_slots, steps, drift)
    # The drift beyond the box needs V (d 47 - box) ~ 0.26 m/s by the last step; give 1 mm/s per slot.
    with pytest.raises(Infeasible, match="infeasible"):
        program.solve(model, np.zeros((n_slots, 3)), np.full(n_slots, 1e-3), box, gimbal(), 4.2e7)


def test_arm_pricing_bounds_the_continuous_maximum_from_above():
    # Second method: the maximum of g . d over 200 000 random directions of each arm's yaw/pitch rectangle
    # never exceeds the oracle's upper value, which is within 1e-5 |g| of it.
    geometry = arms(*np.radians([70.0, 0.0, 60.0, 30.0]))
    rng = np.random.default_rng(1)
    g = rng.normal(size=(64, 3))
    boxes = [((-30, 60), (0, 70)), ((-60, 30), (-70, 0))]
    for oracle, ((a_lo, a_hi), (b_lo, b_hi)) in zip(geometry.best, boxes):
        alpha = np.radians(rng.uniform(a_lo, a_hi, 200_000))
        beta = np.radians(rng.uniform(b_lo, b_hi, 200_000))
        sampled = np.max(g @ arm_direction(alpha, beta).T, axis=1)
        direction, upper = oracle(g)
        assert np.all(sampled <= upper + 1e-12)
        assert np.all(upper - np.sum(g * direction, axis=1) <= 1e-5 * np.linalg.norm(g, axis=1))
        assert np.allclose(np.linalg.norm(direction, axis=1), 1.0)


def _model_of(sc, u, slot_steps=4):
    batch = prepare([_uncontrolled(sc)])
    params = unstack(batch.params, 0)
    env = batch.shared.env
    n_slots = env.earth_angle_rad.shape[0] * env.earth_angle_rad.shape[1] // slot_steps
    env_slots = jax.tree_util.tree_map(lambda x: x.reshape((n_slots, slot_steps) + x.shape[2:]), env)
    return linearize(params.initial.orbit, jnp.asarray(u), env_slots, params.forces,
                     jnp.full(n_slots, params.initial.mass_kg), params.station["lon_rad"], slot_s=slot_steps * batch.step_s, step_s=batch.step_s,
                     dynamics=batch.dynamics)


def _predict(model, u):
    dx, out = np.zeros(6), []
    for k in range(len(u)):
        out.append(model.y[k] + model.c[k] @ dx + model.e[k] @ u[k])
        dx = model.phi[k] @ dx + model.b[k] @ u[k]
    return np.array(out), dx


@pytest.mark.slow
def test_the_linear_model_over_one_cycle_against_the_nonlinear_propagation():
    # Stated: over one sidereal day, burns of 0.05 m/s (north and east, two slots) are predicted by the model
    # about the uncontrolled run to within 1e-8 rad (0.4 m at GEO) in longitude and latitude; the error is
    # second order, so halving the burns quarters it (the check of a linearisation independent of its size).
    sc = geojax.load_scenario("li2022-qffc", {"duration.days": 1})
    n_slots = 24
    reference = jax.tree_util.tree_map(np.asarray, _model_of(sc, np.zeros((n_slots, 3))))
    errors = []
    for scale in (0.05, 0.025):
        u = np.zeros((n_slots, 3))
        u[3, 2], u[15, 1] = scale, scale
        flown = jax.tree_util.tree_map(np.asarray, _model_of(sc, u))
        predicted, dx = _predict(reference, u)
        errors.append(np.max(np.abs(predicted - flown.y)))
        assert np.max(np.abs(flown.y - reference.y)) > 1e3 * errors[-1]  # the burns matter; the model follows
    assert errors[0] < 1e-8
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.1)


@pytest.fixture(scope="module")
def ten_days():
    """li2022-qffc over 10 days and its free-end bound."""
    sc = geojax.load_scenario("li2022-qffc", {"duration.days": 10})
    return sc, bound(sc, free_end=True)


@pytest.mark.slow
def test_bound_holds_the_box_and_never_exceeds_a_controller(ten_days):
    # li2022 over 10 days: the re-simulated plan holds the box in the closed loop, its Delta-V is the plan's,
    # and the QFFC (which also holds the box, and need not end where it started) flies at least the free-end bound.
    sc, result = ten_days
    assert result.resim_status == 0
    assert result.resim["max_abs_dlon_deg"] <= 0.05 and result.resim["max_abs_dlat_deg"] <= 0.05
    assert result.lower_mps <= result.fuel_mps
    assert result.resim["dv_per_year_mps"] <= result.plan_per_year_mps * (1 + 1e-6)
    assert result.resim["dv_per_year_mps"] >= result.bound_per_year_mps * (1 - 1e-3)
    # The flown trajectory of the last round is the closed loop's: same steps, same forces.
    assert np.max(np.abs(result.lon_deg)) == pytest.approx(result.resim["max_abs_dlon_deg"], abs=1e-6)
    qffc = geojax.simulate(sc)
    assert int(qffc.status) == 0
    assert float(qffc.metrics["dv_per_year_mps"]) >= result.bound_per_year_mps


@pytest.mark.slow
def test_periodic_end_returns_to_the_start_and_costs_at_least_the_drift_it_cancels(ten_days):
    """li2022 over 10 days, periodic (the default) beside the free end.  (1) The flown plan ends where it
    started: its inclination vector (MEE h, k) within 1 % of the uncontrolled change over the horizon.
    (2) The free end costs no more: its program is the periodic one less the six end rows (nested programs, a
    property of the construction; here about two flown trajectories).  (3) Independent arithmetic (README, "The
    fuel bound"): a periodic plan cancels the uncontrolled change of the inclination vector, Delta(h, k); each
    out-of-plane m/s moves (h, k) by at most 1 / (2 V) (Gauss, circular orbit), and the arms put at most sin 70 deg
    of a burn out of plane, so Delta-V >= 2 V |Delta(h, k)| / sin 70 deg."""
    sc, free = ten_days
    periodic = bound(sc)
    uncontrolled = geojax.simulate(_uncontrolled(sc))
    dhk = np.asarray(uncontrolled.final.orbit[3:5]) - np.asarray(uncontrolled.params.initial.orbit[3:5])
    miss = periodic.rounds[-1]["terminal_miss"]
    assert np.hypot(*miss[3:5]) < 0.01 * np.hypot(*dhk)
    assert free.lower_mps <= periodic.lower_mps
    floor_mps = 2 * V_SYNC_MPS * np.hypot(*dhk) / np.sin(np.radians(70.0))
    assert periodic.lower_mps >= 0.99 * floor_mps
    assert periodic.resim_status == 0


@pytest.mark.slow
def test_bound_of_a_gimballed_feedback_scenario_is_below_the_lyapunov_law():
    sc = geojax.load_scenario("katz2025-constant", {"duration.days": 4})
    result = bound(sc, free_end=True)
    assert result.geometry == "gimbal"
    law = geojax.simulate(sc)
    assert float(law.metrics["dv_per_year_mps"]) >= result.bound_per_year_mps
    assert result.resim_status == 0
    # A free acquisition relaxes the program: its bound can only be lower (by weak duality both are bounds).
    relaxed = bound(sc, acquisition_days=2.0, free_end=True)
    assert relaxed.lower_mps <= result.lower_mps * (1 + 1e-6) + 1e-9
    assert relaxed.max_abs_box_deg <= 0.05
    with pytest.raises(ValueError, match="acquisition"):
        bound(sc, acquisition_days=10.0)


@pytest.mark.slow
def test_cli_bound_writes_results_and_refuses_an_impossible_box(tmp_path, capsys):
    # One real process end to end, periodic by default (Gazzino's x(T) = x(0), recorded), and the end condition
    # can only cost more than the free end of the same horizon (a program with more rows).
    out = tmp_path / "b.h5"
    run = subprocess.run([sys.executable, "-m", "geojax", "bound", "li2022-qffc", "--days", "2",
                          "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "bound" in run.stdout and "re-simulated plan" in run.stdout
    assert "; every m/s/yr extrapolated from 1.99 days):" in run.stdout  # 2 sidereal days, a short plan's rates
    data = geojax.open_results(out)
    assert float(data["status"]) == 0 and int(data["free_end"]) == 0
    assert float(data["bound_per_year_mps"]) <= float(data["resim_dv_per_year_mps"]) + 1e-6  # solver tolerance
    free = bound(geojax.load_scenario("li2022-qffc", {"duration.days": 2}), free_end=True)
    assert free.lower_mps > 0 and free.bound_per_year_mps < float(data["bound_per_year_mps"])
    # A box of +-0.001 deg: the start itself is outside it; refused in one line, exit 2 (in this process).
    assert cli.main(["scenarios", "--show", "li2022-qffc"]) == 0
    text = capsys.readouterr().out
    tight = tmp_path / "tight.toml"
    tight.write_text(text.replace("[station]", "[station]\nbox_half_width_deg = 0.001"))
    assert cli.main(["bound", str(tight), "--days", "2"]) == 2
    err = capsys.readouterr().err
    assert err.strip().count("\n") == 0 and "outside the box" in err
    with pytest.raises(ValueError, match="bound.slot_steps"):
        bound(geojax.load_scenario("li2022-qffc", {"duration.days": 1}), slot_steps=5)


@pytest.mark.slow
def test_gazzino_scenario_takes_its_four_fixed_thrusters_from_the_layout_key():
    # The scenario names its layout (thrusters.layout = "fixed4"): four thrusters, the flown plan holds the box,
    # the bound (full box, free end: about the same trajectory as the plan) is below the plan (flown within the box less its 1e-3 margin).  Second method for the
    # fuel: the plan's per-thruster Delta-Vs add up to it.
    sc = geojax.load_scenario("gazzino2016", {"duration.days": 10})
    result = bound(sc, free_end=True)
    assert result.geometry == "fixed4" and result.thruster_mps.shape[1] == 4
    assert 0 < result.lower_mps <= result.fuel_mps
    assert np.sum(result.thruster_mps) == pytest.approx(result.fuel_mps, rel=1e-9)
    assert result.resim_status == 0
    with pytest.raises(ValueError, match="thrusters.layout"):
        geojax.load_scenario("gazzino2016", {"thrusters.layout": "boom"})
