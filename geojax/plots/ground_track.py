"""The sub-satellite point's daily libration, rebuilt from the mean elements stored once per cycle."""

from __future__ import annotations

import numpy as np


def ground_track_deg(lon_deg, ex, ey, ix, iy, samples_per_cycle: int = 48):
    """Longitude and latitude (deg) over each cycle, rebuilt from its mean elements [n].

    First order in e and i: the true minus the mean longitude is 2 (f sin L - g cos L)
    and the latitude i sin(L - Omega) = 2 (h sin L - k cos L) for MEE (f, g, h, k),
    with L the true longitude running once round per cycle.  This is the daily
    libration of Li 2022 Fig. 4 drawn from the stored cycle means.
    """
    turn = np.linspace(0.0, 2 * np.pi, samples_per_cycle, endpoint=False)[None, :]
    lon = np.degrees(np.unwrap(np.radians(np.asarray(lon_deg))))[:, None]
    d_lon, lat = libration_rad(turn, *(np.asarray(x)[:, None] for x in (ex, ey, ix, iy)))
    return (lon + np.degrees(d_lon)).ravel(), np.degrees(lat).ravel()


def libration_rad(true_lon_rad, f, g, h, k):
    """(true minus mean longitude, latitude) at true longitude L, first order in MEE (f, g, h, k)."""
    s, c = np.sin(true_lon_rad), np.cos(true_lon_rad)
    return 2 * (f * s - g * c), 2 * (h * s - k * c)
