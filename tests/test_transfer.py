"""GTO-GEO transfers (Ma & Kong 2023): boom kinematics, steering law, body slew, joint MPC, the transfer loop.

Every test names its independent check: a chain of elementary rotations, the velocity of a Kepler orbit, a
trapezoidal slew profile, a body under constant torque, the rotation of the thrust vector, the rocket
equation, Table 1's joint ranges.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import cli, transfer
from geojax.physics import constants as c
from geojax.physics.elements import kepler_to_mee, mee_to_cartesian
from geojax.transfer import boom, pointing, quadrilateral, steering
from geojax.transfer.rollout import Static

RNG = np.random.default_rng(7)
D1, D2, A1 = 0.5, 1.5, 0.3


@pytest.mark.parametrize("theta", RNG.uniform(-math.pi, math.pi, (4, 3)))
def test_forward_kinematics_9_is_the_chain_of_elementary_rotations(theta):
    """Eq. (9) against Rz(t1) [Ty(d1) Ry(t2) [Tz(d2) Rz(t3) Tx(a1)]] built from 3x3 rotations (numpy-free of
    eq. (9)); the printed y and z translation entries agree with the chain, the x entry only with its a1
    sign flipped (the erratum ``boom.wrist_pose`` documents)."""
    rotation, position = boom.wrist_pose(jnp.asarray(theta), D1, D2, A1)
    rz1, ry2, rz3 = boom.rot_z(theta[0]), boom.rot_y(theta[1]), boom.rot_z(theta[2])
    chain_rotation = rz1 @ ry2 @ rz3
    chain_position = rz1 @ (jnp.array([0.0, D1, 0.0]) + ry2 @ (jnp.array([0.0, 0.0, D2]) + rz3 @ jnp.array([A1, 0, 0])))
    np.testing.assert_allclose(rotation, chain_rotation, atol=1e-14)
    np.testing.assert_allclose(position, chain_position, atol=1e-14)
    s1, s2, s3 = np.sin(theta)
    c1, c2, c3 = np.cos(theta)
    printed_x = A1 * (s1 * s3 - c1 * c2 * c3) + D2 * c1 * s2 - D1 * s1
    printed_y = A1 * (c1 * s3 + c2 * c3 * s1) + D1 * c1 + D2 * s1 * s2
    printed_z = D2 * c2 - A1 * c3 * s2
    np.testing.assert_allclose([printed_y, printed_z], chain_position[1:], atol=1e-14)
    np.testing.assert_allclose(printed_x + 2 * A1 * (c1 * c2 * c3 - s1 * s3), chain_position[0], atol=1e-14)


def test_joint_targets_invert_the_kinematics_and_the_torque_is_r_cross_f():
    """Inverse of (9): the wrist-y thrust axis at the targets equals the azimuth/elevation unit vector
    (spherical coordinates, independent of eq. (9)) over Table 1's ranges; eq. (8) against numpy's cross
    product of the chain position and the thrust."""
    az = RNG.uniform(0.0, math.pi / 2, 20)
    el = RNG.uniform(-math.radians(15), math.radians(15), 20)
    for a, e in zip(az, el):
        theta = boom.joint_targets_rad(jnp.asarray(a), jnp.asarray(e))
        assert -math.pi / 2 <= theta[0] <= 0 and abs(theta[2]) <= math.radians(15) + 1e-15
        expected = [math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)]
        np.testing.assert_allclose(boom.thrust_direction_body(theta), expected, atol=1e-14)
    theta = jnp.array([-0.4, 1.7, 0.2])
    offset = np.array([0.1, -0.2, -1.0])
    _, r = boom.wrist_pose(theta, D1, D2, A1)
    force = 0.5 * np.asarray(boom.rot_z(theta[0]) @ boom.rot_y(theta[1]) @ boom.rot_z(theta[2]))[:, 1]
    np.testing.assert_allclose(boom.coupling_torque_nm(theta, 0.5, D1, D2, A1, jnp.asarray(offset)),
                               np.cross(np.asarray(r) + offset, force), atol=1e-14)


def _geometry(nu_rad, e=0.7, argp_rad=math.pi, raan_rad=0.3, i_rad=math.radians(20.8), a_m=24.7e6):
    return steering.orbit_geometry(kepler_to_mee(a_m, e, i_rad, raan_rad, argp_rad, nu_rad))


@pytest.mark.parametrize("nu_deg", [0.0, 180.0])
def test_steering_law_1_at_perigee_and_apogee(nu_deg):
    """Closed form: at both apsides the velocity is perpendicular to the radius, so alpha = 90 deg (thrust
    along S); beta = -(pi/2) cos u with u = argp + nu (perigee at the descending node: u = 180 deg -> +90 deg,
    apogee at the ascending node: u = 360 deg -> -90 deg)."""
    geo = _geometry(math.radians(nu_deg))
    assert float(steering.alpha_rad(geo.e, geo.true_anomaly_rad)) == pytest.approx(math.pi / 2, abs=1e-12)
    u = math.pi + math.radians(nu_deg)
    assert float(steering.beta_rad(geo.arg_latitude_rad)) == pytest.approx(-math.pi / 2 * math.cos(u), abs=1e-12)


def test_alpha_is_the_velocity_direction_and_the_printed_law_at_e_1():
    """alpha against the velocity of the Kepler orbit (mee_to_cartesian, projected on R and S) at any anomaly;
    the printed eq. (1), arctan[-2 cot(nu/2)(1 - sin^2(nu/2))/(1 + cos nu)], has the same tangent up to sign
    at e = 1 (the reading documented in ``steering``)."""
    mu = c.MU_EARTH_M3_S2
    for nu in np.radians([20.0, 75.0, 130.0, 230.0, 320.0]):
        mee = kepler_to_mee(24.7e6, 0.7, 0.36, 0.3, math.pi, nu)
        r, v = (np.asarray(x) for x in mee_to_cartesian(mee, mu))
        radial = r / np.linalg.norm(r)
        along = np.cross(np.cross(r, v), r)
        along /= np.linalg.norm(along)
        geo = steering.orbit_geometry(mee)
        assert float(steering.alpha_rad(geo.e, geo.true_anomaly_rad)) == pytest.approx(
            math.atan2(v @ along, v @ radial), abs=1e-12)
        half = nu / 2
        printed = math.atan(-2 / math.tan(half) * (1 - math.sin(half) ** 2) / (1 + math.cos(nu)))
        assert math.tan(float(steering.alpha_rad(1.0, nu))) == pytest.approx(-math.tan(printed), rel=1e-9)


@pytest.mark.parametrize("disturbance_deg_s2", [0.0, 0.0005, -0.0005])
def test_a_rate_and_acceleration_limited_slew_takes_the_trapezoid_time(disturbance_deg_s2):
    """Kinematics closed form: a rest-to-rest slew of 30 deg at 0.1 deg/s and 0.001 deg/s^2 takes
    30/0.1 + 0.1/0.001 = 400 s to rest at the target, never exceeding the rate bound nor overshooting.  A
    constant torque / inertia d shifts the wheels' window to [-a + d, a + d]: the ramps become w/(a + d) and
    w/(a - d) (swapped for -d), so the slew takes 30/0.1 + (0.1/0.0015 + 0.1/0.0005)/2 = 433.3 s either way.
    "At rest at the target" to the discrete law's resolution: within 1e-5 rad, the rate within a dt of zero
    (the law can chatter by a dt about the last micro-radian)."""
    rate, accel, step = math.radians(0.1), math.radians(0.001), 1.0
    disturbance = math.radians(disturbance_deg_s2)
    angle, speed, t = jnp.array(0.0), jnp.array(0.0), 0.0
    target = math.radians(30.0)
    slew = jax.jit(pointing.slew_step)
    while abs(float(angle) - target) > 1e-5 or abs(float(speed)) > accel * step:
        new_angle, new_speed = slew(angle, speed, target, rate, accel, step, disturbance)
        assert abs(float(new_speed)) <= rate * (1 + 1e-12) and float(new_angle) <= target + 1e-12
        assert disturbance - accel - 1e-15 <= float(new_speed - speed) / step <= disturbance + accel + 1e-15
        angle, speed, t = new_angle, new_speed, t + step
        assert t < 1000
    expected = 300.0 + 0.5 * (0.1 / (0.001 + abs(disturbance_deg_s2)) + 0.1 / (0.001 - abs(disturbance_deg_s2)))
    assert t == pytest.approx(expected, abs=2.0)


@pytest.mark.parametrize("wheels_deg_s2", [0.0, 0.004, 0.02])
def test_a_constant_torque_drives_a_body_at_rest_as_half_alpha_t_squared(wheels_deg_s2):
    """Newton for a rigid body (eq. (6) at rest, no rate terms): a torque T on inertia I with the wheels' authority
    a (holding the attitude, target = the start) turns the body by 0.5 (T/I - a) t^2 when T/I > a (a = 0: the
    free body's 0.5 (T/I) t^2), and not at all when the wheels can take it (T/I <= a)."""
    torque_nm, inertia_kg_m2, step = 0.75, 2000.0, 120.0
    alpha = torque_nm / inertia_kg_m2
    wheels = math.radians(wheels_deg_s2)
    slew = jax.jit(pointing.slew_step)
    angle, speed = jnp.array(0.0), jnp.array(0.0)
    for _ in range(10):
        angle, speed = slew(angle, speed, 0.0, math.radians(0.1), wheels, step, alpha)
    t = 10 * step
    assert float(angle) == pytest.approx(0.5 * max(alpha - wheels, 0.0) * t**2, rel=1e-12, abs=1e-15)
    assert float(speed) == pytest.approx(max(alpha - wheels, 0.0) * t, rel=1e-12, abs=1e-15)


def test_the_slew_axes_take_the_thrust_turn_of_the_torque():
    """Rigid-body kinematics, independent of the projection: a body angular acceleration J^-1 tau turns the
    body-frame thrust d (theta2 = 90 deg, theta3 = 0) by (J^-1 tau) x d; its azimuth and elevation rates
    (finite differences of atan2 and asin) are what ``slew_disturbance_rad_s2`` gives the two slew axes; a
    torque about d's in-plane direction does not move the thrust."""
    inertia = np.array([1800.0, 2500.0, 3100.0])
    for theta1 in (-1.2, -0.4, 0.0):
        d = np.asarray(boom.thrust_direction_body(jnp.array([theta1, math.pi / 2, 0.0])))
        for torque in RNG.normal(size=(3, 3)):
            eps = 1e-5 / np.linalg.norm(torque / inertia)  # a 1e-5 rad turn: central differences
            ahead, back = (d + sign * eps * np.cross(torque / inertia, d) for sign in (1, -1))
            expected = [(math.atan2(ahead[1], ahead[0]) - math.atan2(back[1], back[0])) / (2 * eps),
                        (math.asin(ahead[2]) - math.asin(back[2])) / (2 * eps)]
            got = pointing.slew_disturbance_rad_s2(jnp.asarray(torque), theta1, jnp.asarray(inertia))
            np.testing.assert_allclose(got, expected, rtol=1e-8, atol=1e-15)
        along = np.asarray(d) * inertia  # J^-1 tau parallel to d
        np.testing.assert_allclose(pointing.slew_disturbance_rad_s2(jnp.asarray(along), theta1, jnp.asarray(inertia)),
                                   0.0, atol=1e-15)


def test_mpc_tracks_a_ramp_within_its_limits():
    """Double-integrator closed form: a joint can follow a ramp of 0.01 deg/s exactly, so after the start-up the
    MPC's tracking error vanishes; the acceleration bound is never exceeded."""
    limits = boom.JointLimits(jnp.full(3, -2.0), jnp.full(3, 2.0), jnp.full(3, math.radians(0.5)),
                              jnp.full(3, math.radians(0.05)))
    weights = boom.MpcWeights(jnp.ones(3), jnp.zeros(3), jnp.full(3, 1e4))
    step, ramp = 10.0, math.radians(0.01)
    step_fn = jax.jit(boom.joint_step, static_argnums=(7, 8))
    theta, omega = jnp.zeros(3), jnp.zeros(3)
    for k in range(200):
        target = jnp.full(3, ramp * step * (k + 1))
        new_theta, new_omega = step_fn(theta, omega, target, jnp.full(3, ramp), limits, weights, step, 10, 20)
        assert np.all(np.abs(np.asarray(new_omega - omega)) <= math.radians(0.05) * step * (1 + 1e-9))
        theta, omega = new_theta, new_omega
    np.testing.assert_allclose(theta, ramp * step * 200, atol=math.radians(1e-4))


# One compilation serves the loop tests: the same Static (2 days, a record every step) for every transfer.
STATIC = Static(120.0, 1440, 1, 10, 20)


@pytest.fixture(scope="module")
def loop():
    return jax.jit(transfer.transfer, static_argnums=2)


def _run(loop, sc):
    final, records = loop(sc.params, transfer.env_grid(sc, STATIC), STATIC)
    return jax.device_get(final), jax.device_get(records)


def test_short_transfer_delta_v_is_the_rocket_equation_and_joints_stay_in_table_1(loop):
    """Rocket equation: the delivered Delta-V (integral of F/m) equals Isp g0 ln(m0/m1) of the mass used, and
    both equal F x firing time / mean mass to first order; Table 1's joint ranges and the drive's rate bound
    hold at every step of two days of the boom transfer (its body knocked about by the coupling torque)."""
    sc = transfer.load("ma2023-boom")
    final, records = _run(loop, sc)
    m0, m1 = float(sc.params.initial.mass_kg), float(final.craft.mass_kg)
    rocket = float(sc.params.isp_s) * c.G0_MPS2 * math.log(m0 / m1)
    assert float(final.craft.dv_mps) == pytest.approx(rocket, rel=1e-9)
    assert float(final.craft.dv_mps) == pytest.approx(0.5 * float(final.stats.firing_s) / (0.5 * (m0 + m1)), rel=1e-4)
    assert rocket > 1.0  # it fired
    theta = np.degrees(records.theta_rad)
    assert theta[:, 0].min() >= -90.0 - 1e-9 and theta[:, 0].max() <= 1e-9
    assert np.all(np.abs(theta[:, 1] - 90.0) < 1e-9) and np.all(np.abs(theta[:, 2]) <= 15.0 + 1e-9)
    assert np.all(np.abs(np.degrees(records.omega_rad_s)) <= 0.5 + 1e-9)
    assert np.ptp(np.degrees(records.theta_rad[:, 2])) > 5.0  # joint 3 worked its range


OFF_COM = {"boom.d2_m": 1.5, "boom.a1_m": 0.3, "boom.base_offset_m": [0.0, 0.0, -1.0]}  # thrust line 1.5 m off


def test_quadrilateral_keeps_its_joints_and_loses_more_thrust_to_slewing(loop):
    """The quadrilateral's thrusters never move (joints frozen at (0, 90, 0) deg), so with a slow body it must
    wait for slews the boom's joints absorb: more time lost to slewing over the same two days than a boom on
    a body stiff against its torque (1e8 kg m^2).  A boom mounted with its thrust line 1.5 m off the centre of
    mass (eq. (8) up to 1 N m against the wheels' 0.035 N m) loses more than either; the shipped mounting
    (the line through the centre of mass at the nominal pose) less than that one."""
    slow = {"attitude.slew_rate_deg_s": 0.02}
    stiff_final, _ = _run(loop, transfer.load("ma2023-boom", {**slow, "attitude.inertia_kg_m2": [1e8] * 3}))
    boom_final, _ = _run(loop, transfer.load("ma2023-boom", slow))
    off_final, _ = _run(loop, transfer.load("ma2023-boom", {**slow, **OFF_COM}))
    fixed_final, fixed_records = _run(loop, transfer.load("ma2023-quadrilateral", slow))
    np.testing.assert_allclose(np.degrees(fixed_records.theta_rad), np.broadcast_to([0.0, 90.0, 0.0], (1440, 3)),
                               atol=1e-12)
    assert float(fixed_final.stats.lost_to_slew_s) > float(stiff_final.stats.lost_to_slew_s) + 3600.0
    assert float(off_final.stats.lost_to_slew_s) > float(fixed_final.stats.lost_to_slew_s) + 3600.0
    assert float(off_final.stats.lost_to_slew_s) > float(boom_final.stats.lost_to_slew_s) + 3600.0
    assert float(fixed_final.stats.overpowered_s) == 0.0 and float(off_final.stats.overpowered_s) > 0.0


def test_the_shipped_mounting_leaves_only_joint_3s_lever(loop):
    """Closed form of eq. (8) for the shipped mounting (d2 = 0, l_0 = (0, 0, a1): the thrust line through the
    centre of mass at theta3 = 0 for every theta1): |tau| = F |(d1 + a1 s3) s3 - a1 c3 (1 - c3)|, zero at
    theta3 = 0; the two-day transfer's largest torque is that at joint 3's +-15 deg stop, never above it."""
    sc = transfer.load("ma2023-boom")
    p = sc.params
    f, d1, a1 = float(p.thrust_n), float(p.d1_m), float(p.a1_m)
    for theta1, theta3 in ((-0.3, 0.0), (-1.2, 0.0), (-0.7, 0.2), (-0.1, -0.26)):
        theta = jnp.asarray([theta1, np.pi / 2, theta3])
        s3, c3 = np.sin(theta3), np.cos(theta3)
        got = np.linalg.norm(boom.coupling_torque_nm(theta, f, p.d1_m, p.d2_m, p.a1_m, p.base_offset_m))
        assert got == pytest.approx(f * abs((d1 + a1 * s3) * s3 - a1 * c3 * (1 - c3)), abs=1e-12)
    final, _ = _run(loop, sc)
    s3, c3 = np.sin(np.radians(15.0)), np.cos(np.radians(15.0))
    stop = f * ((d1 + a1 * s3) * s3 - a1 * c3 * (1 - c3))
    assert float(final.stats.torque_max_nm) <= stop * (1 + 1e-9)
    assert float(final.stats.torque_max_nm) >= 0.9 * stop  # joint 3 reached its stop while firing


def test_the_body_accelerates_within_the_wheels_window_shifted_by_the_torque(loop):
    """Eq. (6) with bounded wheels, |tau_c| <= J a: at every step of two days the body's rate change lies in
    [(-a + delta) dt, (a + delta) dt], delta = J^-1 tau of the step's recorded eq. (8) torque on each slew axis
    (numpy, from the records); on the mounting 1.5 m off the centre of mass the torque beats the wheels on some
    steps (a change beyond a dt), the quadrilateral's is zero (no boom arm) and its body never exceeds a."""
    sc = transfer.load("ma2023-boom", OFF_COM)
    _, records = _run(loop, sc)
    a, dt = float(sc.params.slew_accel_rad_s2), STATIC.step_s
    alpha = np.asarray(records.torque_nm) / np.asarray(sc.params.inertia_kg_m2)
    theta1 = np.asarray(records.theta_rad)[:-1, 0]  # the joint angle the step flew with (the previous record's)
    alpha = alpha[1:]
    delta = np.stack([alpha[:, 2], alpha[:, 0] * np.cos(theta1) + alpha[:, 1] * np.sin(theta1)], -1)
    change = np.diff(np.asarray(records.body_rate_rad_s), axis=0) / dt
    assert np.all(change >= delta - a - 1e-12) and np.all(change <= delta + a + 1e-12)
    assert np.abs(change).max() > 10 * a
    _, fixed = _run(loop, transfer.load("ma2023-quadrilateral"))
    assert np.all(np.asarray(fixed.torque_nm) == 0.0)
    assert np.abs(np.diff(np.asarray(fixed.body_rate_rad_s), axis=0)).max() <= a * dt * (1 + 1e-12)


def test_a_transfer_that_starts_at_geo_ends_at_once_and_freezes(loop):
    """Termination is data: a circular equatorial start at the GEO radius meets the end conditions after the
    first step (status 0, the success, t_end = one step), and the state is frozen from then on (mass unchanged)."""
    alt_km = 42164.16 - c.R_EARTH_M / 1e3
    sc = transfer.load("ma2023-boom", {"orbit.perigee_alt_km": alt_km, "orbit.apogee_alt_km": alt_km,
                                       "orbit.i_deg": 0.01})
    final, records = _run(loop, sc)
    assert int(final.status) == transfer.STATUS_REACHED_GEO == 0 and float(final.t_end_s) == 120.0
    assert np.all(records.mass_kg == records.mass_kg[0])


@pytest.mark.parametrize("argv, message", [
    (["transfer", "nowhere"], "transfer scenario 'nowhere': unknown"),
    (["transfer", "ma2023-boom", "--days", "0"], "duration.days: must be > 0"),
    (["transfer", "li2022"], "transfer scenario 'li2022': unknown"),
])
def test_bad_input_exits_2_with_one_line(argv, message, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_bad_fields_name_the_field(tmp_path):
    """A transfer file's mistakes are one line naming the field (the station-keeping scenarios' convention)."""
    text = (transfer.scenario._shipped() / "ma2023-boom.toml").read_text()
    for old, new, message in [('layout = "boom"', 'layout = "arm"', "thruster.layout: must be one of"),
                              ("dry_mass_kg = 2000.0", "dry_mass_kg = 3000.0", "spacecraft.dry_mass_kg: must be less"),
                              ("j2_deg = [75.0, 105.0]", "j2_deg = [95.0, 105.0]", "boom.j2_deg: must contain")]:
        path = tmp_path / "bad.toml"
        path.write_text(text.replace(old, new))
        with pytest.raises(ValueError, match=message.replace("(", r"\(")):
            transfer.load(path)
    assert "ma2023-boom" not in __import__("geojax").scenario.available()


def test_cli_writes_metrics_and_records(tmp_path, capsys):
    """The HDF5 file holds what the summary printed (read back with h5py, an independent reader); half a day
    stops at the time limit, status 1, a failure as in ``simulate`` (0 is success), the file's codes say so."""
    import h5py

    out = tmp_path / "t.h5"
    assert cli.main(["transfer", "ma2023-quadrilateral", "--days", "0.5", "--out", str(out)]) == 0
    assert "  status 1: time limit reached first" in capsys.readouterr().out.splitlines()
    with h5py.File(out) as f:
        assert int(f["metrics/status"][()]) == 1 and f.attrs["layout"] == "quadrilateral"
        assert f.attrs["status_codes"].startswith("0 reached GEO") and "1 time limit reached first" in f.attrs["status_codes"]
        assert float(f["metrics/transfer_days"][()]) == pytest.approx(0.5)
        assert f["records/a_km"].shape == (1,) and 'layout = "quadrilateral"' in f.attrs["config_toml"]


def test_a_transfer_is_refused_by_station_keeping_and_shown_by_scenarios(capsys):
    """The shipped-scenario list stays station keeping; a transfer named to `simulate` says where it belongs."""
    assert cli.main(["simulate", "ma2023-boom"]) == 2
    assert "run it with `geojax transfer ma2023-boom`" in capsys.readouterr().err
    assert cli.main(["scenarios", "--show", "ma2023-quadrilateral"]) == 0
    assert 'layout = "quadrilateral"' in capsys.readouterr().out


def test_apsis_gain_is_the_kepler_change_of_the_apsides_and_fires_at_apogee_first():
    """G(nu) against a finite impulse: add 1 mm/s along the velocity of the Cartesian state and recompute the
    apsides with cartesian_to_kepler (independent of the closed form); on the GTO (perigee 35,000 km short,
    apogee 45 km short) the rule fires forward at apogee and not at perigee."""
    from geojax.physics.elements import cartesian_to_kepler

    mu, r_geo = c.MU_EARTH_M3_S2, 42164.16e3
    for nu in np.radians([10.0, 100.0, 180.0, 260.0]):
        mee = kepler_to_mee(24.7e6, 0.7, 0.36, 0.3, math.pi, nu)
        geo = steering.orbit_geometry(mee)
        r, v = (np.asarray(x) for x in mee_to_cartesian(mee, mu))
        dv = 1e-3
        a1, e1, *_ = cartesian_to_kepler(jnp.asarray(r), jnp.asarray(v + dv * v / np.linalg.norm(v)), mu)
        d_perigee = float(a1 * (1 - e1)) - float(geo.perigee_m)
        d_apogee = float(a1 * (1 + e1)) - float(geo.apogee_m)
        expected = ((r_geo - float(geo.perigee_m)) * d_perigee + (r_geo - float(geo.apogee_m)) * d_apogee) / dv
        gain = float(steering.apsis_gain(geo, r_geo, geo.true_anomaly_rad, mu))
        assert gain == pytest.approx(expected, rel=1e-5)
    span_m = 2 * c.R_EARTH_M + 964e3 + 35741e3
    gto = dict(a_m=0.5 * span_m, e=(35741e3 - 964e3) / span_m)
    at = {nu: steering.steer(_geometry(math.radians(nu), **gto), r_geo, 20e3, math.radians(0.1), 0.5, mu)
          for nu in (0.0, 180.0)}
    assert float(at[180.0].fire) == 1.0 and float(at[180.0].azimuth_rad) == pytest.approx(math.pi / 2)
    assert float(at[0.0].fire) == 1.0  # the plane change (i = 20.8 deg) fires all orbit long ...
    flat = _geometry(0.0, **gto, i_rad=0.0)
    assert float(steering.steer(flat, r_geo, 20e3, math.radians(0.1), 0.5, mu).fire) == 0.0  # ... the rule: not here


def _rotation(angle_rad):
    """2x2 rotation in the face's (t, l) plane, from t towards l."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s], [s, c]])


@pytest.mark.parametrize("cant_deg", [0.0, 20.0, 40.0, 45.0, 50.0])
def test_quadrilateral_pairs_resultant_and_cosine_loss_are_the_closed_form(cant_deg):
    """Closed form of a planar quadrilateral canted by c from its north-south axis: the north pair's resultant
    per unit thrust is cos c along t (lateral parts cancel), the east pair's sin c along l, a diagonal pair's
    zero; the cosine loss 1 - cos c is 23.4 % at 40 deg and 29.3 % at 45 deg.  The thrusters are built by
    rotation matrices; the best of the six pairs (numpy) is max(cos c, sin c), what the layout flies."""
    cant = math.radians(cant_deg)
    units = np.asarray(quadrilateral.thruster_units(jnp.asarray(cant)))
    t = np.array([1.0, 0.0])  # NE, NW: t turned by +-c; SE, SW: -t turned by the same (towards +l, -l)
    built = np.array([_rotation(cant) @ t, _rotation(-cant) @ t, -_rotation(-cant) @ t, -_rotation(cant) @ t])
    np.testing.assert_allclose(units, built, atol=1e-15)
    north, east, diagonal = units[[0, 1]].mean(0), units[[0, 2]].mean(0), units[[0, 3]].mean(0)
    np.testing.assert_allclose(north, [math.cos(cant), 0.0], atol=1e-15)
    np.testing.assert_allclose(east, [0.0, math.sin(cant)], atol=1e-15)
    np.testing.assert_allclose(diagonal, [0.0, 0.0], atol=1e-15)
    best = max(np.linalg.norm(units[[i, j]].mean(0)) for i in range(4) for j in range(i + 1, 4))
    eff = np.asarray(quadrilateral.pair_axis_efficiency(jnp.asarray(cant)))
    assert eff[0] == pytest.approx(best, abs=1e-15) and eff[1] == eff[0]
    assert eff[2] == pytest.approx(min(math.cos(cant), math.sin(cant)), abs=1e-15)
    if cant_deg in (40.0, 45.0):
        assert 1 - eff[0] == pytest.approx({40.0: 0.2340, 45.0: 0.2929}[cant_deg], abs=5e-5)


def test_best_pair_fires_the_pair_closest_to_the_wish():
    """The south pair serves a wish behind the body (no half-turn), the north pair one ahead; the resultant's
    norm is the pair's efficiency; a layout without a south pair (the boom: (1, 0, 0, 0)) gets none behind."""
    t, l = jnp.array([0.0, 1.0, 0.0]), jnp.array([1.0, 0.0, 0.0])
    eff = quadrilateral.pair_axis_efficiency(jnp.asarray(math.radians(40.0)))
    ahead = jnp.array([0.1, 0.99, 0.0]) / math.hypot(0.1, 0.99)
    for wish, index in ((ahead, 0), (-ahead, 1), (jnp.array([1.0, 0.0, 0.0]), 2)):
        got, resultant = quadrilateral.best_pair(t, l, wish, eff)
        assert int(got) == index and float(jnp.linalg.norm(resultant)) == pytest.approx(float(eff[index]))
    _, resultant = quadrilateral.best_pair(t, l, -ahead, jnp.array([1.0, 0.0, 0.0, 0.0]))
    assert float(jnp.linalg.norm(resultant)) == 0.0


def test_quadrilateral_delivers_cos_cant_of_the_thrust_for_the_same_propellant(loop):
    """Gauss's equations to first order: the same firing pattern with the pair's resultant scaled by cos c
    turns the orbit plane (the first days' plane change) by cos c times as much per second of firing (c = 40 deg
    against 0), for the same propellant per second (the pair's mass flow F / (Isp g0) does not depend on its cant)."""
    final0, rec0 = _run(loop, transfer.load("ma2023-quadrilateral", {"thruster.cant_deg": 0.0}))
    final40, rec40 = _run(loop, transfer.load("ma2023-quadrilateral", {"thruster.cant_deg": 40.0}))
    firing0, firing40 = float(final0.stats.firing_s), float(final40.stats.firing_s)
    assert firing40 == pytest.approx(firing0, rel=0.01)  # the pattern differs only where the orbits have drifted
    used0, used40 = (2500.0 - float(f.craft.mass_kg) for f in (final0, final40))
    assert used40 / firing40 == pytest.approx(used0 / firing0, rel=1e-6)
    i_start = float(steering.orbit_geometry(transfer.load("ma2023-boom").params.initial.orbit).i_rad)
    ratio = (float(rec40.i_rad[-1]) - i_start) / firing40 / ((float(rec0.i_rad[-1]) - i_start) / firing0)
    assert ratio == pytest.approx(math.cos(math.radians(40.0)), rel=0.01)
    assert float(final40.stats.aligned_s) / float(final40.stats.firing_s) == pytest.approx(
        math.cos(math.radians(40.0)), rel=0.002)


def test_one_slews_attitude_propellant_is_the_hand_impulse_budget():
    """Impulse budget by hand for one rest-to-rest slew of 30 deg at 0.1 deg/s on J = 2000 kg m^2: the
    thrusters give J w = 2000 x 1.745e-3 = 3.49 N m s to start and as much to stop, 6.98 N m s, which a couple of
    1 m arm at 220 s pays with 6.98 / (1 x 220 x 9.80665) = 3.24 g; summing |slew_torque_nm| dt over the
    discrete slew gives the same (to the last step's chatter)."""
    inertia, rate, accel, step = 2000.0, math.radians(0.1), math.radians(0.001), 1.0
    angle, speed, impulse = jnp.array(0.0), jnp.array(0.0), 0.0
    slew = jax.jit(pointing.slew_step)
    for _ in range(500):
        new_angle, new_speed = slew(angle, speed, math.radians(30.0), rate, accel, step)
        impulse += abs(float(pointing.slew_torque_nm(speed, new_speed, step, 0.0, accel, inertia))) * step
        angle, speed = new_angle, new_speed
    assert float(angle) == pytest.approx(math.radians(30.0), abs=1e-5)
    hand_kg = 2 * inertia * rate / (1.0 * 220.0 * 9.80665)
    assert hand_kg == pytest.approx(3.236e-3, rel=1e-3)
    assert float(pointing.attitude_propellant_kg(impulse, 1.0, 220.0)) == pytest.approx(hand_kg, rel=0.01)
    # a push twice what the wheels hold, the wheels braking at full (body accelerating at 2a - a): no slew is
    # charged; the same body change with no push is a slew of J a
    assert float(pointing.slew_torque_nm(0.0, accel * step, step, 2.0 * accel, accel, inertia)) == 0.0
    no_push = pointing.slew_torque_nm(0.0, accel * step, step, 0.0, accel, inertia)
    assert float(no_push) == pytest.approx(inertia * accel)


@pytest.mark.parametrize("seed", range(3))
def test_remark_2_split_never_exceeds_a_joint_range(seed):
    """Ma 2023 Remark 2, joints first within their ranges, attitude for the rest, against Table 1: for wishes
    over the whole sphere of directions and any body lag, the joints' share stays within [low, high]
    (azimuth 0-90 deg, elevation +-15 deg); inside the range the body's share is zero; with the body at its
    share, body + joints = the wish (mod 2 pi)."""
    rng = np.random.default_rng(seed)
    low, high = jnp.radians(jnp.array([0.0, -15.0])), jnp.radians(jnp.array([90.0, 15.0]))
    for _ in range(50):
        wish = jnp.asarray([rng.uniform(-math.pi, math.pi), rng.uniform(-math.pi / 2, math.pi / 2)])
        body = pointing.body_share_rad(wish, low, high)
        for lag in (jnp.zeros(2), jnp.asarray(rng.normal(0, 0.5, 2))):
            joints = np.asarray(pointing.joint_share_rad(wish, body + lag, low, high))
            assert np.all(joints >= np.asarray(low) - 1e-15) and np.all(joints <= np.asarray(high) + 1e-15)
        joints = pointing.joint_share_rad(wish, body, low, high)
        np.testing.assert_allclose(np.angle(np.exp(1j * np.asarray(body + joints - wish))), 0.0, atol=1e-12)
        inside = (np.asarray(wish) >= np.asarray(low)) & (np.asarray(wish) <= np.asarray(high))
        assert np.all(np.asarray(body)[inside] == 0.0)


def test_the_slew_settles_on_a_moving_target_without_a_limit_cycle():
    """A rest start behind a target moving at 0.004 deg/s (the attitude loop's 10 s step, 0.1 deg/s, 0.001
    deg/s^2): the body ends on the target at the target's rate, and the total variation of its rate is that
    of one acceleration and one braking, below 2 x the rate bound (a law that chatters about the target adds
    a x dt at every step: 400 steps of it would be 40 times that)."""
    rate, accel, step, v = math.radians(0.1), math.radians(0.001), 10.0, math.radians(0.004)
    slew = jax.jit(pointing.slew_step)
    angle, speed, target, variation = jnp.array(0.0), jnp.array(0.0), math.radians(5.0), 0.0
    for _ in range(400):
        new_angle, new_speed = slew(angle, speed, target, rate, accel, step, 0.0, v)
        variation += abs(float(new_speed - speed))
        angle, speed, target = new_angle, new_speed, target + v * step
    assert float(angle) == pytest.approx(target, abs=1e-9) and float(speed) == pytest.approx(v, abs=1e-12)
    assert variation <= 2 * rate


def test_the_moons_shadow_cuts_the_thrust_as_the_earths_does():
    """A solar eclipse by the Moon (Montenbruck & Gill's conical model with the Moon as the occulting body):
    the Sun straight above the satellite (so the Earth hides none of it) and the Moon 300,000 km from the
    satellite on the line to the Sun (its disc, 0.33 deg in radius, covers the Sun's 0.27 deg: umbra).  One
    step from the start fires its full Delta-V (F/m over the step, to first order in the mass change)
    without ``moon_shadow``, or with the Moon moved 10 deg off the line, and nothing with it."""
    from geojax.physics.elements import mee_to_rv_xyz
    from geojax.physics.forces import Environment
    from geojax.transfer.rollout import _step, initial_carry

    step = jax.jit(_step, static_argnums=3)

    def one_step(moon_shadow: bool, off_deg: float = 0.0):
        sc = transfer.load("ma2023-boom", {"forces.moon_shadow": moon_shadow})
        (x, y, z), _ = mee_to_rv_xyz(*(sc.params.initial.orbit[j] for j in range(6)), c.MU_EARTH_M3_S2)
        r = np.array([float(x), float(y), float(z)])
        up = r / np.linalg.norm(r)
        side = np.cross(up, [0.0, 0.0, 1.0])
        side /= np.linalg.norm(side)
        towards_moon = math.cos(math.radians(off_deg)) * up + math.sin(math.radians(off_deg)) * side
        env3 = Environment(jnp.asarray(np.tile(r + 1.496e11 * up, (3, 1))),
                           jnp.asarray(np.tile(r + 3.0e8 * towards_moon, (3, 1))),
                           jnp.zeros(3), jnp.ones(3), jnp.zeros(3))
        carry, _ = step(initial_carry(sc.params), env3, sc.params, STATIC)
        return float(carry.craft.dv_mps), float(sc.params.thrust_n) / float(sc.params.initial.mass_kg) * STATIC.step_s

    fired, full = one_step(False)
    assert fired == pytest.approx(full, rel=1e-4)
    assert one_step(True, off_deg=10.0)[0] == pytest.approx(full, rel=1e-4)
    assert one_step(True)[0] == 0.0


def test_the_boom_unloads_its_wheels_with_its_own_line(loop):
    """The wheels over two days of the boom's transfer (``transfer.wheels``): with attitude thrusters alone they are
    unloaded many times (eq. (8) fills 50 N m s wheels in hours of firing at joint 3's stop; the conservation and
    the closed forms are in tests/test_transfer_wheels.py), never holding more than the 80 % threshold plus a
    step's impulse; with the line tilted up to 30 deg the boom's own torque unloads them: fewer
    thruster unloadings, a tilt impulse and a Delta-V across the line > 0, and the thrust along the wish lower by
    at most 1 - cos 30 deg.  The quadrilateral's pairs fire through the centre of mass: its wheels only turn the
    body with the orbit frame (at most I n at perigee, 2.6 N m s) and are never unloaded."""
    plain, _ = _run(loop, transfer.load("ma2023-boom"))
    tilted, records = _run(loop, transfer.load("ma2023-boom", {"attitude.dump_angle_max_deg": 30.0}))
    assert float(plain.wheels.rcs_dumps) >= 10 and float(plain.wheels.tilt_impulse_nms) == 0.0
    assert float(tilted.wheels.rcs_dumps) < 0.5 * float(plain.wheels.rcs_dumps)
    assert float(tilted.wheels.tilt_impulse_nms) > 0.0 and float(tilted.wheels.tilt_cross_mps) > 0.0
    assert np.max(np.abs(records.wheel_nms)) <= 0.8 * 50.0 + 0.1 * 120.0  # a step's impulse beyond the threshold
    efficiency = lambda final: float(final.stats.aligned_s) / float(final.stats.firing_s)  # noqa: E731
    assert efficiency(plain) * math.cos(math.radians(30.0)) - 1e-9 <= efficiency(tilted) < efficiency(plain)
    quad, _ = _run(loop, transfer.load("ma2023-quadrilateral"))
    r_p = (964.0 + c.R_EARTH_M / 1e3) * 1e3
    a = 0.5 * (r_p + (35741.0 + c.R_EARTH_M / 1e3) * 1e3)
    n_perigee = math.sqrt(c.MU_EARTH_M3_S2 * a * (1 - ((a - r_p) / a) ** 2)) / r_p**2
    assert float(quad.wheels.rcs_dumps) == 0.0
    assert float(np.max(quad.wheels.max_abs_nms)) <= 2000.0 * n_perigee * 1.01


def test_a_transfer_flown_in_blocks_for_its_progress_is_the_one_call(capsys):
    """``run`` flies its records in blocks (``rollout.advance``) so that a bar can count them; second method: the
    whole transfer in one call of ``rollout.transfer``, the same numbers to the last bits (XLA orders a block's
    operations a little differently from the whole loop's: 4e-16 relative here)."""
    sc = transfer.load("ma2023-boom")
    static = transfer.static_for(sc, 1.0, 3600.0)  # 24 records of 30 steps: 24 blocks
    final, records = jax.device_get(jax.jit(transfer.transfer, static_argnums=2)(sc.params, transfer.env_grid(sc, static),
                                                                                 static))
    blocked = transfer.run(sc, 1.0, record_every_s=3600.0, progress=True)
    assert "24/24 records" in capsys.readouterr().err
    for name, value in transfer.metrics(final, sc.params).items():
        np.testing.assert_allclose(blocked.metrics[name], value, rtol=1e-12, atol=1e-12, err_msg=name)
    from geojax.transfer.run import record_table

    for name, value in record_table(records).items():
        np.testing.assert_allclose(blocked.records[name], value, rtol=1e-12, atol=1e-12, err_msg=name)
