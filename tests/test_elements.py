"""Element conversions: round trips, and GEO-element definitions."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics.constants import MU_EARTH_M3_S2 as MU
from geojax.physics.elements import (
    cartesian_to_kepler,
    cartesian_to_mee,
    cycle_mean,
    kepler_to_cartesian,
    kepler_to_mee,
    mee_to_cartesian,
    mee_to_kepler,
)

rng = np.random.default_rng(7)
N = 200
KEPLER = (
    rng.uniform(7e6, 5e7, N),  # a
    rng.uniform(1e-3, 0.8, N),  # e
    rng.uniform(0.01, 3.0, N),  # i (prograde, not equatorial, for Kepler angles)
    rng.uniform(0, 2 * np.pi, N),
    rng.uniform(0, 2 * np.pi, N),
    rng.uniform(0, 2 * np.pi, N),
)


def rel(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b)) / np.maximum(np.abs(np.asarray(b)), 1.0))


def test_kepler_cartesian_round_trip():
    r, v = kepler_to_cartesian(*KEPLER, MU)
    back = cartesian_to_kepler(r, v, MU)
    assert rel(back[0], KEPLER[0]) < 1e-12
    for got, want in zip(back[1:], KEPLER[1:]):
        assert np.max(np.abs(np.sin(np.asarray(got) - want))) < 1e-12


def test_mee_cartesian_round_trip_including_geo():
    r, v = kepler_to_cartesian(*KEPLER, MU)
    mee = cartesian_to_mee(r, v, MU)
    r2, v2 = mee_to_cartesian(mee, MU)
    assert np.max(np.linalg.norm(r2 - r, axis=-1) / np.linalg.norm(r, axis=-1)) < 1e-12
    assert np.max(np.linalg.norm(v2 - v, axis=-1) / np.linalg.norm(v, axis=-1)) < 1e-12
    # Equatorial, circular GEO (where Keplerian angles are singular): MEE -> Cartesian -> MEE.
    geo = jnp.array([42164.17e3, 1e-5, -2e-5, 3e-6, -1e-6, 1.234])
    again = cartesian_to_mee(*mee_to_cartesian(geo, MU), MU)
    assert rel(again, geo) < 1e-12


def test_kepler_mee_round_trip():
    mee = kepler_to_mee(*KEPLER)
    back = mee_to_kepler(mee)
    assert rel(back[0], KEPLER[0]) < 1e-12
    for got, want in zip(back[1:], KEPLER[1:]):
        assert np.max(np.abs(np.sin(np.asarray(got) - want))) < 1e-12


def test_mee_definition_matches_eq5_through_cartesian():
    # Independent path: Kepler -> Cartesian -> MEE must equal eq. (5) applied directly.
    r, v = kepler_to_cartesian(*KEPLER, MU)
    via_cartesian = np.asarray(cartesian_to_mee(r, v, MU))
    direct = np.array(kepler_to_mee(*KEPLER))
    direct[:, 5] = np.angle(np.exp(1j * direct[:, 5]))
    assert rel(via_cartesian[:, :5], direct[:, :5]) < 1e-12
    assert np.max(np.abs(np.sin(via_cartesian[:, 5] - direct[:, 5]))) < 1e-12


def test_cycle_mean_is_the_time_average():
    # Closed form: the average of c + d t + A sin(w t + phi) over a whole period is c + d T / 2.
    n = 96
    t = np.linspace(0.0, 1.0, n + 1)
    signal = 3.0 + 0.5 * t + 0.2 * np.sin(2 * np.pi * t + 0.3) + 0.05 * np.cos(4 * np.pi * t)
    assert float(cycle_mean(jnp.asarray(signal))) == pytest.approx(3.25, abs=1e-14)


def test_conversions_are_differentiable():
    grad = jax.grad(lambda p: mee_to_cartesian(jnp.array([p, 1e-4, 0.0, 0.0, 5e-5, 0.3]), MU)[0][0])(42164e3)
    assert np.isfinite(float(grad))
