"""Navigation: stations, measurement models, schedules, the EKF's pieces and the planned keys.

Each test names its independent check: closed-form geometry of a geostationary satellite, central finite
differences, the standard Kalman update, a Monte Carlo draw, the integral that defines the process noise,
published chi-square quantiles, and a batch least-squares information matrix on a Kepler propagator (the
Cramer-Rao bound) against the filter run on an RK4 propagator.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.navigation import ekf, keys
from geojax.navigation.measurements import MODELS, elevation_visible, jacobian, light_times_s, observed
from geojax.navigation.schedule import continuous, schedule, tracking_weight
from geojax.navigation.stations import station_from_geodetic
from geojax.physics.constants import C_MPS, MU_EARTH_M3_S2, OMEGA_EARTH_RAD_S, WGS84_A_M, WGS84_F

R_GEO_M = 42164.16e3


def _geostationary(lon_rad, earth_angle_rad=0.0, r_m=R_GEO_M):
    """A satellite fixed above longitude ``lon_rad``: ECI state at the Earth angle (co-rotating, v = omega x r)."""
    angle = lon_rad + earth_angle_rad
    r = r_m * jnp.array([jnp.cos(angle), jnp.sin(angle), 0.0])
    v = OMEGA_EARTH_RAD_S * r_m * jnp.array([-jnp.sin(angle), jnp.cos(angle), 0.0])
    return jnp.concatenate([r, v])


@pytest.mark.parametrize("alt_m", [0.0, 1500.0])
def test_range_to_the_subsatellite_point_is_r_minus_the_earth_radius(alt_m):
    """Closed form: a station on the equator under a geostationary satellite is r - a - h away.  Light time adds
    r R (omega tau)^2 / (2 (r - R)) per leg (0.3 mm): the satellite and the station both turn by omega tau while
    the signal travels, and the leg is the chord of that angle."""
    lon, angle = np.deg2rad(75.0), 1.3
    station = station_from_geodetic(0.0, lon, alt_m)
    x = _geostationary(lon, angle)
    rho = R_GEO_M - WGS84_A_M - alt_m
    tau = rho / C_MPS
    closed = rho + R_GEO_M * (WGS84_A_M + alt_m) * (OMEGA_EARTH_RAD_S * tau) ** 2 / (2 * rho)
    got = float(MODELS["range"].h(x, station, angle)[0])
    assert got == pytest.approx(closed, abs=1e-6)
    assert abs(got - rho) < 1e-3
    # A co-rotating satellite seen from under it: no range rate.
    assert abs(float(MODELS["range_rate"].h(x, station, angle)[0])) < 1e-6


def test_light_time_at_geo():
    """Closed form: the two-way light time to a satellite overhead at GEO is 2 x 35786 km / c = 0.2387 s."""
    station = station_from_geodetic(0.0, 0.0, 0.0)
    tau_down, tau_up = light_times_s(_geostationary(0.0), station, 0.0)
    assert float(tau_down + tau_up) == pytest.approx(2 * 35786.0e3 / C_MPS, rel=1e-5)
    assert float(tau_down + tau_up) == pytest.approx(0.2387, abs=1e-4)


def test_a_satellite_overhead_is_at_90_degrees_elevation_less_its_light_time_arc():
    """Closed form: overhead means elevation 90 deg, except that the satellite is seen where it was a down-leg
    light time tau earlier, turned by omega tau about the Earth's axis: elevation atan2(r cos(omega tau) - R,
    r sin(omega tau)) = 90 deg - 5.9e-4 deg, toward the west (azimuth 270 deg)."""
    angle = 0.4
    station = station_from_geodetic(0.0, 0.0, 0.0)
    az, el = MODELS["angles"].h(_geostationary(0.0, angle), station, angle)
    turn = OMEGA_EARTH_RAD_S * (R_GEO_M - WGS84_A_M) / C_MPS
    closed = np.arctan2(R_GEO_M * np.cos(turn) - WGS84_A_M, R_GEO_M * np.sin(turn))
    assert float(el) == pytest.approx(closed, abs=1e-9)
    assert 90.0 - np.rad2deg(float(el)) == pytest.approx(5.9e-4, abs=1e-5)
    assert float(az) == pytest.approx(1.5 * np.pi, abs=1e-9)


@pytest.mark.parametrize("lat_deg", [30.0, -45.0, 70.0])
def test_elevation_from_a_station_on_the_satellites_meridian(lat_deg):
    """Closed form on the ellipsoid by another parametrisation: the station at reduced latitude beta, tan beta =
    (1 - f) tan(lat), sits at (a cos beta, b sin beta) in its meridian plane with normal (cos lat, sin lat), so
    sin(el) = n . (r - s) / |r - s|; the satellite is due south (north) of a northern (southern) station.  The
    light-time arc (east-west, 2") moves the elevation by its square, < 1e-10 rad."""
    lat, lon = np.deg2rad(lat_deg), np.deg2rad(-20.0)
    b = WGS84_A_M * (1 - WGS84_F)
    beta = np.arctan((1 - WGS84_F) * np.tan(lat))
    s = np.array([WGS84_A_M * np.cos(beta), b * np.sin(beta)])
    d = np.array([R_GEO_M, 0.0]) - s
    closed = np.arcsin(np.dot([np.cos(lat), np.sin(lat)], d) / np.linalg.norm(d))
    az, el = MODELS["angles"].h(_geostationary(lon, 2.0), station_from_geodetic(lat, lon, 0.0), 2.0)
    assert float(el) == pytest.approx(closed, abs=1e-9)
    assert float(jnp.cos(az)) == pytest.approx(-np.sign(lat_deg), abs=1e-9)
    station = station_from_geodetic(lat, lon, 0.0)
    visible = [float(elevation_visible(_geostationary(lon, 2.0), station, 2.0, np.deg2rad(m))) for m in (5.0, 30.0)]
    assert visible == [float(closed >= np.deg2rad(5.0)), float(closed >= np.deg2rad(30.0))]


@pytest.mark.parametrize("kind", list(MODELS))
def test_jacobians_against_central_differences(kind):
    """Second method: central differences of the measurement (10 m in position, 1 m/s in velocity; the
    truncation error is h^2 times third derivatives of order 1/rho^2, far below the tolerance)."""
    x = _geostationary(np.deg2rad(10.0), 0.9) + jnp.array([3.0e3, -2.0e3, 5.0e3, 0.4, -0.3, 0.8])
    station = station_from_geodetic(np.deg2rad(35.0), np.deg2rad(-5.0), 400.0)
    h = MODELS[kind].h
    got = np.asarray(jacobian(h, x, station, 0.9))
    steps = np.array([10.0, 10.0, 10.0, 1.0, 1.0, 1.0])
    finite = np.stack([(np.asarray(h(x.at[j].add(steps[j]), station, 0.9))
                        - np.asarray(h(x.at[j].add(-steps[j]), station, 0.9))) / (2 * steps[j]) for j in range(6)], -1)
    assert got.shape == (MODELS[kind].size, 6)
    scale = np.max(np.abs(got), axis=1, keepdims=True)
    assert np.all(np.abs(got - finite) <= 1e-6 * scale)


def test_noise_and_bias_of_a_measurement():
    """Sample statistics: z - h(x) has the bias for mean and sigma for standard deviation (4000 draws)."""
    station = station_from_geodetic(np.deg2rad(30.0), 0.0, 0.0)
    x = _geostationary(0.0)
    keys_ = jax.random.split(jax.random.PRNGKey(3), 4000)
    z = jax.vmap(lambda k: observed(MODELS["range"].h, x, station, 0.0, 5.0, 12.0, k))(keys_)[:, 0]
    residual = np.asarray(z - MODELS["range"].h(x, station, 0.0)[0])
    assert residual.mean() == pytest.approx(12.0, abs=4 * 5.0 / np.sqrt(4000))
    assert residual.std() == pytest.approx(5.0, rel=0.05)


def test_joseph_update_equals_the_standard_form_and_stays_positive_definite():
    """Second method: on a well-conditioned case the Joseph form equals (I - K H) P; over many small-noise updates
    (where the standard form loses symmetry and definiteness) it stays symmetric positive definite; weight 0 changes
    nothing."""
    rng = np.random.default_rng(4)
    a = rng.normal(size=(6, 6))
    p = a @ a.T + 6 * np.eye(6)
    p = jnp.asarray((p + p.T) / 2)
    h = jnp.asarray(rng.normal(size=(2, 6)))
    r = jnp.asarray(np.diag([0.5, 2.0]))
    y = jnp.asarray(rng.normal(size=2))
    x = jnp.zeros(6)
    x1, p1, s = ekf.measurement_update(x, p, y, h, r)
    k = p @ h.T @ np.linalg.inv(h @ p @ h.T + r)
    np.testing.assert_allclose(p1, (np.eye(6) - k @ h) @ p, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(x1, k @ y, rtol=1e-12)
    np.testing.assert_allclose(s, h @ p @ h.T + r, rtol=1e-14)
    x0, p0, _ = ekf.measurement_update(x, p, y, h, r, weight=0.0)
    assert np.array_equal(x0, x) and np.array_equal(p0, p)
    scales = jnp.asarray([1e4, 1e4, 1e4, 1.0, 1.0, 1.0])
    p = jnp.diag(scales**2)
    update = jax.jit(lambda p, h: ekf.measurement_update(x, p, jnp.zeros(1), h, jnp.asarray([[1e-8]]))[1])
    for h in rng.normal(size=(50, 1, 6)):
        p = update(p, jnp.asarray(h) / scales)
    assert np.array_equal(p, p.T)
    assert np.min(np.linalg.eigvalsh(np.asarray(p) / np.outer(scales, scales))) > 0


def test_process_noise_is_the_integral_of_white_acceleration():
    """Definition: Q = q integral_0^dt Phi(s) G G^T Phi(s)^T ds with Phi(s) = [[I, s I], [0, I]], G = [0; I]
    (Simpson's rule, exact for the cubic integrand)."""
    dt, sigma = 300.0, 2e-9
    s = np.linspace(0.0, dt, 3)
    block = [np.block([[si**2 * np.eye(3), si * np.eye(3)], [si * np.eye(3), np.eye(3)]]) for si in s]
    integral = dt / 6 * (block[0] + 4 * block[1] + block[2]) * sigma**2
    np.testing.assert_allclose(ekf.process_noise(dt, sigma), integral, rtol=1e-14)


def test_chi2_bounds_are_the_published_quantiles():
    """Published values (chi-square table): 2.5 % and 97.5 % of chi^2(3) are 0.2158 and 9.348; the average of
    N NEES values of n dof, times N, is chi^2(N n)."""
    assert ekf.chi2_bounds(3, 1) == pytest.approx((0.2158, 9.348), abs=1e-3)
    low, high = ekf.chi2_bounds(6, 64)
    # Wilson-Hilferty for chi^2(384): 384 (1 - 2/(9 384) +- 1.96 sqrt(2/(9 384)))^3 / 64
    k = 384
    wh = [k * (1 - 2 / (9 * k) + z * np.sqrt(2 / (9 * k))) ** 3 / 64 for z in (-1.959964, 1.959964)]
    assert (low, high) == pytest.approx(wh, rel=1e-3)
    e = jnp.asarray([1.0, 2.0, 3.0])
    assert float(ekf.nees(e, jnp.diag(jnp.asarray([1.0, 4.0, 9.0])))) == pytest.approx(3.0, rel=1e-14)


def _kepler(x0, dt_s, mu=MU_EARTH_M3_S2):
    """Two-body state after ``dt_s``: Lagrange f and g in the eccentric-anomaly change (Battin 1999, Sec. 4.5),
    Kepler's equation by a fixed 12 Newton passes (quadratic convergence from dE = n dt at e ~ 1e-4)."""
    r0v, v0v = x0[:3], x0[3:]
    r0 = jnp.linalg.norm(r0v)
    a = 1.0 / (2.0 / r0 - jnp.dot(v0v, v0v) / mu)
    sigma0 = jnp.dot(r0v, v0v) / jnp.sqrt(mu)
    mean = jnp.sqrt(mu / a**3) * dt_s
    de = mean
    for _ in range(12):
        f = de - (1 - r0 / a) * jnp.sin(de) + sigma0 / jnp.sqrt(a) * (1 - jnp.cos(de)) - mean
        de = de - f / (1 - (1 - r0 / a) * jnp.cos(de) + sigma0 / jnp.sqrt(a) * jnp.sin(de))
    r = a + (r0 - a) * jnp.cos(de) + sigma0 * jnp.sqrt(a) * jnp.sin(de)
    f = 1 - a / r0 * (1 - jnp.cos(de))
    g = dt_s - jnp.sqrt(a**3 / mu) * (de - jnp.sin(de))
    f_dot = -jnp.sqrt(mu * a) / (r * r0) * jnp.sin(de)
    g_dot = 1 - a / r * (1 - jnp.cos(de))
    return jnp.concatenate([f * r0v + g * v0v, f_dot * r0v + g_dot * v0v])


def _rk4_two_body(x, dt_s, substeps):
    def rhs(y):
        return jnp.concatenate([y[3:], -MU_EARTH_M3_S2 * y[:3] / jnp.linalg.norm(y[:3]) ** 3])

    def step(x, _):
        k1 = rhs(x)
        k2 = rhs(x + h / 2 * k1)
        k3 = rhs(x + h / 2 * k2)
        k4 = rhs(x + h * k3)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), None

    h = dt_s / substeps
    return jax.lax.scan(step, x, None, length=substeps)[0]


@pytest.mark.slow  # the loop's filter meets the same bound in the default tier (test_navigation_loop.py)
def test_filter_covariance_matches_the_batch_least_squares_bound():
    """Independent method (the Cramer-Rao check): two stations (30 deg N and 30 deg S of the sub-satellite
    point, 15 deg apart in longitude) range an unperturbed, slightly eccentric and inclined GEO orbit every
    10 min for a day, sigma 5 m.  The batch information matrix P0^-1 + sum Phi_k^T H_k^T R^-1 H_k Phi_k, at the
    truth, with Phi_k from jax.jacfwd of a Kepler (f and g) propagator, mapped to the last epoch, against the
    EKF's covariance after the same measurements (no process noise; RK4 at 60 s, the filter's STM by jacfwd
    of the RK4 step; the filter started off the truth by a draw of P0 and linearised about its own estimate):
    every sigma of the one along every direction within 10 % of the other (generalised eigenvalues)."""
    n_epochs, dt = 144, 600.0
    x_true0 = _geostationary(0.0) + jnp.array([0.0, 0.0, 0.0, 0.3, 0.2, 5.0])
    stations = jax.vmap(station_from_geodetic)(jnp.deg2rad(jnp.array([30.0, -30.0])),
                                               jnp.deg2rad(jnp.array([-7.5, 7.5])), jnp.zeros(2))
    sigma_m = 5.0
    r_cov = sigma_m**2 * jnp.eye(2)
    times = dt * jnp.arange(n_epochs)
    angles = OMEGA_EARTH_RAD_S * times

    def ranges(x, angle):
        return jax.vmap(lambda st: MODELS["range"].h(x, st, angle)[0])(stations)

    def range_jacobian(x, angle):
        return jax.vmap(lambda st: jacobian(MODELS["range"].h, x, st, angle)[0])(stations)

    truth = jax.vmap(lambda t: _kepler(x_true0, t))(times)
    z = jax.vmap(ranges)(truth, angles) + sigma_m * jax.random.normal(jax.random.PRNGKey(7), (n_epochs, 2))
    p0 = jnp.diag(jnp.array([1e4, 1e4, 1e4, 1.0, 1.0, 1.0]) ** 2)

    stms = jax.vmap(lambda t: jax.jacfwd(_kepler)(x_true0, t))(times)
    hs = jax.vmap(range_jacobian)(truth, angles)
    info = jnp.linalg.inv(p0) + jnp.einsum("kmi,kmj->ij", jnp.einsum("kmi,kij->kmj", hs, stms),
                                           jnp.einsum("kmi,kij->kmj", hs, stms)) / sigma_m**2
    p_batch = stms[-1] @ jnp.linalg.solve(info, stms[-1].T)

    @jax.jit
    def run_filter(x0):
        def update(x, p, k):
            innovation = z[k] - ranges(x, angles[k])
            x, p, _ = ekf.measurement_update(x, p, innovation, range_jacobian(x, angles[k]), r_cov)
            return x, p

        def body(carry, k):
            x, p = carry
            step = lambda y: _rk4_two_body(y, dt, 10)  # noqa: E731
            stm = jax.jacfwd(step)(x)  # the time update: P = Phi P Phi^T, Phi = d step / d x
            x, p = step(x), stm @ p @ stm.T
            return update(x, p, k), None

        return jax.lax.scan(body, update(x0, p0, 0), jnp.arange(1, n_epochs))[0]

    start = x_true0 + jnp.linalg.cholesky(p0) @ jax.random.normal(jax.random.PRNGKey(8), (6,))
    x_ekf, p_ekf = run_filter(start)
    # sigma ratios along every direction: generalised eigenvalues of (P_batch, P_ekf)
    ratio = np.sqrt(np.linalg.eigvals(np.linalg.solve(np.asarray(p_ekf), np.asarray(p_batch))).real)
    assert np.all(np.abs(ratio - 1.0) < 0.10), ratio
    # The filter converged on the truth it was given (its model agrees with the Kepler truth): NEES of a 6-dof
    # error inside chi^2(6)'s 99.9 % quantile, 22.5.
    assert float(ekf.nees(x_ekf - truth[-1], p_ekf)) < 22.5
    # and the bound is informative: the last position sigma is far below the prior's 10 km
    assert np.sqrt(np.max(np.diag(p_batch)[:3])) < 1e3


def test_the_schedule_passes():
    """Closed form: passes of 2 h every 12 h from 1 h on cover 1/6 of the time; an outage removes its window."""
    plan = schedule(12 * 3600.0, 2 * 3600.0, 3600.0, [(13 * 3600.0, 14 * 3600.0)])
    hours = np.array([0.5, 1.0, 2.9, 3.0, 12.5, 13.2, 14.5, 25.5, -10.5])
    assert np.asarray(tracking_weight(hours * 3600.0, plan)).tolist() == [0, 1, 1, 0, 0, 0, 1, 1, 1]
    dense = jnp.linspace(0.0, 10 * 86400.0, 864001)[:-1]
    no_outage = schedule(12 * 3600.0, 2 * 3600.0, 3600.0)
    assert float(jnp.mean(tracking_weight(dense, no_outage))) == pytest.approx(1 / 6, abs=1e-5)
    assert float(jnp.mean(tracking_weight(dense, plan))) == pytest.approx(1 / 6 - 1 / 240, abs=1e-5)
    assert np.asarray(tracking_weight(hours * 3600.0, continuous())).tolist() == [1] * len(hours)
    # jit and vmap over stations' schedules
    padded = schedule(12 * 3600.0, 2 * 3600.0, 3600.0, [(0.0, 0.0)])  # an empty window pads to a common count
    both = jax.tree_util.tree_map(lambda a, b: jnp.stack([a, b]), padded, continuous([(0.0, 0.0)]))
    got = jax.jit(jax.vmap(tracking_weight, in_axes=(None, 0)))(3.5 * 3600.0, both)
    assert np.asarray(got).tolist() == [0, 1]


GOOD = {"model": "ekf", "stations": [{"lat_deg": 30.0, "lon_deg": 10.0, "measurements": ["range", "angles"],
                                      "pass_s": 7200.0, "cadence_s": 43200.0}],
        "gnss": {"sigma_m": 20.0}}


@pytest.mark.parametrize("path, value, message", [
    (("stations", 0, "lat_deg"), -95.0, "navigation.stations[0].lat_deg: must be >= -90 and < 90, got -95.0"),
    (("stations", 0, "range_sigma_m"), -1.0, "navigation.stations[0].range_sigma_m: must be >= 0"),
    (("gnss", "sigma_m"), -3.0, "navigation.gnss.sigma_m: must be >= 0"),
    (("stations", 0, "pass_s"), 50000.0, "navigation.stations[0].pass_s: must be <= cadence_s (43200), got 50000.0"),
    (("stations", 0, "mask_deg"), 95.0, "navigation.stations[0].mask_deg: must be >= -90 and < 90, got 95.0"),
    (("stations", 0, "measurements"), ["range", "lidar"],
     "navigation.stations[0].measurements[1]: must be one of 'range', 'range_rate', 'angles', got 'lidar'"),
    (("stations", 0, "outages_s"), [[5.0, 1.0]], "navigation.stations[0].outages_s[0]: must be [start_s, stop_s]"),
    (("stations", 0, "elevation"), 1.0, "navigation.stations[0].elevation: unknown key"),
    (("model",), "ukf", "navigation.model: must be one of 'gaussian_fix', 'ekf', got 'ukf'"),
])
def test_bad_input_is_refused_naming_the_key(path, value, message):
    """The validation's contract: one ValueError whose message starts with the key."""
    import copy

    table = copy.deepcopy(GOOD)
    target = table
    for step in path[:-1]:
        target = target[step]
    target[path[-1]] = value
    with pytest.raises(ValueError) as caught:
        keys.validate(table)
    assert str(caught.value).startswith(message)


def test_a_good_table_is_completed_with_defaults():
    out = keys.validate(GOOD)
    assert out["stations"][0]["mask_deg"] == 5.0 and out["stations"][0]["range_sigma_m"] == 5.0
    assert out["gnss"]["cadence_s"] == 86400.0 and out["snc_mps2_per_rthz"] == 0.0
    with pytest.raises(ValueError, match=r"^navigation.stations\[0\].lat_deg: missing"):
        keys.validate({"stations": [{"lon_deg": 0.0}]})
    with pytest.raises(ValueError, match=r"^navigation.stations: the filter needs"):
        keys.validate({"model": "ekf"})
