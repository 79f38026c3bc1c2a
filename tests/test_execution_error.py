"""Burn magnitude execution errors (``errors.sigma3_dv_pct``, ``control.burns.magnitude_scale``).

Checked against the documented draw, re-derived here from JAX's generator (not through geojax's function): each
cycle's delivered Delta-V (the integrated thrust, ``/cycles/dv_mps``) equals the burns' planned magnitudes
each times 1 + sigma3 / 3 x normal(fold_in(fold_in(key, cycle), 2))[burn], within the mass's change over a
cycle; and the key is refused by a law that flies no planned burns.  At 0 % every number is unchanged: the stored
reference numbers (``tests/test_reference_numbers.py``) are run with the key at its default.
"""

import jax
import numpy as np
import pytest

import geojax
from geojax import scenario
from geojax.physics.execution import MAGNITUDE_KEY

SIGMA3_PCT = 30.0  # large, so the check sees the error well above the mass's 1e-5 effect


def test_each_burn_flies_its_planned_magnitude_times_the_drawn_level():
    seed = 7
    sc = scenario.load("li2022-qffc", {"duration.days": 6, "errors.sigma3_dv_pct": SIGMA3_PCT})
    run = geojax.simulate(sc, seed=seed)
    cycles = run.cycles()
    key = jax.random.key(seed)
    levels = np.array([1 + SIGMA3_PCT / 100 / 3 * np.asarray(
        jax.random.normal(jax.random.fold_in(jax.random.fold_in(key, k), MAGNITUDE_KEY), (2,)))
        for k in range(len(cycles["dv_mps"]))])
    planned = np.stack([cycles["v1_mps"], cycles["v2_mps"]], axis=1)
    fired = planned > 0
    assert fired.sum() >= 8  # both burns fly in most cycles
    expected = np.sum(planned * levels, axis=1)
    np.testing.assert_allclose(cycles["dv_mps"], expected, rtol=2e-4)
    # and the planned alone would be off by far more: the error is in the flight
    assert np.max(np.abs(cycles["dv_mps"] / np.sum(planned, axis=1) - 1)) > 0.02


def test_a_law_without_planned_burns_refuses_the_key():
    with pytest.raises(ValueError, match="errors.sigma3_dv_pct"):
        scenario.load("katz2025-continuous", {"errors.sigma3_dv_pct": 5.0})


def test_the_truth_read_back_from_planned_and_flown_is_exact():
    """Closed form: ``truth_of`` inverts ``executed`` (a filter's model of a burn) for a burn flown with Li's
    errors (yaw and pitch added to the planned angles, the level scaled): executed(planned, truth_of(...)) is the
    flown direction and thrust to rounding, and nothing planned reads as no error."""
    import jax.numpy as jnp

    from geojax.physics.execution import executed, truth_of
    from geojax.physics.propulsion import delta_v_direction_rsw

    planned = delta_v_direction_rsw(jnp.asarray(0.7), jnp.asarray(-1.1))
    flown = delta_v_direction_rsw(jnp.asarray(0.7 + 0.004), jnp.asarray(-1.1 - 0.003))
    eps, phi = truth_of(planned, 0.5, flown, 0.5 * 1.03)
    direction, thrust_n = executed(planned, 0.5, eps, phi)
    np.testing.assert_allclose(np.asarray(direction), np.asarray(flown), atol=1e-15)
    assert float(thrust_n) == pytest.approx(0.515, rel=1e-15) and float(eps) == pytest.approx(0.03, rel=1e-12)
    assert abs(float(jnp.dot(phi, planned))) < 1e-15  # perpendicular to the line: no roll
    eps0, phi0 = truth_of(jnp.zeros(3), 0.0, jnp.zeros(3), 0.0)
    assert float(eps0) == 0.0 and np.all(np.asarray(phi0) == 0.0)


def test_one_key_set_states_the_execution_errors_under_either_navigation_model():
    """The truth's execution errors are the ``[errors]`` keys whether the Gaussian fix or the filter navigates;
    the filter's priors default to them and are keys of their own."""
    ekf = scenario.load("li2022-qffc-ranging", {"errors.sigma3_att_deg": 0.15, "errors.sigma3_dv_pct": 3.0})
    assert ekf.config["navigation"]["assumed_sigma3_att_deg"] == 0.15
    assert ekf.config["navigation"]["assumed_sigma3_dv_pct"] == 3.0
    own = scenario.load("li2022-qffc-ranging", {"navigation.assumed_sigma3_dv_pct": 9.0})
    assert own.config["navigation"]["assumed_sigma3_dv_pct"] == 9.0 and own.config["errors"]["sigma3_dv_pct"] == 6.0
    with pytest.raises(ValueError, match="errors.h_rv"):
        scenario.load("li2022-qffc-ranging", {"errors.h_rv": 1.0})


def test_the_filters_pointing_prior_is_the_truths_covariance():
    """Second method (Monte Carlo): a filter's prior of the pointing rotation phi (``execution_prior``) is the
    covariance of the rotations that the truth's model flies (yaw and pitch errors added to the planned angles,
    read back by ``truth_of``), 20 000 draws at beta = -60 deg (a turn of alpha moves the line by cos beta = 1/2 of
    it): the sample covariance within 3 % of the prior across the line (the roll about it moves nothing)."""
    import jax.numpy as jnp

    from geojax.navigation.execution import execution_prior
    from geojax.physics.execution import truth_of
    from geojax.physics.propulsion import delta_v_direction_rsw

    alpha, beta, sigma = 0.4, -np.pi / 3, 1e-3
    planned = delta_v_direction_rsw(jnp.asarray(alpha), jnp.asarray(beta))
    draws = sigma * jax.random.normal(jax.random.key(11), (20000, 2))
    flown = jax.vmap(lambda e: delta_v_direction_rsw(alpha + e[0], beta + e[1]))(draws)
    phi = np.asarray(jax.vmap(lambda f: truth_of(planned, 1.0, f, 1.0)[1])(flown))
    prior = np.asarray(execution_prior(0.02, sigma, planned))
    across = np.eye(3) - np.outer(planned, planned)  # the covariance seen across the line
    np.testing.assert_allclose(across @ np.cov(phi.T) @ across, across @ prior[1:, 1:] @ across, atol=0.03 * sigma**2)
    assert prior[0, 0] == pytest.approx(0.02**2)
    # and the yaw part is cos beta of the pitch part, not equal: an isotropic prior would overstate it 4 times
    eig = np.sort(np.linalg.eigvalsh(across @ prior[1:, 1:] @ across))
    assert eig[1] == pytest.approx(0.25 * sigma**2, rel=1e-9) and eig[2] == pytest.approx(sigma**2, rel=1e-9)
