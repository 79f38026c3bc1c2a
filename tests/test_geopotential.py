"""The field to degree N (``physics.geopotential``) against an independent evaluation, its derivatives and
the degree-2 terms.

The reference (``studies/force_model/reference.py``) is written from a different method: the gradient of the
potential in spherical coordinates with the normalised Legendre functions by the forward-column recursion
(Holmes & Featherstone 2002) and their latitude derivatives, in plain Python.
"""

import importlib.util
import math
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics import constants as c
from geojax.physics.forces import c22_s22_acceleration, j2_acceleration
from geojax.physics.geopotential import MAX_DEGREE, Geopotential, egm2008, geopotential_acceleration

_spec = importlib.util.spec_from_file_location(
    "force_model_reference", Path(__file__).resolve().parents[1] / "studies" / "force_model" / "reference.py")
reference = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(reference)


def reference_acceleration_ecef(r, degree, order, c_nm, s_nm):
    return reference.field_acceleration_ecef(r, degree, order, c_nm, s_nm, c.MU_EARTH_M3_S2, c.R_EARTH_M)


def random_points(count, seed=33):
    """Positions (m) with directions uniform on the sphere and radii uniform in 6,600-50,000 km."""
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=(count, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    return direction * rng.uniform(6.6e6, 5.0e7, size=(count, 1))


def test_shipped_coefficients_are_egm2008():
    # Published EGM2008 values (Pavlis et al. 2012; NGA file EGM2008_to2190_TideFree), typed from the file.
    field = egm2008(20)
    assert field.c_nm[2, 0] == -4.84165143790815e-04 and field.c_nm[3, 0] == 9.57161207093473e-07
    assert (field.c_nm[2, 2], field.s_nm[2, 2]) == (2.43938357328313e-06, -1.40027370385934e-06)
    assert (field.c_nm[20, 20], field.s_nm[20, 20]) == (3.73507214738094e-09, -1.26949126479726e-08)
    # The un-normalised J2 of ``constants`` is -sqrt(5) C_20 of the same model.
    assert math.isclose(-math.sqrt(5) * field.c_nm[2, 0], c.J2, rel_tol=1e-13)
    assert field.c_nm.shape == (21, 21) and egm2008(8, 4).c_nm.shape == (9, 5)


def compare_with_reference(field, points, angle=2.1):
    """Largest relative error of the degree-2..N acceleration at ECI ``points`` (Earth angle ``angle``, so the
    frame rotation is exercised too) against the spherical-gradient reference."""
    ca, sa = math.cos(angle), math.sin(angle)
    got = np.asarray(jax.jit(geopotential_acceleration)(jnp.asarray(points), angle, c.MU_EARTH_M3_S2, c.R_EARTH_M,
                                                        jax.tree_util.tree_map(jnp.asarray, field)))
    c_nm, s_nm = np.asarray(field.c_nm), np.asarray(field.s_nm)
    worst = 0.0
    for r_eci, a_eci in zip(points, got):
        r_ecef = np.array([ca * r_eci[0] + sa * r_eci[1], -sa * r_eci[0] + ca * r_eci[1], r_eci[2]])
        a_ecef = reference_acceleration_ecef(r_ecef, field.degree, field.order, c_nm, s_nm)
        want = np.array([ca * a_ecef[0] - sa * a_ecef[1], sa * a_ecef[0] + ca * a_ecef[1], a_ecef[2]])
        worst = max(worst, np.linalg.norm(a_eci - want) / np.linalg.norm(want))
    return worst


@pytest.mark.parametrize("degree, order", [(2, 0), (2, 2), (3, 1), (5, 5), (8, 8), (8, 3), (9, 8), (12, 12), (13, 6), (20, 20)])
def test_field_matches_spherical_gradient(degree, order):
    # 300 points, 6,600-50,000 km: the relative error of the degree-2..N acceleration is below 1e-12, for
    # fields of order at and below the degree.
    assert compare_with_reference(egm2008(degree, order), random_points(300, seed=degree + 100 * order)) <= 1e-12


def test_every_degree_to_twenty():
    # Degrees 2..20 through two compiled shapes: the coefficients above degree N set to zero.
    for shape in (8, 20):
        full = egm2008(shape)
        for degree in range(2, shape + 1):
            keep = (np.arange(shape + 1) <= degree)[:, None]
            field = Geopotential(full.c_nm * keep, full.s_nm * keep)
            assert compare_with_reference(field, random_points(40, seed=degree)) <= 1e-12, (shape, degree)


def test_degree_two_equals_j2_and_c22_s22():
    # With the same coefficients (C_20 = -J2 / sqrt(5), and C_22, S_22 = the constants' un-normalised
    # C22 = 1.5744604e-6, S22 = -9.0380380e-7 divided by N_22 = sqrt(5/12)), degree 2 is the sum of the
    # closed-form J2 and C22/S22 terms.
    n22 = math.sqrt(5 / 12)
    c_nm = np.zeros((3, 3))
    s_nm = np.zeros((3, 3))
    c_nm[2, 0], c_nm[2, 2], s_nm[2, 2] = -c.J2 / math.sqrt(5), c.C22 / n22, c.S22 / n22
    field = Geopotential(jnp.asarray(c_nm), jnp.asarray(s_nm))
    points = jnp.asarray(random_points(50))
    angle = 0.7
    got = geopotential_acceleration(points, angle, c.MU_EARTH_M3_S2, c.R_EARTH_M, field)
    want = (j2_acceleration(points, c.MU_EARTH_M3_S2, c.J2, c.R_EARTH_M)
            + c22_s22_acceleration(points, angle, c.MU_EARTH_M3_S2, c.C22, c.S22, c.R_EARTH_M))
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-13, atol=1e-13 * float(jnp.max(jnp.abs(want))))


@pytest.mark.parametrize("degree", [4, 8])
def test_jacobian_matches_finite_differences(degree):
    # d a / d r by jax.jacfwd against central differences (step 10 m).
    field = jax.tree_util.tree_map(jnp.asarray, egm2008(degree))
    accel = jax.jit(lambda r: geopotential_acceleration(r, 0.3, c.MU_EARTH_M3_S2, c.R_EARTH_M, field))
    jacobian = jax.jit(jax.jacfwd(accel))
    for r in random_points(5, seed=7):
        r = jnp.asarray(r)
        jac = np.asarray(jacobian(r))
        h = 10.0
        fd = np.stack([(np.asarray(accel(r + h * e)) - np.asarray(accel(r - h * e))) / (2 * h) for e in np.eye(3)], -1)
        np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-7 * np.abs(jac).max())
        # The field is a gradient: its Jacobian is symmetric; of a harmonic potential (Laplace's equation
        # outside the Earth): its trace is zero.
        np.testing.assert_allclose(jac, jac.T, atol=1e-12 * np.abs(jac).max())
        assert abs(np.trace(jac)) <= 1e-12 * np.abs(jac).max()


def test_gradient_reaches_coefficients():
    # The acceleration is linear in the coefficients: d a / d C_nm times C_nm, summed, is a itself.
    field = jax.tree_util.tree_map(jnp.asarray, egm2008(3))
    r = jnp.asarray(random_points(1, seed=3)[0])
    accel = lambda f: geopotential_acceleration(r, 0.0, c.MU_EARTH_M3_S2, c.R_EARTH_M, f)  # noqa: E731
    jac = jax.jit(jax.jacrev(accel))(field)
    linear = sum(jnp.einsum("inm,nm->i", j, f) for j, f in zip(jac, field))
    np.testing.assert_allclose(np.asarray(linear), np.asarray(accel(field)), rtol=1e-12)


def test_bad_degree_is_refused():
    with pytest.raises(ValueError, match="degree"):
        egm2008(MAX_DEGREE + 1)
    with pytest.raises(ValueError, match="order"):
        egm2008(4, 5)


def test_two_days_match_dop853():
    # geojax's uncontrolled MEE RK4 at EGM2008 4x4 against the independent Cartesian DOP853 integration
    # (studies/force_model/propagation_check.py: 200 days at 8x8 there), 2 days at 0 deg E from 2027-01-01.
    spec = importlib.util.spec_from_file_location(
        "propagation_check", Path(__file__).resolve().parents[1] / "studies" / "force_model" / "propagation_check.py")
    check = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(check)
    result = check.compare(0.0, 2027, 2.0, degree=4)
    assert result["max_mean_lon_difference_deg"] < 1e-6  # 2 days at 8x8: 1.0e-9
    assert result["inclination_change_relative_difference"] < 1e-6  # 6.5e-11
    assert result["eccentricity_excursion_relative_difference"] < 1e-5  # 3.8e-9


@pytest.mark.parametrize("degree", [4, 8])
def test_drift_atlas_equilibria_are_the_published_ones(degree):
    # Published equilibrium longitudes of the geostationary ring: stable 75.1 E and 105.3 W, unstable 11.5 W
    # and 161.9 E; from degree 3-4 on the field gives them within 0.5 deg (degree 2 puts the unstable ones
    # at -14.9 and 165.1).  studies/force_model/drift_atlas.py draws the whole atlas.
    spec = importlib.util.spec_from_file_location(
        "drift_atlas", Path(__file__).resolve().parents[1] / "studies" / "force_model" / "drift_atlas.py")
    atlas = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(atlas)
    stable, unstable, _ = atlas.equilibria(degree, samples=720)
    np.testing.assert_allclose(stable, [-105.3, 75.1], atol=0.5)
    np.testing.assert_allclose(unstable, [-11.5, 161.9], atol=0.5)


def test_degree_two_east_west_budget_errors_are_the_published_ones():
    # Published: a degree-2 field is off by about 19 % of the yearly east-west Delta-V at 96 deg E and by
    # 24-31 % at 0 deg and 75 deg W (docs/studies.md, the force model's rows).  The budget here: |a_east| of the field alone over a
    # year (studies/force_model/drift_atlas.py), degree 2 against 20.
    spec = importlib.util.spec_from_file_location(
        "drift_atlas", Path(__file__).resolve().parents[1] / "studies" / "force_model" / "drift_atlas.py")
    atlas = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(atlas)
    error = {lon: abs(atlas.east_west_dv_per_year_mps(lon, 2) / atlas.east_west_dv_per_year_mps(lon, 20) - 1)
             for lon in (96.0, 0.0, -75.0)}
    assert abs(error[96.0] - 0.19) <= 0.01
    assert 0.24 - 0.01 <= error[0.0] <= 0.31 + 0.01 and 0.24 - 0.01 <= error[-75.0] <= 0.31 + 0.01


def test_equations_of_motion_differentiate_through_the_field():
    # The MEE right-hand side with EGM2008 2x2 behind the step's fusion boundaries: forward and reverse
    # derivatives agree with each other and with central differences.
    from geojax import scenario
    from geojax.physics.dynamics import SpacecraftState, mee_rhs, no_thrust
    from geojax.physics.propagate import environment_at

    sc = scenario.load("geo", {"forces.gravity_degree": 2})
    env = environment_at(sc.epoch_tt_s + 1000.0, sc.epoch_tt_s, sc.tt_minus_ut1_s)
    fm = jax.tree_util.tree_map(jnp.asarray, sc.force_model)

    def rates(mee):
        state = SpacecraftState(mee, jnp.asarray(sc.mass_kg), jnp.asarray(0.0))
        return mee_rhs(state, env, fm, no_thrust(), boundaries=True).orbit[:5]

    mee = jnp.asarray(sc.initial_mee)
    forward, reverse = jax.jit(jax.jacfwd(rates))(mee), jax.jit(jax.jacrev(rates))(mee)
    np.testing.assert_allclose(np.asarray(forward), np.asarray(reverse), rtol=1e-10, atol=1e-20)
    step = np.array([10.0, 1e-7, 1e-7, 1e-7, 1e-7, 1e-6])
    fd = np.stack([(np.asarray(rates(mee + h * e)) - np.asarray(rates(mee - h * e))) / (2 * h)
                   for h, e in zip(step, np.eye(6))], -1)
    for got, want in zip(np.asarray(forward), fd):  # per rate: their scales differ
        np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-6 * np.abs(want).max())
