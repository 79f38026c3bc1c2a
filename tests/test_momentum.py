"""The wheels' momentum (``geojax.states.momentum``) and the loop's extension point (``geojax.states.base``).

Independent checks (the numbers where no state is carried are ``tests/test_reference_numbers.py``'s): the SRP-offset
torque's momentum against a separate quadrature of the SRP force (within 2 %); the gravity-gradient momentum against
the closed-form solutions of the body-frame equation; the conservation of the total angular momentum without torque
(with the closed-form rotation in body axes); bad input refused with one line naming the key.
"""

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import cli, scenario
from geojax.runner import setup
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate
from geojax.loop.simulate import simulate as closed_loop
from geojax.states.base import WHEEL_MOMENTUM
from geojax.physics import constants as c
from geojax.physics.ephemeris import sun_position_eci_m
from geojax.physics.frames import earth_rotation_angle_rad
from geojax.control.base import Controller, coast, stateless_init
from geojax.physics.dynamics import Thrust
from geojax.states import momentum
from geojax.states.base import StateModel, ThrustContext

STATUS_WHEELS_SATURATED = STATUS_MEANINGS.index(momentum.SATURATED)

DAYS = 4
N_RATE = 2 * np.pi / c.SIDEREAL_DAY_S  # GEO mean motion, rad/s


def _wheels(days=DAYS, **attitude):
    overrides = {"duration.days": days, "attitude.wheels": True}
    overrides.update({f"attitude.{k}": v for k, v in attitude.items()})
    return scenario.load("li2022", overrides)


def test_srp_offset_along_the_array_axis_grows_momentum_at_d_times_the_perpendicular_force():
    """An SRP force F acting at d along the orbit normal n_hat on a nadir-pointing body, no
    dumping: the inertial angular momentum grows by tau = d n_hat x F, whose secular part is d |F_perp| per second
    (F_perp: F less its component along n_hat).  Expected: a separate quadrature (60 s trapezoid) of d n_hat x F
    over the run, F = -P (1 + eta) A (1 AU / rho)^2 rho_hat from the Sun's position and the station's circular
    orbit (January: no eclipse); the body inertia is made negligible (1 kg m^2), so |h_w| = |H|."""
    d_m = 0.1
    sc = _wheels(srp_offset_array_m=[d_m, 0.0, 0.0], inertia_kg_m2=[1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    result = simulate(sc)
    cycles = result.records.cycles.states["wheels"]
    run_s = len(cycles.end_nms) * c.SIDEREAL_DAY_S
    t, force, torque, expected = _srp_quadrature(sc, d_m, run_s)

    got = np.linalg.norm(cycles.end_nms[-1] - cycles.start_nms[0])
    assert got == pytest.approx(np.linalg.norm(expected), rel=0.02)
    f_perp = np.linalg.norm(force[:, :2], axis=-1)
    # the external torques' secular rate, and (no dumping, no thrust torque) the wheels' worst day: both d |F_perp|
    per_day = d_m * np.mean(f_perp) * c.SECONDS_PER_DAY
    assert result.metrics["external_momentum_per_day_nms"] == pytest.approx(per_day, rel=0.02)
    assert result.metrics["max_wheel_growth_per_day_nms"] == pytest.approx(per_day, rel=0.02)
    # The torque is perpendicular to the normal: the pitch wheel (body y, the anti-normal) stores none of it but
    # what the osculating normal's wobble (inclination 1e-4) leaves, parts in 1e4.
    assert np.max(np.abs(cycles.max_abs_nms[:, 1])) < 1e-4 * np.max(cycles.max_abs_nms)
    assert result.metrics["srp_torque_impulse_nms"] == pytest.approx(
        np.sum((np.linalg.norm(torque[1:], axis=-1) + np.linalg.norm(torque[:-1], axis=-1)) / 2 * np.diff(t)),
        rel=0.02)
    assert result.metrics["gravity_gradient_impulse_nms"] < 1e-9


def _srp_quadrature(sc, d_m, run_s):
    """(t [n], F [n, 3], tau [n, 3], the integral of tau) of d n_hat x F over ``run_s`` by a 60 s trapezoid, F the
    SRP force from the Sun's position and the station's circular equatorial orbit, independent of the loop."""
    t = np.arange(0.0, run_s + 1.0, 60.0)
    station_rad = np.radians(sc.station_lon_deg)
    theta = station_rad + np.asarray(earth_rotation_angle_rad(sc.epoch_tt_s + t, sc.epoch_tt_s, sc.tt_minus_ut1_s))
    radius_m = 42164.16e3
    r = radius_m * np.stack([np.cos(theta), np.sin(theta), np.zeros_like(t)], axis=-1)
    sun = np.asarray(sun_position_eci_m(jnp.asarray(sc.epoch_tt_s + t), sc.epoch_tt_s))
    rho = sun - r
    dist = np.linalg.norm(rho, axis=-1, keepdims=True)
    craft = sc.config["spacecraft"]
    force = -sc.config["forces"]["srp_pressure_n_m2"] * (1 + craft["reflectivity"]) * craft["srp_area_m2"] * (
        c.AU_M / dist) ** 2 * rho / dist
    normal = np.array([0.0, 0.0, 1.0])  # the station's orbit is equatorial to 1e-3
    torque = d_m * np.cross(normal, force)
    return t, force, torque, np.sum((torque[1:] + torque[:-1]) / 2 * np.diff(t)[:, None], axis=0)


@pytest.mark.slow
def test_the_cli_run_of_li2022_momentum_without_dumping_stores_the_quadratures_momentum(tmp_path):
    """The SRP offset's momentum as a user runs it: ``geojax scenarios --show li2022-momentum`` edited to dumping off
    (``dump_angle_max_deg = 0``), ``geojax simulate FILE --days 4``: the momentum its file records (the external
    torques' secular rate per day; the QFFC's burns fire through the centre of mass, so the SRP offset alone
    drives the wheels) within 2 % of the independent quadrature of d n_hat x F."""
    import contextlib
    import io

    import h5py
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert cli.main(["scenarios", "--show", "li2022-momentum"]) == 0
    assert "dump_angle_max_deg = 5.0" in text.getvalue()
    path = tmp_path / "mine.toml"
    path.write_text(text.getvalue().replace("dump_angle_max_deg = 5.0", "dump_angle_max_deg = 0.0"))
    assert cli.main(["simulate", str(path), "--days", "4", "--out", str(tmp_path / "run.h5")]) == 0
    with h5py.File(tmp_path / "run.h5") as f:
        per_day = float(f["metrics/external_momentum_per_day_nms"][()])
        assert float(f["metrics/thrust_torque_impulse_nms"][()]) == 0.0
    sc = scenario.load(path)
    run_s = 4 * c.SIDEREAL_DAY_S
    _, _, _, expected = _srp_quadrature(sc, 0.1, run_s)
    assert per_day == pytest.approx(np.linalg.norm(expected) * c.SECONDS_PER_DAY / run_s, rel=0.02)


def _mean_motion(sc):
    """The orbit's angular rate |r x v| / r^2 at the start (the closed forms' n)."""
    from geojax.physics.elements import mee_to_cartesian
    r, v = (np.asarray(x) for x in mee_to_cartesian(jnp.asarray(sc.initial_mee), sc.force_model.mu_m3_s2))
    return np.linalg.norm(np.cross(r, v)) / np.dot(r, r)


def test_gravity_gradient_of_principal_axes_is_zero_and_of_a_product_of_inertia_the_closed_form():
    """At nadir, r_b = (0, 0, -r), so tau_gg = 3 mu / r^5 (r_b x I r_b) = 3 n^2 (-I_yz, I_xz, 0): zero for
    principal axes; with I_xz alone a constant pitch torque and omega x I omega = 0, so h_y = 3 n^2 I_xz t
    (secular, the roll and yaw wheels none); with I_yz alone the body-frame equation dh/dt = tau - omega x (I omega
    + h), omega = (0, -n, 0), reads dh_x/dt = f + n h_z, dh_z/dt = -n h_x with f = -3 n^2 I_yz - n^2 I_yz: from
    rest, h_x = (f/n) sin(nt), h_z = (f/n)(cos(nt) - 1) (bounded: the cyclic momentum of a product of inertia)."""
    principal = simulate(_wheels(days=1), keep_steps=True)
    assert principal.metrics["gravity_gradient_impulse_nms"] < 1e-9
    # No torque; what the wheels hold is the change of I omega as the orbit rate n varies on the (e ~ 1e-4)
    # orbit, about 2 e n I_yy = 1e-4 N m s.
    assert principal.metrics["max_wheel_momentum_nms"] < 2 * 1e-3 * N_RATE * 7925.0

    i_xz = 500.0
    sc = _wheels(days=2, inertia_kg_m2=[85866.7, 7925.0, 83566.7, 0.0, i_xz, 0.0])
    n = _mean_motion(sc)
    got = simulate(sc, keep_steps=True).records.steps.states["wheels"].h_nms.reshape(-1, 3)
    t = np.arange(len(got)) * (c.SIDEREAL_DAY_S / 96)
    np.testing.assert_allclose(got[:, 1], 3 * n**2 * i_xz * t, rtol=1e-3, atol=1e-3 * 3 * n**2 * i_xz * t[-1])
    assert np.max(np.abs(got[:, [0, 2]])) < 1e-3 * np.max(np.abs(got[:, 1]))

    i_yz = 500.0
    sc = _wheels(days=1, inertia_kg_m2=[85866.7, 7925.0, 83566.7, 0.0, 0.0, i_yz])
    n = _mean_motion(sc)
    got = simulate(sc, keep_steps=True).records.steps.states["wheels"].h_nms.reshape(-1, 3)
    t = np.arange(len(got)) * (c.SIDEREAL_DAY_S / 96)
    f = -4 * n**2 * i_yz
    amplitude = abs(f / n)
    np.testing.assert_allclose(got[:, 0], f / n * np.sin(n * t), atol=2e-3 * amplitude)
    np.testing.assert_allclose(got[:, 2], f / n * (np.cos(n * t) - 1), atol=2e-3 * amplitude)
    # (the pitch wheel: only the change of I_yy n with the orbit rate, 1e-4 N m s, as for principal axes)
    np.testing.assert_allclose(got[:, 1], 0.0, atol=2e-3 * amplitude)


def test_without_torque_the_total_momentum_is_conserved_and_turns_in_body_axes():
    """No torque (principal axes, no offset): the inertial H = I omega + h_w is constant, so |h_w + I omega| is
    (conservation law), and in body axes a momentum in the orbit plane turns at -n about y: h_x = h_x0 cos(nt) +
    h_z0 sin(nt), h_z = h_z0 cos(nt) - h_x0 sin(nt) (the closed form of dh/dt = -omega x h)."""
    h0 = np.array([10.0, 0.0, 20.0])
    sc = _wheels(days=2, initial_momentum_nms=h0.tolist())
    n = _mean_motion(sc)
    got = simulate(sc, keep_steps=True).records.steps.states["wheels"].h_nms.reshape(-1, 3)
    t = np.arange(len(got)) * (c.SIDEREAL_DAY_S / 96)
    i_omega = np.array([0.0, -n * 7925.0, 0.0])
    total = np.linalg.norm(got + i_omega, axis=1)
    np.testing.assert_allclose(total, np.linalg.norm(h0 + i_omega), rtol=1e-5)
    np.testing.assert_allclose(got[:, 0], h0[0] * np.cos(n * t) + h0[2] * np.sin(n * t), atol=1e-3 * 22.4)
    np.testing.assert_allclose(got[:, 2], h0[2] * np.cos(n * t) - h0[0] * np.sin(n * t), atol=1e-3 * 22.4)


def test_saturated_wheels_are_status_6_and_the_sample_is_kept():
    """12 N m s a day of SRP momentum (d = 0.1 m) in 5 N m s wheels: saturated within the first day, status 6
    ("wheels saturated"), every metric finite; the time above 80 % of capacity is most of the run."""
    result = simulate(_wheels(days=2, srp_offset_array_m=[0.1, 0.0, 0.0], wheel_capacity_nms=5.0))
    assert STATUS_MEANINGS[STATUS_WHEELS_SATURATED] == "wheels saturated"
    assert result.status == STATUS_WHEELS_SATURATED
    assert all(np.isfinite(v) for v in result.metrics.values())
    assert result.metrics["max_wheel_momentum_nms"] > 5.0
    assert 0.5 < result.metrics["time_above_80pct_capacity_fraction"] < 1.0
    assert "wheel_max_abs_x_nms" in result.cycles()


def _counter_init(params, r, v, env, force_model):
    return {"steps": jnp.zeros(()), "cycles": jnp.zeros(()), "t_s": jnp.zeros(())}


def _counter_step(params, state, ctx):
    # the step's end position is the orbit one step on: |r_end| within 1e-3 of |r| at GEO
    ratio = jnp.linalg.norm(ctx.r_end_eci_m) / jnp.linalg.norm(ctx.r_eci_m)
    return {**state, "steps": state["steps"] + 1, "t_s": state["t_s"] + ctx.step_s}, ratio


def _counter_cycle(params, state, start):
    return {**state, "cycles": state["cycles"] + 1}


def _counter_summary(params, start, end, steps):
    return {"end": end, "max_ratio_error": jnp.max(jnp.abs(steps - 1))}


COUNTER = StateModel("counter", _counter_init, _counter_step, _counter_summary, metrics=None, cycle=_counter_cycle)


@pytest.mark.parametrize("pad", [False, True])
def test_extension_point_carries_a_state_through_steps_and_cycles(pad):
    """A counting state through the loop's carry, plain and padded (``Shared.n_active``): after cycle k it has
    seen k + 1 cycle starts and (k + 1) x 96 steps, and its time is theirs; the padded slots stay zero."""
    batch = setup.prepare([scenario.load("li2022", {"duration.days": 3})], pad=pad)
    params = jax.tree_util.tree_map(lambda x: x[0], batch.params)
    _, records = jax.jit(lambda p: closed_loop(batch.controller, p, batch.shared, jax.random.key(0),
                                               step_s=batch.step_s, states=(COUNTER,)))(params)
    rec = records.cycles.states["counter"]
    k = np.arange(1, 4)
    np.testing.assert_array_equal(rec["end"]["cycles"][:3], k)
    np.testing.assert_array_equal(rec["end"]["steps"][:3], 96 * k)
    np.testing.assert_allclose(rec["end"]["t_s"][:3], k * c.SIDEREAL_DAY_S, rtol=1e-12)
    assert np.max(rec["max_ratio_error"][:3]) < 1e-3
    if pad:
        assert np.all(np.asarray(rec["end"]["steps"][3:]) == 0)


@pytest.mark.parametrize("key, value, says", [
    ("attitude.wheel_capacity_nms", -50.0, "attitude.wheel_capacity_nms: must be > 0"),
    ("attitude.inertia_kg_m2", [1e4, float("nan"), 1e4, 0, 0, 0], "attitude.inertia_kg_m2: must be a list of 6 finite"),
    ("attitude.inertia_kg_m2", [1e4, 1e3, 1e3, 0, 0, 0], "attitude.inertia_kg_m2: not a physical inertia tensor"),
    ("attitude.srp_offset_body_m", [0.1, 0.0], "attitude.srp_offset_body_m: must be a list of 3"),
    ("attitude.dump_angle_max_deg", 95.0, "attitude.dump_angle_max_deg: must be >= 0 and < 90"),
    ("attitude.dump_gain_per_s", float("nan"), "attitude.dump_gain_per_s: must be a finite number"),
    ("attitude.dump_gain_per_s", 0.0, "attitude.dump_gain_per_s: must be > 0"),
    ("attitude.tank_offset_body_m", [0.0, float("inf"), 0.0], "attitude.tank_offset_body_m: must be a list of 3"),
])
def test_bad_input_is_refused_with_one_line_naming_the_key(tmp_path, capsys, key, value, says):
    table, name = key.split(".")
    text = scenario.read_text("li2022") + f"\n[{table}]\nwheels = true\n{name} = {json.dumps(value).replace('NaN', 'nan').replace('Infinity', 'inf')}\n"
    path = tmp_path / "bad.toml"
    path.write_text(text)
    before = sorted(p.name for p in tmp_path.iterdir())
    assert cli.main(["simulate", str(path), "--out", str(tmp_path / "out.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_dumping_tilt_needs_a_thrust_arm(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(scenario.read_text("li2022-momentum").replace("thrust_arm_m = 2.5", "thrust_arm_m = 0.0"))
    assert cli.main(["simulate", str(path), "--out", str(tmp_path / "out.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "attitude.thrust_arm_m: a dumping tilt" in err, err
    assert not (tmp_path / "out.h5").exists()


def test_attitude_keys_need_the_wheels_and_an_srp_offset_needs_srp():
    with pytest.raises(ValueError, match=r"attitude.wheel_capacity_nms: read only where attitude.wheels = true"):
        scenario.load("li2022", {"attitude.wheel_capacity_nms": 20.0})
    with pytest.raises(ValueError, match=r"attitude.srp_offset_array_m: an SRP torque needs SRP"):
        scenario.load("li2022", {"attitude.wheels": True, "attitude.srp_offset_array_m": [0.1, 0, 0],
                                 "forces.srp": False})


# --- the thrusters' torques and dumping (``momentum.thrust``) ---

def _params(**attitude):
    sc = _wheels(days=1, **attitude)
    return jax.tree_util.tree_map(lambda x: x[0], setup.prepare([sc]).params)


def _wheels_state(h_body):
    zero, none = jnp.zeros(()), jnp.zeros(3)
    return momentum.Wheels(none, jnp.asarray(h_body, float), zero, zero, zero, zero, zero, none, none, zero, none,
                           none, none, none, none, none)


def _at(mass_kg=5000.0):
    """A step at the station: r along ECI x, v along y (body x = ECI y, y = -ECI z, z = -ECI x)."""
    return ThrustContext(jnp.asarray(0.0), 900.0, jnp.asarray([42164.2e3, 0.0, 0.0]),
                         jnp.asarray([0.0, 3074.66, 0.0]), jnp.asarray(mass_kg))


def _rsw_to_body(d):
    return np.array([d[1], -d[2], -d[0]])  # the nadir body axes are (S, -W, -R)


@pytest.mark.parametrize("theta_deg, bound_nms", [(30.0, 100.0), (10.0, 100.0), (10.0, 20.0), (2.0, 100.0)])
def test_the_two_burn_remainder_is_what_the_next_burn_can_empty(theta_deg, bound_nms):
    """``remainder_nms`` against its defining conditions, checked here by hand: it keeps the momentum along the
    burn (r . u = h . u: a tilt's torque is perpendicular to u); where its norm |h . u| / sin(theta) fits the bound
    it has no part along the next line (r . u_o = 0), so the next burn's one-burn least squares empties it (two
    projections to zero, where the one-burn law leaves (h . u) cos(theta)); beyond the bound its norm is the bound;
    lines within 3 deg and no other line give the one-burn least squares."""
    rng = np.random.default_rng(int(theta_deg * 10 + bound_nms))
    u = np.array([0.2, 0.9, -0.3])
    u /= np.linalg.norm(u)
    side = np.cross(u, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    u_o = -(np.cos(np.radians(theta_deg)) * u + np.sin(np.radians(theta_deg)) * side)  # antiparallel as Li's
    h = rng.normal(size=3) * 4.0 + 3.0 * u
    r = np.asarray(momentum.remainder_nms(jnp.asarray(h), jnp.asarray(u), jnp.asarray(u_o), bound_nms))
    assert np.dot(r, u) == pytest.approx(np.dot(h, u), rel=1e-12)
    one = np.dot(h, u) * u
    if theta_deg < 3.0:
        np.testing.assert_allclose(r, one, rtol=1e-12)
    elif abs(np.dot(h, u)) / np.sin(np.radians(theta_deg)) <= bound_nms:
        # the next burn empties all but r's part along u_o: nothing
        assert abs(np.dot(r, u_o)) < 1e-12 * np.linalg.norm(r)
        assert np.linalg.norm(r) == pytest.approx(abs(np.dot(h, u)) / np.sin(np.radians(theta_deg)), rel=1e-9)
    else:
        assert np.linalg.norm(r) == pytest.approx(bound_nms, rel=1e-12)
        assert abs(np.dot(r, u_o)) < abs(np.dot(one, u_o))
    np.testing.assert_allclose(np.asarray(momentum.remainder_nms(jnp.asarray(h), jnp.asarray(u), jnp.zeros(3),
                                                                bound_nms)), one, rtol=1e-12)


@pytest.mark.parametrize("h_body, direction_rsw", [
    ([3.0, -1.0, 7.0], [0.2, 0.4, np.sqrt(0.8)]),  # a north-south burn with Li's yaw and pitch
    ([30.0, 20.0, -40.0], [0.0, 1.0, 0.0]),  # along-track; the tilt saturates
    ([0.0, 5.0, 0.0], [0.0, 0.0, -1.0]),  # momentum along the thrust: no torque can reach it
])
def test_the_dumping_tilt_makes_the_torque_of_a_line_turned_about_its_nozzle(h_body, direction_rsw):
    """The torque the hook reports is r_n x F u' computed here from the geometry alone: the nozzle at L behind the
    centre of mass on the planned line (r_n = -L u_hat), the flown direction u' it returns; u' is a unit vector
    within delta_max of u_hat; the torque never adds momentum (h . tau <= 0) and, for a first burn (no other line
    yet), is the asked -(1 - exp(-k T)) / T h less its part along u_hat where it fits within delta_max (then
    exactly: the one-burn least squares)."""
    params = _params(dump_angle_max_deg=5.0, thrust_arm_m=2.5, dump_gain_per_s=1e-4)
    flown = Thrust(jnp.asarray(direction_rsw), jnp.asarray(0.5), jnp.asarray(2250.0), jnp.asarray(1.0))
    state, tilted = momentum.thrust(params, _wheels_state(h_body), flown, _at())
    u_hat, u_new = _rsw_to_body(np.asarray(direction_rsw)), _rsw_to_body(np.asarray(tilted.direction_rsw))
    expected = np.cross(-2.5 * u_hat, 0.5 * u_new)
    np.testing.assert_allclose(np.asarray(state.thrust_torque_body_nm), expected, atol=1e-12)
    assert np.linalg.norm(u_new) == pytest.approx(1.0, abs=1e-12)
    assert np.degrees(np.arccos(min(1.0, np.dot(u_hat, u_new)))) <= 5.0 + 1e-9
    h = np.asarray(h_body)
    assert np.dot(h, expected) <= 1e-15
    asked = -(1 - np.exp(-1e-4 * 900.0)) / 900.0 * h
    asked_perp = asked - np.dot(asked, u_hat) * u_hat
    if np.linalg.norm(asked_perp) <= 2.5 * 0.5 * np.sin(np.radians(5.0)):
        np.testing.assert_allclose(expected, asked_perp, atol=1e-12)
    else:  # saturated: the asked direction at the largest tilt
        assert np.linalg.norm(expected) == pytest.approx(2.5 * 0.5 * np.sin(np.radians(5.0)), rel=1e-9)
        assert np.dot(expected, asked_perp) / np.linalg.norm(asked_perp) == pytest.approx(
            np.linalg.norm(expected), rel=1e-9)
    assert float(state.cross_force_n) == pytest.approx(0.5 * np.linalg.norm(u_new - np.dot(u_new, u_hat) * u_hat),
                                                       rel=1e-9, abs=1e-15)


def test_no_tilt_flies_the_controllers_direction_exactly_and_a_moved_centre_of_mass_leaves_f_times_its_shift():
    """At delta_max = 0 the direction is the controller's to the bit and without a tank offset no torque; with the
    propellant's centre p off the starting centre of mass, after using dm of propellant the centre of mass is at
    dc = -(dm / m) p (the mass-weighted mean, here by hand), and a line still aimed at the old centre leaves
    tau = (r_n - dc) x F = -dc x F."""
    direction = jnp.asarray([0.3, 0.5, -np.sqrt(0.66)])
    flown = Thrust(direction, jnp.asarray(0.5), jnp.asarray(2250.0), jnp.asarray(0.7))
    state, tilted = momentum.thrust(_params(), _wheels_state([10.0, 10.0, 10.0]), flown, _at(4900.0))
    assert np.array_equal(np.asarray(tilted.direction_rsw), np.asarray(direction))
    assert np.all(np.asarray(state.thrust_torque_body_nm) == 0.0) and float(state.cross_force_n) == 0.0

    p = np.array([0.0, 0.0, -1.2])  # the tank 1.2 m above the centre of mass (anti-nadir)
    state, _ = momentum.thrust(_params(tank_offset_body_m=p.tolist()), _wheels_state([10.0, 10.0, 10.0]), flown,
                               _at(4900.0))
    # 5000 kg at 0 = 4900 kg at dc plus 100 kg at p
    dc = (5000.0 * np.zeros(3) - 100.0 * p) / 4900.0
    force = 0.7 * 0.5 * _rsw_to_body(np.asarray(direction))
    np.testing.assert_allclose(np.asarray(state.thrust_torque_body_nm), -np.cross(dc, force), rtol=1e-12)


@pytest.mark.slow  # the suite's budget: test_a_year_of_li2022_momentum_keeps_box_and_wheels_... checks it on a year
def test_dumping_holds_the_wheels_that_saturate_without_it():
    """li2022-momentum over 6 days, dumping on and off in one batch (the tilt limit is a leaf): off, the SRP offset
    fills the 50 N m s wheels at 12 N m s a day and the run ends "wheels saturated" (status 6, kept); on, the wheels
    stay within the law's transient bound (3/4 of the capacity) plus a day's SRP momentum, the thrust's torque
    undoes the SRP's (the net momentum after 6 days under a quarter of what it is without), the tilts put under
    5 % of the run's Delta-V across the plan, and the Delta-V changes by under 1 %."""
    on = scenario.load("li2022-momentum", {"duration.days": 6})
    off = scenario.load("li2022-momentum", {"duration.days": 6, "attitude.dump_angle_max_deg": 0.0})
    from geojax.runner.rollout import simulate_batch
    result = simulate_batch([on, off])
    m = {k: np.asarray(v) for k, v in result.metrics.items()}
    assert list(result.status) == [0, STATUS_WHEELS_SATURATED]
    assert m["max_wheel_momentum_nms"][0] < 0.75 * 50.0 + 12.0 < 50.0 < m["max_wheel_momentum_nms"][1]
    assert m["external_momentum_per_day_nms"][1] == pytest.approx(12.0, rel=0.05)
    assert m["max_wheel_growth_per_day_nms"][1] == pytest.approx(12.0, rel=0.05)
    # the same torques with dumping on; the wheels' worst day is the first, before the law has a line to pair with
    assert m["external_momentum_per_day_nms"][0] == pytest.approx(m["external_momentum_per_day_nms"][1], rel=1e-3)
    assert m["thrust_torque_impulse_nms"][0] > m["srp_torque_impulse_nms"][0] - 12.0
    assert m["thrust_torque_impulse_nms"][1] == 0.0 and m["dump_cross_dv_mps"][1] == 0.0
    assert 0.0 < m["dump_cross_dv_mps"][0] < 0.05 * m["dv_per_year_mps"][0] * 6 / 365.25
    assert m["dv_per_year_mps"][0] == pytest.approx(m["dv_per_year_mps"][1], rel=0.01)


@pytest.mark.slow
def test_a_year_of_li2022_momentum_keeps_box_and_wheels_in_every_draw_and_saturates_without_dumping():
    """A year of li2022-momentum, 16 draws of Li's nominal errors (H_rv = H_att = 1), dumping on and
    off on the same draws in one batch.  On: every draw keeps the box and its wheels under capacity (status 0).
    Off: every draw saturates its 50 N m s wheels within days (status 6), while its orbit is the dumping-free one.
    The Delta-V spent on momentum (on less off, draw by draw) is under 5 % of the station keeping's."""
    from geojax.runner.rollout import simulate_batch
    errors = {"duration.days": 365.25, "errors.h_rv": 1.0, "errors.h_att": 1.0}
    on = scenario.load("li2022-momentum", errors)
    off = scenario.load("li2022-momentum", {**errors, "attitude.dump_angle_max_deg": 0.0})
    seeds = np.concatenate([np.arange(16), np.arange(16)])
    result = simulate_batch([on] * 16 + [off] * 16, seeds=seeds)
    status = np.asarray(result.status)
    assert np.all(status[:16] == 0), status[:16]
    assert np.all(status[16:] == STATUS_WHEELS_SATURATED), status[16:]
    peak = np.asarray(result.records.cycles.states["wheels"].max_abs_nms).max(axis=-1)  # [sample, cycle]
    first_day = np.argmax(peak[16:] > 50.0, axis=1) + 1
    assert np.all(first_day <= 7), first_day
    dv = np.asarray(result.metrics["dv_per_year_mps"])
    spent = dv[:16] - dv[16:]
    assert np.all(np.abs(spent) < 0.05 * dv[16:]), spent


def test_one_element_of_a_list_key_is_an_override_and_a_sweep_axis(tmp_path):
    """``TABLE.KEY[i]`` sets one element (the others the file's); a sweep file takes it as a grid axis, each point
    loaded as a scenario (``sweep.load`` checks every point); bad indices and non-list keys are refused."""
    sc = scenario.load("li2022-momentum", {"attitude.srp_offset_array_m[2]": 0.03})
    assert sc.config["attitude"]["srp_offset_array_m"] == [0.1, 0.0, 0.03]
    with pytest.raises(ValueError, match=r"has 3 elements \(indices 0 to 2\)"):
        scenario.load("li2022-momentum", {"attitude.srp_offset_array_m[3]": 0.2})
    with pytest.raises(ValueError, match="is not a list key of the \\[attitude\\] table"):
        scenario.load("li2022-momentum", {"attitude.wheel_capacity_nms[0]": 20.0})
    from geojax import sweep
    path = tmp_path / "s.toml"
    path.write_text('scenario = "li2022-momentum"\ncontrollers = ["qffc"]\n[set]\n"duration.days" = 2\n'
                    '[grid]\n"attitude.srp_offset_array_m[0]" = [0.05, 0.2]\n')
    spec = sweep.load(path)
    assert spec.grid == {"attitude.srp_offset_array_m[0]": [0.05, 0.2]}


def _told_plan(params, controller_state, estimate, context, key):
    return estimate.states[WHEEL_MOMENTUM], controller_state


TOLD = Controller(stateless_init, _told_plan, coast, record=lambda plan: {"told_nms": plan})


def test_the_controller_is_told_the_measured_wheel_momentum():
    """``Estimate.states[WHEEL_MOMENTUM]`` (the quantity the wheels tell, ``states.base``) at a cycle start is the wheels' momentum there (the cycle record's start)
    plus the cycle's measurement error: exactly it at sigma 0; at 2 N m s per axis, errors of that spread (20
    cycles x 3 axes: the sample standard deviation within 25 %, 2.7 of its standard errors).  One batch."""
    from geojax.runner.rollout import simulate_batch
    scenarios = [_wheels(days=20, srp_offset_array_m=[0.1, 0.0, 0.0], wheel_momentum_sigma_nms=sigma)
                 for sigma in (0.0, 2.0)]
    result = simulate_batch(scenarios, controller=TOLD)
    told = np.asarray(result.records.cycles.controller["told_nms"])
    start = np.asarray(result.records.cycles.states["wheels"].start_nms)
    np.testing.assert_array_equal(told[0], start[0])
    error = told[1] - start[1]
    assert np.std(error) == pytest.approx(2.0, rel=0.25)
    assert abs(np.mean(error)) < 3 * 2.0 / np.sqrt(error.size)


@pytest.mark.slow
def test_zone_nssk_fires_at_least_the_t_dump_its_measured_momentum_asks():
    """Ye's zone NSSK with the wheels and a 5 deg tilt (100 N m s a day of SRP momentum: a 40 m^2 wing's centre
    of pressure 5.12 m off): each cycle's north-south firing is at least max(t_min, |h_xz| / (L F sin 5 deg)),
    computed here from the cycle-start momentum the wheels record (sigma 0: what the controller is told), at most
    t_max; and it exceeds Ye's constant t_min where the momentum asks more."""
    from geojax.control.zone_nssk import dump_time_s
    sc = scenario.load("ye2022-ex1", {"duration.days": 6, "attitude.wheels": True,
                                      "attitude.srp_offset_array_m": [5.12, 0.0, 0.0],
                                      "attitude.dump_angle_max_deg": 5.0, "attitude.wheel_capacity_nms": 500.0})
    result = simulate(sc)
    h = np.asarray(result.records.cycles.states["wheels"].start_nms)
    asked = np.hypot(h[:, 0], h[:, 2]) / (2.5 * 0.08 * np.sin(np.radians(5.0)))
    ctl = sc.config["controller"]
    fired = np.asarray(result.records.cycles.controller["burn_ns_s"])
    assert np.all(fired >= np.minimum(np.maximum(ctl["t_min_s"], asked), ctl["t_max_s"]) - 1e-6)
    assert np.all(fired <= ctl["t_max_s"] + 1e-6)
    assert np.any(asked[1:] > ctl["t_min_s"]) and np.any(fired[1:] > ctl["t_min_s"] + 1.0)
    params = jax.tree_util.tree_map(lambda x: x[0], setup.prepare([sc]).params)
    told = jax.vmap(lambda w: dump_time_s(params.states["wheels"], w, 0.08))(jnp.asarray(h))
    np.testing.assert_allclose(np.asarray(told), asked, rtol=1e-12)


@pytest.mark.parametrize("direction_rsw", [[-0.3, 0.2, -np.sqrt(0.87)], [-0.4, -0.1, np.sqrt(0.83)]])
def test_an_arms_reach_puts_the_nozzle_on_the_line_through_the_centre_of_mass(direction_rsw):
    """Closed form (``nozzle_distance_m``): with arms of reach rho from bases on the north and south sides of the
    anti-nadir face, the burn that pushes south is flown by the north arm (and north by the south arm), its nozzle
    r_n = -L u_hat on the line through the centre of mass at distance rho from that base (|r_n - b| = rho, the root
    farther out); the dumping tilt's torque is then -L F (u_hat x s) with that L (the geometry's r_n x F u')."""
    north, south, reach = [0.0, -1.0, -1.75], [0.0, 1.0, -1.75], 2.2
    params = _params(dump_angle_max_deg=5.0, thrust_reach_m=reach, thrust_base_north_m=north,
                     thrust_base_south_m=south, dump_gain_per_s=1e-4)
    d = np.asarray(direction_rsw)
    u_hat = _rsw_to_body(d)
    base = np.asarray(north if d[2] < 0 else south)
    arm = float(momentum.nozzle_distance_m(params.states[momentum.NAME], jnp.asarray(u_hat), d[2]))
    assert np.linalg.norm(-arm * u_hat - base) == pytest.approx(reach, rel=1e-12)
    other = -np.dot(u_hat, base) - np.sqrt(np.dot(u_hat, base) ** 2 - np.dot(base, base) + reach**2)
    assert arm > other and arm > 0
    flown = Thrust(jnp.asarray(d), jnp.asarray(0.5), jnp.asarray(2250.0), jnp.asarray(1.0))
    state, tilted = momentum.thrust(params, _wheels_state([3.0, -1.0, 7.0]), flown, _at())
    u_new = _rsw_to_body(np.asarray(tilted.direction_rsw))
    np.testing.assert_allclose(np.asarray(state.thrust_torque_body_nm), np.cross(-arm * u_hat, 0.5 * u_new),
                               atol=1e-12)
    assert np.linalg.norm(np.asarray(state.thrust_torque_body_nm)) > 0
    # without a reach: the common nozzle distance, whatever the bases
    common = _params(thrust_base_north_m=north, thrust_arm_m=2.5)
    assert float(momentum.nozzle_distance_m(common.states[momentum.NAME], jnp.asarray(u_hat), d[2])) == 2.5


def test_an_arms_reach_needs_its_bases():
    with pytest.raises(ValueError, match="attitude.thrust_reach_m: the arms' reach is measured from their bases"):
        _wheels(thrust_reach_m=2.0)
