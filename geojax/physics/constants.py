"""Physical constants, SI units.

Sources: IERS Conventions (2010) Table 1.1 for GM_earth, the Earth's rotation
rate and the astronomical unit; EGM2008 for J2, C22 and S22 (un-normalised);
DE430 for GM_sun and GM_moon; NIMA TR8350.2 (2000) for the WGS-84 ellipsoid that ground
stations' geodetic coordinates refer to (its equatorial radius differs from the gravity field's R_EARTH_M
by 0.7 m); the SI definition of the speed of light.
"""

MU_EARTH_M3_S2 = 3.986004418e14
R_EARTH_M = 6378136.3
J2 = 1.0826261738522e-3  # sqrt(5) * 4.84165143790815e-4
# EGM2008 normalised C22 = 2.43914352e-6, S22 = -1.40016683e-6, times
# N22 = sqrt(5 * 2 / 4!) to un-normalise.
C22 = 1.5744604e-6
S22 = -9.0380380e-7
OMEGA_EARTH_RAD_S = 7.292115146706979e-5
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
C_MPS = 299792458.0

MU_SUN_M3_S2 = 1.32712440041e20
MU_MOON_M3_S2 = 4.902800066e12
AU_M = 1.495978707e11
R_SUN_M = 6.957e8
R_MOON_M = 1.7374e6  # mean radius (IAU WG on Cartographic Coordinates, Archinal et al. 2011)

G0_MPS2 = 9.80665
SIDEREAL_DAY_S = 86164.0905
SECONDS_PER_DAY = 86400.0
SECONDS_PER_YEAR = 365.25 * SECONDS_PER_DAY  # the yearly rates' year (Julian)
DAYS_PER_JULIAN_CENTURY = 36525.0
JD_J2000 = 2451545.0
