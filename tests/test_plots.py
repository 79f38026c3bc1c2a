"""Figures: the ground-track reconstruction against Kepler's equation; files are written."""

import jax.numpy as jnp
import numpy as np

from geojax.physics import constants as c
from geojax import plots
from geojax.control.effects import R_SYNC_M
from geojax.physics.elements import kepler_to_cartesian, kepler_to_mee


def test_libration_matches_keplers_equation_to_second_order():
    # Independent: a Keplerian orbit sampled in mean anomaly (Kepler's equation by Newton), its
    # right ascension minus mean longitude and its latitude, against the first-order MEE formula.
    e, i, raan, argp = 2e-4, np.radians(0.05), 1.1, 2.3
    mean_anomaly = np.linspace(0, 2 * np.pi, 97)
    ecc_anomaly = mean_anomaly.copy()
    for _ in range(20):
        ecc_anomaly -= (ecc_anomaly - e * np.sin(ecc_anomaly) - mean_anomaly) / (1 - e * np.cos(ecc_anomaly))
    nu = 2 * np.arctan2(np.sqrt(1 + e) * np.sin(ecc_anomaly / 2), np.sqrt(1 - e) * np.cos(ecc_anomaly / 2))
    r, _ = kepler_to_cartesian(R_SYNC_M, e, i, raan, argp, jnp.asarray(nu), c.MU_EARTH_M3_S2)
    r = np.asarray(r)
    ra = np.arctan2(r[..., 1], r[..., 0])
    lat = np.arcsin(r[..., 2] / np.linalg.norm(r, axis=-1))
    d_lon = np.angle(np.exp(1j * (ra - (raan + argp + mean_anomaly))))
    mee = np.asarray(kepler_to_mee(R_SYNC_M, e, i, raan, argp, 0.0))
    model_lon, model_lat = plots.libration_rad(raan + argp + nu, *mee[1:5])
    # Residuals are O(e^2, i^2) ~ 1e-7 rad against amplitudes 2e = i = 4e-4 and 8.7e-4 rad.
    assert np.max(np.abs(d_lon - model_lon)) < 3e-7
    assert np.max(np.abs(lat - model_lat)) < 3e-7
    assert np.max(np.abs(model_lat)) > 8e-4
