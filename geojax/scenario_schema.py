"""The keys of a station-keeping scenario file: every table's ``Field`` declarations (``SCHEMA``: type, default,
bounds, unit, the ``Params`` leaf each becomes), the bounds they share, the dates each ephemeris covers and the
orbit keys each kind of initial elements needs.  ``geojax.scenario`` validates a file against them."""

from __future__ import annotations

from geojax.nominal_errors import AXES, NOMINAL_3SIGMA_ATT_DEG, NOMINAL_3SIGMA_R_M, NOMINAL_3SIGMA_V_MPS
from geojax.params import LOG, NUMBER as _NUMBER, REQUIRED, Field, degrees
from geojax.physics import constants as c
from geojax.physics.forces import ForceModel
from geojax.physics.geopotential import MAX_DEGREE as MAX_GRAVITY_DEGREE
from geojax.physics.propagate import cycle_count, steps_per_cycle

MAX_ORBIT_KM = 2.0e6  # beyond Earth's Hill sphere (1.5e6 km)
MAX_ANGLE_RAD, MAX_ANGLE_DEG = 1.0e3, 1.0e5  # about 160 and 280 turns: more is a unit slip
MAX_MASS_KG = 1.0e6  # twice the ISS
MAX_DAYS = 36526.0  # a hundred years
# The UTC dates a run may span, by ephemeris: from the leap-second table's start (``physics.time``) to the end of
# the years the Meeus series are checked over against ERFA (tests/test_ephemeris.py, 2000-2050), or to the end of
# the DE421 kernel (JD 2524624.5, 2200-02-02).
EPHEMERIS_UTC_RANGE = {"meeus": ("1999-01-01", "2051-01-01"), "de421": ("1999-01-01", "2200-02-01")}

SCHEMA: dict[str, dict[str, Field]] = {
    "": {"name": Field(str, REQUIRED), "description": Field(str, ""),
         "states": Field(list, [], static=True, identity=tuple,
                         doc="parts of one's own the loop carries, by import path ('package.module:NAME' of a "
                             "geojax.StateModel or geojax.Part)")},
    "epoch": {
        "utc": Field(str, REQUIRED, symbol="epoch", unit="year", static=True),  # a sweep axis of dates is drawn in years
        "ut1_minus_utc_s": Field(_NUMBER, 0.0, lower=-0.9, upper=0.9, static=True),
    },
    "orbit": {
        "elements": Field(str, REQUIRED, choices=("mee", "kepler", "station_offset", "station")),
        # elements = "mee": Li 2022, eq. (5)
        # Bounds catch unit slips, not physics: an orbit beyond Earth's Hill sphere (1.5e6 km), |h|, |k| of
        # 100 (i = 178.9 deg, near the retrograde singularity of MEE), angles of tens of turns.
        "p_km": Field(_NUMBER, None, lower=0.0, upper=MAX_ORBIT_KM),
        "f": Field(_NUMBER, None, lower=-1.0, upper=1.0), "g": Field(_NUMBER, None, lower=-1.0, upper=1.0),
        "h": Field(_NUMBER, None, lower=-100.0, upper=100.0), "k": Field(_NUMBER, None, lower=-100.0, upper=100.0),
        "L_rad": Field(_NUMBER, None, lower=-MAX_ANGLE_RAD, upper=MAX_ANGLE_RAD),
        # elements = "kepler"
        "a_km": Field(_NUMBER, None, lower=0.0, upper=MAX_ORBIT_KM),
        "e": Field(_NUMBER, None, lower=0.0, upper=1.0, lower_inclusive=True),
        "i_deg": Field(_NUMBER, None, lower=0.0, upper=180.0, lower_inclusive=True),
        "raan_deg": Field(_NUMBER, None, lower=-MAX_ANGLE_DEG, upper=MAX_ANGLE_DEG),
        "argp_deg": Field(_NUMBER, None, lower=-MAX_ANGLE_DEG, upper=MAX_ANGLE_DEG),
        "true_anomaly_deg": Field(_NUMBER, None, lower=-MAX_ANGLE_DEG, upper=MAX_ANGLE_DEG),
        # elements = "station_offset": at the station, displaced in ECEF, with the station's inertial velocity
        "offset_ecef_km": Field(list, None, length=3),
    },
    "station": {
        "lon_deg": Field(_NUMBER, REQUIRED, lower=-180.0, upper=360.0, lower_inclusive=True, si="lon_rad",
                         to_si=degrees),
        "radius_km": Field(_NUMBER, 42164.16, lower=0.0, upper=MAX_ORBIT_KM, si="radius_m", to_si=1e3),
        # Target mean e and i vectors, MEE (f, g) and (h, k) (Li 2022 eq. (10)): e < 1, i < 90 deg.
        "ex": Field(_NUMBER, 0.0, lower=-1.0, upper=1.0, si="ex"), "ey": Field(_NUMBER, 0.0, lower=-1.0, upper=1.0, si="ey"),
        "ix": Field(_NUMBER, 0.0, lower=-1.0, upper=1.0, si="ix"), "iy": Field(_NUMBER, 0.0, lower=-1.0, upper=1.0, si="iy"),
        # The box: a sample whose sub-satellite point leaves +-this in longitude or latitude at any step
        # start gets status 2 or 3 (``geojax.loop.metrics``).
        "box_half_width_deg": Field(_NUMBER, 0.05, lower=0.0, upper=90.0, si="box_half_width_rad", to_si=degrees),
    },
    "spacecraft": {
        "mass_kg": Field(_NUMBER, REQUIRED, lower=0.0, upper=MAX_MASS_KG),
        # The mass without propellant: the thrusters stop when it is reached (status 5).  0: no limit set.
        "dry_mass_kg": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=MAX_MASS_KG, si="dry_mass_kg"),
        "srp_area_m2": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6),
        # The SRP model's reflectivity eta (Li 2022 eq. (4)); the default is the force model's (Li's 0.6).
        "reflectivity": Field(_NUMBER, ForceModel._field_defaults["reflectivity"], lower=0.0, upper=1.0 + 1e-12,
                              lower_inclusive=True),
    },
    "thrusters": {
        # The thrusters on board: unset, the controller's (2 for Li's arms, 1 for a gimbal or a manipulator; the
        # arms' planners also fly 4, two per arm); a count the controller cannot fly is refused at load
        # (``control.base``: its module's ``THRUSTERS`` and ``REDUNDANT_THRUSTERS``).
        "count": Field(int, None, lower=1, upper=65, lower_inclusive=True, si="count",
                       doc="thrusters on board; unset: the controller's (refused if it flies another number)"),
        "thrust_n": Field(_NUMBER, REQUIRED, lower=0.0, upper=1e5, si="thrust_n", transform=LOG),
        "isp_s": Field(_NUMBER, REQUIRED, lower=0.0, upper=1e6, si="isp_s", transform=LOG),
        # Robotic-arm limits, Li 2022 eq. (1); defaults: the "normal" level of Table 1.
        "beta_max_deg": Field(_NUMBER, 70.0, si="beta_max_rad", to_si=degrees, symbol="β_max"),
        "beta_min_deg": Field(_NUMBER, 0.0, si="beta_min_rad", to_si=degrees, symbol="β_min"),
        "alpha_max_deg": Field(_NUMBER, 60.0, si="alpha_max_rad", to_si=degrees, symbol="α_max"),
        "alpha_min_deg": Field(_NUMBER, 30.0, si="alpha_min_rad", to_si=degrees, symbol="α_min"),
        "min_burn_s": Field(_NUMBER, 30.0, lower=0.0, lower_inclusive=True, upper=c.SIDEREAL_DAY_S, si="min_burn_s"),
        # The thruster geometry the fuel bound uses (geojax.bound.directions): Li's two arms, Katz's gimbal,
        # Gazzino's four fixed NE/NW/SE/SW thrusters (cant_deg from the north-south axis); unset: from the
        # controller (gimbal for lyapunov and zone_nssk, else arms).
        "layout": Field(str, None, choices=("arms", "gimbal", "fixed4", "axes")),
        "cant_deg": Field(_NUMBER, 45.0, lower=0.0, lower_inclusive=True, upper=90.0),
    },
    # The [controller] table: `kind` here, `recovery` from geojax.control.recovery, the other keys from the
    # controller's module (control.REGISTRY); geojax.scenario joins them.
    "controller": {"kind": Field(str, "none")},
    # Each error stated once (``geojax.nominal_errors``): its 3-sigma size (sigma3_*), or for Li 2022's errors
    # (eqs. (47)-(48)) the multiple H of the paper's nominal 3-sigma errors (0.3 m, 5e-5 m/s, 0.05 deg).
    "errors": {
        "h_rv": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, symbol="H_rv", unit="",
                      doc=f"orbit-determination error as a multiple of Li 2022's nominal 3-sigma per component, "
                          f"{NOMINAL_3SIGMA_R_M:g} m and {NOMINAL_3SIGMA_V_MPS:g} m/s (eq. (48)): a preset of "
                          f"sigma3_r_m and sigma3_v_mps; 0: none"),
        "h_att": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, symbol="H_att", unit="",
                       doc=f"attitude (yaw and pitch) error of the burns as a multiple of Li 2022's nominal 3-sigma, "
                           f"{NOMINAL_3SIGMA_ATT_DEG:g} deg (eq. (48)): a preset of sigma3_att_deg; 0: none"),
        "sigma3_r_m": Field(_NUMBER, None, lower=0.0, lower_inclusive=True, upper=1e6, symbol="3σ_r",
                            doc="orbit-determination (Gaussian fix) position error, 3-sigma per component, in m "
                                "(unset: errors.h_rv's)"),
        "sigma3_v_mps": Field(_NUMBER, None, lower=0.0, lower_inclusive=True, upper=1e3, symbol="3σ_v",
                              doc="orbit-determination (Gaussian fix) velocity error, 3-sigma per component, in m/s "
                                  "(unset: errors.h_rv's)"),
        "sigma3_att_deg": Field(_NUMBER, None, lower=0.0, lower_inclusive=True, upper=1e4, symbol="3σ_att",
                                doc="pointing error of every burn, 3-sigma in yaw and in pitch, in deg (unset: "
                                    "errors.h_att's)"),
        "sigma3_dv_pct": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=100.0, si="sigma3_dv_frac",
                               to_si=0.01, symbol="3σ_ΔV", unit="%",
                               doc="thrust-level error of every burn (the plan unaware), 3-sigma in % of the "
                                   "planned; 0: none"),
        # How the attitude error enters (physics.execution; studies/ablation/li_attitude_error.py): on both axes (Li's
        # eq. (47) as printed) or one, one draw shared by a cycle's two burns instead of one each, and the burns'
        # magnitudes re-fitted to the directions flown (the plan knows the error) instead of kept.
        "att_axes": Field(str, "yaw_pitch", choices=tuple(AXES)),
        "att_shared": Field(bool, False, si="att_shared"),
        "att_known": Field(bool, False, si="att_known"),
    },
    "forces": {
        "j2": Field(bool, True),
        "c22_s22": Field(bool, False),
        "sun": Field(bool, True),
        "moon": Field(bool, True),
        "srp": Field(bool, True),
        # The Earth's shadow ("conical": umbra and penumbra, Montenbruck & Gill Sec. 3.4.2); moon_shadow adds the
        # Moon as an occulting body (same model): both cut SRP and the thrusters' sunlit windows.
        "shadow": Field(str, "conical", choices=("conical", "none")),
        "moon_shadow": Field(bool, False, static=True),
        # Sun and Moon: "meeus" (analytic series, geojax.physics.ephemeris) or "de421" (JPL DE421 through
        # jplephem), evaluated once per scenario on the environment grid.
        "ephemeris": Field(str, "meeus", choices=("meeus", "de421"), static=True),
        "srp_pressure_n_m2": Field(_NUMBER, ForceModel._field_defaults["srp_pressure_1au_n_m2"], lower=0.0, lower_inclusive=True, upper=1e-2),
        # The Earth's field to degree and order N (EGM2008, tide-free, shipped to degree 20): replaces `j2` and
        # `c22_s22` where given (those stay for the papers' models).  Order: default the degree, 0 <= M <= N.
        "gravity_degree": Field(int, None, lower=2, upper=MAX_GRAVITY_DEGREE + 1, lower_inclusive=True, static=True),
        "gravity_order": Field(int, None, lower=0, upper=MAX_GRAVITY_DEGREE + 1, lower_inclusive=True, static=True),
    },
    "integration": {
        "step_s": Field(_NUMBER, 900.0, lower=0.0, upper=c.SIDEREAL_DAY_S + 1.0, static=True, identity=steps_per_cycle),
        "dynamics": Field(str, "mee", choices=("mee", "cartesian"), static=True),
    },
    "duration": {"days": Field(_NUMBER, 365.25, lower=0.0, upper=MAX_DAYS, static=True, identity=cycle_count)},
}

# The keys of ``orbit`` that each ``orbit.elements`` needs (every other one of them must be left out).
ORBIT_KEYS = {
    "mee": ("p_km", "f", "g", "h", "k", "L_rad"),
    "kepler": ("a_km", "e", "i_deg", "raan_deg", "argp_deg", "true_anomaly_deg"),
    "station_offset": ("offset_ecef_km",),
    "station": (),  # on the station's targets: its longitude, e and i vectors, at its radius
}
