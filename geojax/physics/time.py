"""Time scales and Earth rotation.

Time inside geojax is TT seconds since J2000.0 (JD 2451545.0 TT) as float64,
named ``t_tt_s``.  Calendar dates are UTC at the edges; UT1 enters only through
GMST, as the scenario constant ``ut1_minus_utc_s`` (|UT1 - UTC| < 0.9 s).

GMST is the IAU 1982 expression (Aoki et al. 1982) in the form of Meeus,
*Astronomical Algorithms*, 2nd ed., eq. (12.4).
"""

from __future__ import annotations

import datetime as _dt

import jax.numpy as jnp

from geojax.physics.constants import DAYS_PER_JULIAN_CENTURY, JD_J2000, SECONDS_PER_DAY

TT_MINUS_TAI_S = 32.184

# TAI - UTC (s) from the date it takes effect (IERS Bulletin C).  No leap
# second has been announced after 2017-01-01.
_LEAP_SECONDS = (
    (_dt.date(1999, 1, 1), 32.0),
    (_dt.date(2006, 1, 1), 33.0),
    (_dt.date(2009, 1, 1), 34.0),
    (_dt.date(2012, 7, 1), 35.0),
    (_dt.date(2015, 7, 1), 36.0),
    (_dt.date(2017, 1, 1), 37.0),
)


def tai_minus_utc_s(date: _dt.date) -> float:
    """TAI - UTC in seconds on a UTC date from 1999 on."""
    if date < _LEAP_SECONDS[0][0]:
        raise ValueError(f"epoch.utc: dates before {_LEAP_SECONDS[0][0]} are not supported")
    offset = _LEAP_SECONDS[0][1]
    for start, value in _LEAP_SECONDS:
        if date >= start:
            offset = value
    return offset


def julian_date(year: int, month: int, day: int, day_fraction: float = 0.0) -> float:
    """Julian date of a Gregorian calendar date (Meeus eq. (7.1))."""
    if month <= 2:
        year, month = year - 1, month + 12
    a = year // 100
    b = 2 - a + a // 4
    return int(365.25 * (year + 4716)) + int(30.6001 * (month + 1)) + day + b - 1524.5 + day_fraction


def tt_seconds_from_utc(utc: _dt.datetime) -> float:
    """TT seconds since J2000.0 of a UTC datetime (naive datetimes are UTC)."""
    if utc.tzinfo is not None:
        utc = utc.astimezone(_dt.timezone.utc).replace(tzinfo=None)
    seconds_of_day = utc.hour * 3600.0 + utc.minute * 60.0 + utc.second + utc.microsecond * 1e-6
    jd_utc_midnight = julian_date(utc.year, utc.month, utc.day)
    tt_minus_utc = TT_MINUS_TAI_S + tai_minus_utc_s(utc.date())
    return (jd_utc_midnight - JD_J2000) * SECONDS_PER_DAY + seconds_of_day + tt_minus_utc


def parse_utc(text: str) -> _dt.datetime:
    """Parse an ISO 8601 UTC timestamp such as ``2020-01-01T12:00:00``."""
    try:
        value = _dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except (TypeError, ValueError):
        raise ValueError(f"epoch.utc: {text!r} is not an ISO 8601 date-time such as '2020-01-01T12:00:00'") from None
    return value


def julian_centuries_tt(t_tt_s):
    """Julian centuries of TT since J2000.0."""
    return t_tt_s / (SECONDS_PER_DAY * DAYS_PER_JULIAN_CENTURY)


def gmst_rad(t_tt_s, tt_minus_ut1_s):
    """Greenwich mean sidereal time (IAU 1982) in radians, in [0, 2 pi).

    Args:
      t_tt_s: TT seconds since J2000.0, any shape.
      tt_minus_ut1_s: TT - UT1 in seconds (69.184 - (UT1 - UTC) since 2017).
    """
    d_ut1 = (t_tt_s - tt_minus_ut1_s) / SECONDS_PER_DAY
    t = d_ut1 / DAYS_PER_JULIAN_CENTURY
    # Split 360.98564736629 d into whole turns (d itself) and the rest so the
    # large product does not cost float64 digits.
    gmst_deg = 280.46061837 + 0.98564736629 * d_ut1 + 360.0 * jnp.mod(d_ut1, 1.0)
    gmst_deg = gmst_deg + 0.000387933 * t**2 - t**3 / 38710000.0
    return jnp.deg2rad(jnp.mod(gmst_deg, 360.0))
