"""Time scales and GMST against published values."""

import datetime as dt

import numpy as np
import pytest

from geojax.physics.time import gmst_rad, julian_date, tt_seconds_from_utc


def test_julian_date_meeus_example_7a():
    # Meeus, Astronomical Algorithms, Example 7.a: 1957 October 4.81 = JD 2436116.31.
    assert julian_date(1957, 10, 4, 0.81) == pytest.approx(2436116.31, abs=1e-9)


def test_j2000_epoch_is_zero_tt_seconds():
    # J2000.0 = 2000-01-01 12:00:00 TT = 11:58:55.816 UTC (TT - UTC = 64.184 s in 2000).
    t = tt_seconds_from_utc(dt.datetime(2000, 1, 1, 11, 58, 55, 816000))
    assert t == pytest.approx(0.0, abs=1e-6)


def test_leap_seconds_2017():
    # TT - UTC = 69.184 s after the 2017-01-01 leap second (IERS Bulletin C 52).
    t = tt_seconds_from_utc(dt.datetime(2020, 1, 1, 12, 0, 0))
    assert t == pytest.approx(7305 * 86400.0 + 69.184, abs=1e-6)


@pytest.mark.parametrize(
    "ut_hours, expected_deg",
    [
        # Meeus Example 12.a: 1987 April 10, 0h UT -> 13h10m46.3668s.
        (0.0, (13 + 10 / 60 + 46.3668 / 3600) * 15),
        # Meeus Example 12.b: 1987 April 10, 19h21m00s UT -> 128.7378734 deg.
        (19 + 21 / 60, 128.7378734),
    ],
)
def test_gmst_meeus_examples(ut_hours, expected_deg):
    jd_ut1 = julian_date(1987, 4, 10, ut_hours / 24)
    tt_minus_ut1 = 55.0  # any value: GMST sees only UT1 = TT - (TT - UT1)
    t_tt_s = (jd_ut1 - 2451545.0) * 86400.0 + tt_minus_ut1
    got = np.degrees(float(gmst_rad(t_tt_s, tt_minus_ut1)))
    assert got == pytest.approx(expected_deg, abs=2e-6)
