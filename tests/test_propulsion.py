"""Robotic-arm limits (Li 2022, eq. (1), Table 1), Delta-V directions (eq. (14)), the sunlit clock."""

import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics.propulsion import (
    PRESETS_DEG,
    arm_limits_deg,
    delta_v_direction_rsw,
    firing_fraction,
    sunlit_clock,
    within_limits,
)


def test_delta_v_points_inward_and_north_south_by_thruster():
    # Eq. (14) with eq. (1): thruster 1 (beta >= 0) pushes south, thruster 2 north, both inward (eq. (34)).
    dv1 = np.asarray(delta_v_direction_rsw(jnp.radians(20.0), jnp.radians(60.0)))
    dv2 = np.asarray(delta_v_direction_rsw(jnp.radians(-20.0), jnp.radians(-60.0)))
    assert dv1[0] < 0 and dv2[0] < 0
    assert dv1[2] < 0 < dv2[2]
    assert np.linalg.norm(dv1) == pytest.approx(1.0, abs=1e-15)


def test_normal_preset_limits():
    limits = arm_limits_deg(*PRESETS_DEG["normal"])  # beta 0..70, alpha -30..60 (thruster 1)
    alpha = jnp.radians(jnp.array([[59.0, -29.0], [61.0, 0.0], [-31.0, 0.0]]))
    beta = jnp.radians(jnp.array([[69.0, -69.0], [10.0, -10.0], [10.0, -10.0]]))
    ok = np.asarray(within_limits(alpha, beta, limits))
    np.testing.assert_array_equal(ok, [[True, True], [False, True], [False, True]])
    assert not bool(within_limits(jnp.radians(jnp.array([0.0, 0.0])), jnp.radians(jnp.array([71.0, -71.0])), limits).any())


@pytest.mark.parametrize(
    "args, message",
    [
        ((40.0, 50.0, 60.0, 30.0), "thrusters.beta_min_deg: must be <= thrusters.beta_max_deg (40.0), got 50.0"),
        ((95.0, 0.0, 60.0, 30.0), "thrusters.beta_max_deg: must be >= 0 and <= 90, got 95.0"),
        ((70.0, 0.0, -1.0, 30.0), "thrusters.alpha_max_deg: must be >= 0 and <= 90, got -1.0"),
        ((0.0, 0.0, 60.0, 30.0), "thrusters.beta_max_deg: must be > 0"),
        ((90.0, 90.0, 0.0, 0.0), "thrusters.beta_min_deg: 90 leaves no in-plane thrust"),
    ],
)
def test_impossible_limits_are_refused(args, message):
    with pytest.raises(ValueError) as err:
        arm_limits_deg(*args)
    assert message in str(err.value)


def test_burn_suspended_in_shadow_fires_its_full_duration():
    # 10 steps of 100 s, shadow over steps 3-5: a 450 s burn from t = 200 s
    # fires 100 s before the shadow and 350 s after it, ending at t = 950 s.
    step = 100.0
    sunlit = jnp.array([1, 1, 1, 0, 0, 0, 1, 1, 1, 1], dtype=float)
    clock = sunlit_clock(sunlit, step)
    fractions = firing_fraction(clock[:-1], clock[1:], clock[2], 450.0, step)
    np.testing.assert_allclose(np.asarray(fractions), [0, 0, 1, 0, 0, 0, 1, 1, 1, 0.5], atol=1e-15)
    assert float(jnp.sum(fractions) * step) == pytest.approx(450.0)
