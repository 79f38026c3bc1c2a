"""Sun and Moon: Meeus worked examples, and ERFA over 2000-2050."""

import erfa
import numpy as np
import pytest

from geojax.physics.ephemeris import moon_ecliptic_of_date, moon_position_eci_m, sun_ecliptic_of_date, sun_position_eci_m
from geojax.physics.time import julian_centuries_tt

AU_M = 1.495978707e11


def centuries(jd_tt):
    return julian_centuries_tt((jd_tt - 2451545.0) * 86400.0)


def test_sun_meeus_example_25a():
    # Meeus Example 25.a, 1992 October 13.0 TD: true longitude 199.90988 deg, R = 0.99766 AU.
    longitude, distance = sun_ecliptic_of_date(centuries(2448908.5))
    assert np.degrees(float(longitude)) % 360 == pytest.approx(199.90988, abs=2e-5)
    assert float(distance) / AU_M == pytest.approx(0.99766, abs=1e-5)


def test_moon_meeus_example_47a():
    # Meeus Example 47.a, 1992 April 12.0 TD: lambda 133.162655, beta -3.229126 deg, 368409.7 km.
    longitude, latitude, distance = moon_ecliptic_of_date(centuries(2448724.5))
    assert np.degrees(float(longitude)) % 360 == pytest.approx(133.162655, abs=2e-6)
    assert np.degrees(float(latitude)) == pytest.approx(-3.229126, abs=2e-6)
    assert float(distance) / 1e3 == pytest.approx(368409.7, abs=0.1)


def _to_icrs(vectors_eci, jd_tt, frame_jd_tt):
    """geojax ECI (mean equator and equinox of the frame epoch) to ICRS via the IAU 2006 precession matrix."""
    precession = erfa.pmat06(frame_jd_tt, 0.0)  # ICRS -> mean of frame epoch
    return vectors_eci @ precession  # row vectors: v_icrs = P^T v


def _angle_deg(a, b):
    cos = np.sum(a * b, -1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


JD_GRID = np.linspace(2451545.0, 2451545.0 + 50 * 365.25, 241)


def test_sun_direction_against_erfa_epv00_2000_2050():
    # eraEpv00 (VSOP2000-based, ~km accuracy) is an independent solar theory.
    # Each date is its own frame epoch, as in a scenario starting that day.
    t_tt_s = (JD_GRID - 2451545.0) * 86400.0
    ours = np.stack([np.asarray(sun_position_eci_m(t, t)) for t in t_tt_s])
    ours_icrs = np.stack([_to_icrs(v, jd, jd) for v, jd in zip(ours, JD_GRID)])
    ref = np.stack([-erfa.epv00(jd, 0.0)[0][0] * AU_M for jd in JD_GRID])
    assert _angle_deg(ours_icrs, ref).max() < 0.01
    assert np.max(np.abs(np.linalg.norm(ours, axis=-1) / np.linalg.norm(ref, axis=-1) - 1)) < 2e-4


def test_moon_against_erfa_moon98_2000_2050():
    # eraMoon98 is SOFA's own implementation of Meeus's ELP-2000/82 selection:
    # it checks our tables and rotations (same theory, independent code).
    t_tt_s = (JD_GRID - 2451545.0) * 86400.0
    ours = np.stack([np.asarray(moon_position_eci_m(t, t)) for t in t_tt_s])
    ours_icrs = np.stack([_to_icrs(v, jd, jd) for v, jd in zip(ours, JD_GRID)])
    ref = np.stack([erfa.moon98(jd, 0.0)[0] * AU_M for jd in JD_GRID])
    assert _angle_deg(ours_icrs, ref).max() < 0.01
    assert np.max(np.abs(np.linalg.norm(ours, axis=-1) / np.linalg.norm(ref, axis=-1) - 1)) < 1e-3


def test_frozen_frame_within_one_year():
    # A year after the frame epoch, the Sun in the frozen frame differs from the
    # Sun in the frame of date by the precession of one year (about 50"), not more.
    t0 = 7305 * 86400.0
    t1 = t0 + 365.25 * 86400.0
    frozen = np.asarray(sun_position_eci_m(t1, t0))
    of_date = np.asarray(sun_position_eci_m(t1, t1))
    assert 40 / 3600 < _angle_deg(frozen, of_date) < 60 / 3600


def test_de421_against_erfa_epv00_and_meeus():
    # JPL DE421 through jplephem, turned into the frame of each date (IAU 1976 precession): the Sun within 0.2"
    # of eraEpv00 (independent theory, km-level; IAU 2006 precession and frame bias on its side) and the Moon
    # within the stated accuracy of the Meeus series (10") of eraMoon98.
    from geojax.physics.ephemeris import de421_sun_moon_eci_m

    jd = np.linspace(2451545.0, 2451545.0 + 50 * 365.25, 25)
    t_tt_s = (jd - 2451545.0) * 86400.0
    pairs = [de421_sun_moon_eci_m(t, t) for t in t_tt_s]
    sun = np.stack([_to_icrs(s, d, d) for (s, _), d in zip(pairs, jd)])
    moon = np.stack([_to_icrs(m, d, d) for (_, m), d in zip(pairs, jd)])
    ref_sun = np.stack([-erfa.epv00(d, 0.0)[0][0] * AU_M for d in jd])
    assert _angle_deg(sun, ref_sun).max() < 0.2 / 3600
    assert np.max(np.abs(np.linalg.norm(sun, axis=-1) / np.linalg.norm(ref_sun, axis=-1) - 1)) < 1e-6
    ref_moon = np.stack([erfa.moon98(d, 0.0)[0] * AU_M for d in jd])
    assert _angle_deg(moon, ref_moon).max() < 10 / 3600
