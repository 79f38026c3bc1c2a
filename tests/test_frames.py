"""Frames: Earth rotation rate, round trips, RSW orthonormality."""

import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics.constants import OMEGA_EARTH_RAD_S
from geojax.physics.frames import earth_rotation_angle_rad, ecef_to_eci, eci_to_ecef, eci_to_rsw, rsw_basis, rsw_to_eci


def test_earth_rotation_rate():
    # GMST advances at 7.2921158553e-5 rad/s against the precessing equinox; less the
    # 46"/yr (7.1e-12 rad/s) of equinox precession this is the inertial rate of the
    # frozen ECI frame, the IERS nominal omega = 7.292115e-5 rad/s.
    t0 = 7305 * 86400.0
    dt = 86400.0
    # One day is one full turn plus the fraction the angle gains.
    gained = (float(earth_rotation_angle_rad(t0 + dt, t0, 69.0)) - float(earth_rotation_angle_rad(t0, t0, 69.0))) % (2 * np.pi)
    rate = (2 * np.pi + gained) / dt
    assert rate == pytest.approx(OMEGA_EARTH_RAD_S, rel=2e-8)


def test_round_trips_and_rsw():
    rng = np.random.default_rng(1)
    r = jnp.asarray(rng.normal(size=(10, 3)) * 4e7)
    v = jnp.asarray(rng.normal(size=(10, 3)) * 3e3)
    np.testing.assert_allclose(ecef_to_eci(eci_to_ecef(r, 0.7), 0.7), r, rtol=1e-15, atol=1e-7)
    basis = rsw_basis(r, v)
    np.testing.assert_allclose(jnp.einsum("nij,nkj->nik", basis, basis), np.broadcast_to(np.eye(3), (10, 3, 3)), atol=1e-15)
    # R along r, W along r x v, right-handed.
    np.testing.assert_allclose(eci_to_rsw(r, r, v)[:, 1:], 0.0, atol=1e-7)
    np.testing.assert_allclose(np.linalg.det(basis), 1.0, atol=1e-14)
    a = jnp.asarray(rng.normal(size=(10, 3)))
    np.testing.assert_allclose(rsw_to_eci(eci_to_rsw(a, r, v), r, v), a, atol=1e-15)
