"""How the attitude error enters a planned pair of burns (Li 2022 eqs. (47)-(48); ``physics.execution``).

Independent checks: eq. (48)'s 3 sigma = 0.05 deg x H_att against sample statistics of many cycles' draws, a
burn pair whose directions are exactly the planned ones (the re-fit must give back the planned magnitudes),
and the least-squares property of the re-fit (no other magnitudes reproduce the planned effect better).
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.control import burns
from geojax.physics.execution import attitude_error_rad
from geojax.control.effects import cycle_coast_s, effect_matrix
from geojax.control.qffc import BurnPair

ERRORS = {"sigma3_att_deg": 15.0, "att_axes": [1.0, 1.0], "att_shared": 0.0, "att_known": 0.0}  # H_att = 300


def _draws(errors, n=4000):
    errors = {k: jnp.asarray(v) for k, v in errors.items()}
    keys = jax.random.split(jax.random.PRNGKey(0), n)
    return np.degrees(np.asarray(jax.vmap(lambda k: attitude_error_rad(errors, k))(keys)))  # [n, 2, 2]


def test_attitude_error_has_eq_48s_sigma_and_its_switches():
    """Eq. (48): 3 sigma = 0.05 deg x H_att, so 5 deg at H_att = 300, in yaw and pitch and for each burn
    (sample std of 4000 cycles within 4 %, the burns uncorrelated); ``att_axes = "yaw"`` leaves the yaw only;
    att_shared gives both burns one draw."""
    draws = _draws(ERRORS)
    np.testing.assert_allclose(draws.std(axis=0), 5.0, rtol=0.04)
    assert abs(np.corrcoef(draws[:, 0, 0], draws[:, 0, 1])[0, 1]) < 0.06
    yaw_only = _draws({**ERRORS, "att_axes": [1.0, 0.0]})
    assert np.all(yaw_only[:, 1] == 0.0) and yaw_only[:, 0].std() == pytest.approx(5.0, rel=0.04)
    shared = _draws({**ERRORS, "att_shared": 1.0})
    np.testing.assert_array_equal(shared[:, :, 0], shared[:, :, 1])
    np.testing.assert_array_equal(shared[:, :, 0], draws[:, :, 0])  # burn 1's draw, the same key


def _pair(dv_rsw):
    dv = jnp.asarray(dv_rsw)
    v = jnp.linalg.norm(dv, axis=1)
    return BurnPair(dv, v, jnp.zeros(2), jnp.zeros(2), jnp.asarray([0.4, 0.4 + math.pi]), jnp.asarray(0.0),
                    jnp.asarray(True))


def test_refit_gives_back_the_plan_and_is_the_least_squares_fit():
    """Directions exactly the planned ones: the re-fit returns the planned magnitudes.  Perturbed directions
    (5 deg): the re-fit's effect misses the planned effect (eq. (29), velocity metric) by less than the planned
    magnitudes' or any nearby pair's (a grid of +-20 %)."""
    pair = _pair([[-0.02, -0.01, -0.07], [-0.015, 0.012, 0.065]])
    units = pair.dv_rsw_mps / pair.v_mps[:, None]
    np.testing.assert_allclose(burns.refit_magnitudes_mps(pair, units, 0.0), pair.v_mps, rtol=1e-10)

    rng = np.random.default_rng(3)
    tilted = units + math.radians(5.0) * rng.normal(size=(2, 3))
    tilted /= np.linalg.norm(tilted, axis=1, keepdims=True)
    b = np.asarray(effect_matrix(pair.l_rad, cycle_coast_s(pair.l_rad, 0.0)))
    w = np.asarray(burns.EFFECT_ROW_MPS)
    target = w * np.einsum("kij,kj->i", b, np.asarray(pair.dv_rsw_mps))

    def miss(v):
        return np.linalg.norm(w * np.einsum("kij,kj->i", b, v[:, None] * tilted) - target)

    refit = np.asarray(burns.refit_magnitudes_mps(pair, jnp.asarray(tilted), 0.0))
    for scale in np.linspace(0.8, 1.2, 9):
        for other in np.linspace(0.8, 1.2, 9):
            assert miss(refit) <= miss(refit * np.array([scale, other])) + 1e-15
    assert miss(refit) < miss(np.asarray(pair.v_mps))


@pytest.mark.parametrize("preset", ["normal", "weak"])
def test_the_qffc_cannot_brake_a_drift_the_error_left(preset):
    """The mechanism of our Fig. 15 failures (``studies/ablation/li_attitude_error.md``): a burn error of +0.02
    m/s along the track (prograde) leaves a westward drift, 3 x 0.02 / R_s, whose undoing needs a net retrograde
    V_DT (same inclination and e deviations as a quiet cycle).  It is not flown: braking burns' coast coupling
    (eq. (33)'s T_i v_ti term) would need V_RS > 0, which eq. (34)'s v_r <= 0 forbids, so eq. (35) raises V_DT
    until the burns accelerate, and the drift deviation is left whole (checked on the effect B v of eq. (29),
    ``qffc.effect``).  A retrograde error of the same size is undone in the cycle with no raise.  The error's
    sign decides, under the normal and the weak limits alike, so errors of both signs walk the drift one way."""
    from geojax.control import qffc
    from geojax.control.effects import R_SYNC_M
    from geojax.physics.propulsion import PRESETS_DEG, arm_limits_deg

    limits = arm_limits_deg(*PRESETS_DEG[preset])
    solve_and_effect = jax.jit(lambda dx: (lambda sol: (sol, qffc.effect(sol, 0.0)))(qffc.solve(dx, 0.0, limits)))
    for error_mps in (-0.02, 0.02):
        dx = jnp.array([0.0, 3 * error_mps / R_SYNC_M, 0.0, 0.0, 1.0e-5, 0.3e-5])  # drift deviation to undo
        sol, effect = solve_and_effect(dx)
        achieved = float(effect[1])
        assert bool(sol.feasible)
        if error_mps > 0:
            assert float(sol.vdt_raise_mps) >= error_mps
            assert achieved <= 0.0  # the drift is not undone at all
        else:
            assert float(sol.vdt_raise_mps) == 0.0
            assert achieved == pytest.approx(float(dx[1]), rel=1e-9)
