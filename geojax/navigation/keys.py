"""The keys of a scenario's ``[navigation]`` table, declared as ``params.Field``s, and their validation.

The table is part of the scenario schema (``geojax.scenario_schema``); its stations (``[[navigation.stations]]``)
and receiver (``[navigation.gnss]``) are sub-tables checked here.  ``validate`` gives one ``ValueError`` naming
the key (``navigation.stations[0].lat_deg: ...``).  With ``model = "ekf"`` the loop carries the filter
(``geojax.states.navigation``); the default, ``"gaussian_fix"``, is Li 2022's fix and reads none of the other keys.
"""

from __future__ import annotations

import math

from geojax.navigation.measurements import MODELS
from geojax.params import NUMBER, REQUIRED, Field, check_table

MAX_SIGMA = 1.0e6  # no measurement noise or bias reaches this in its unit (1000 km, 1000 km/s): a unit slip

SIGMA = dict(lower=0.0, upper=MAX_SIGMA, lower_inclusive=True)
DAY_S = 86400.0

FIELDS = {
    "model": Field(str, "gaussian_fix", choices=("gaussian_fix", "ekf"), static=True,
                   doc="Li 2022's Gaussian fix (today's numbers) or the extended Kalman filter"),
    "filter_forces": Field(str, "loop", choices=("loop", "two_body"), static=True,
                           doc="the filter's prediction model: the loop's force model, or point-mass gravity"),
    "snc_mps2_per_rthz": Field(NUMBER, 0.0, **SIGMA, si="snc_mps2_per_rthz",
                               doc="state-noise compensation: white acceleration noise density per axis"),
    "assumed_sigma3_dv_pct": Field(NUMBER, None, lower=0.0, upper=100.0, lower_inclusive=True,
                                   doc="the filter's prior of every burn's thrust-level error, 3 sigma in % (unset: "
                                       "the truth's, errors.sigma3_dv_pct)"),
    "assumed_sigma3_att_deg": Field(NUMBER, None, lower=0.0, upper=270.0, lower_inclusive=True,
                                    doc="the filter's prior of every burn's pointing error per perpendicular axis, "
                                        "3 sigma in deg (unset: the truth's, errors.sigma3_att_deg)"),
    "initial_sigma_r_m": Field(NUMBER, 100.0, lower=0.0, upper=MAX_SIGMA, si="initial_sigma_r_m",
                               doc="the filter's initial position sigma per axis (and the initial error's)"),
    "initial_sigma_v_mps": Field(NUMBER, 0.01, lower=0.0, upper=MAX_SIGMA, si="initial_sigma_v_mps",
                                 doc="the filter's initial velocity sigma per axis (and the initial error's)"),
    "estimate_biases": Field(bool, False, static=True,
                             doc="the filter estimates each measurement component's bias as a constant state, "
                                 "its prior the bias sigma; false: the biases are drawn and not estimated"),
    "burns_during_passes": Field(bool, True, si="burns_during_passes",
                                 doc="whether the thrusters may fire while a station tracks; false: a burn's steps "
                                     "inside any station's pass are not fired (the plan does not move them: the "
                                     "next cycle's plan makes up what was not flown)"),
    # static: the stations' count and measurement kinds shape the filter (their values are leaves)
    "stations": Field(list, [], static=True, identity=lambda stations: tuple(tuple(s.get("measurements", ()))
                                                                             for s in stations),
                      doc="the ground stations, a list of tables ([[navigation.stations]])"),
    "gnss": Field(dict, None, static=True, identity=lambda gnss: gnss is not None,
                  doc="a GNSS-in-GEO receiver ([navigation.gnss]); absent: none"),
}

SCHEDULE_FIELDS = {
    "cadence_s": Field(NUMBER, DAY_S, lower=0.0, upper=1.0e3 * DAY_S, doc="time between pass starts"),
    "pass_s": Field(NUMBER, DAY_S, lower=0.0, upper=1.0e3 * DAY_S, doc="pass length (= cadence_s: continuous)"),
    "phase_s": Field(NUMBER, 0.0, lower=-1.0e3 * DAY_S, upper=1.0e3 * DAY_S, lower_inclusive=True,
                     doc="start of a pass, s since the start of the run"),
    "outages_s": Field(list, [], doc="windows [start_s, stop_s] without tracking"),
}

STATION_FIELDS = {
    "lat_deg": Field(NUMBER, REQUIRED, lower=-90.0, upper=90.0, lower_inclusive=True, doc="geodetic latitude (WGS-84)"),
    "lon_deg": Field(NUMBER, REQUIRED, lower=-180.0, upper=360.0, lower_inclusive=True, doc="east longitude"),
    "alt_m": Field(NUMBER, 0.0, lower=-1.0e4, upper=1.0e5, doc="height above the WGS-84 ellipsoid"),
    "mask_deg": Field(NUMBER, 5.0, lower=-90.0, upper=90.0, lower_inclusive=True, doc="elevation mask"),
    "measurements": Field(list, ["range"], doc=f"measurement types, of {', '.join(k for k in MODELS if k != 'gnss')}"),
    "range_sigma_m": Field(NUMBER, 5.0, **SIGMA, doc="two-way range noise, 1 sigma"),
    "range_bias_sigma_m": Field(NUMBER, 0.0, **SIGMA, doc="range bias drawn per sample, 1 sigma"),
    "range_rate_sigma_mps": Field(NUMBER, 1.0e-3, **SIGMA, doc="two-way range-rate noise, 1 sigma"),
    "range_rate_bias_sigma_mps": Field(NUMBER, 0.0, **SIGMA, doc="range-rate bias drawn per sample, 1 sigma"),
    "angles_sigma_deg": Field(NUMBER, 0.01, **SIGMA, doc="azimuth and elevation noise, 1 sigma each"),
    "angles_bias_sigma_deg": Field(NUMBER, 0.0, **SIGMA, doc="azimuth and elevation bias per sample, 1 sigma"),
    **SCHEDULE_FIELDS,
}

GNSS_FIELDS = {
    "sigma_m": Field(NUMBER, 10.0, **SIGMA, doc="position-fix noise per axis, 1 sigma"),
    "bias_sigma_m": Field(NUMBER, 0.0, **SIGMA, doc="position-fix bias per axis drawn per sample, 1 sigma"),
    **SCHEDULE_FIELDS,
}


def validate(table: dict, prefix: str = "navigation.") -> dict:
    """The ``[navigation]`` table checked and completed with defaults; ``ValueError`` naming the first bad key."""
    out = check_table(prefix, table, FIELDS)
    if not out["stations"] and out["gnss"] is None and out["model"] == "ekf":
        raise ValueError(f"{prefix}stations: the filter needs a station or [{prefix}gnss], got neither")
    out["stations"] = [_station(f"{prefix}stations[{i}].", s) for i, s in enumerate(out["stations"])]
    if out["gnss"] is not None:
        out["gnss"] = _tracker(f"{prefix}gnss.", out["gnss"], GNSS_FIELDS)
    return out


def _station(prefix: str, table) -> dict:
    out = _tracker(prefix, table, STATION_FIELDS)
    kinds = [k for k in MODELS if k != "gnss"]
    if not out["measurements"]:
        raise ValueError(f"{prefix}measurements: must name at least one of {', '.join(map(repr, kinds))}, got []")
    for i, kind in enumerate(out["measurements"]):
        if kind not in kinds:
            raise ValueError(f"{prefix}measurements[{i}]: must be one of {', '.join(map(repr, kinds))}, got {kind!r}")
    return out


def _tracker(prefix: str, table, fields: dict) -> dict:
    """A station's or the receiver's table, with its schedule's checks across keys."""
    out = check_table(prefix, table, fields)
    if out["pass_s"] > out["cadence_s"]:
        raise ValueError(f"{prefix}pass_s: must be <= cadence_s ({out['cadence_s']:g}), got {out['pass_s']!r}")
    for i, window in enumerate(out["outages_s"]):
        if not (isinstance(window, list) and len(window) == 2
                and all(isinstance(x, NUMBER) and not isinstance(x, bool) and math.isfinite(x) for x in window)
                and window[0] < window[1]):
            raise ValueError(f"{prefix}outages_s[{i}]: must be [start_s, stop_s] with start_s < stop_s, got {window!r}")
    return out


def check_with(config: dict) -> dict:
    """The ``[navigation]`` table of a validated scenario (``config``, its other tables checked) checked across
    tables; returns it completed.  With the Gaussian fix no other key of the table is read; with the filter the
    Gaussian fix's error (``errors.h_rv``, ``sigma3_r_m``, ``sigma3_v_mps``) must be 0, the filter's estimate
    replacing the fix, and the filter's priors of the burns' execution errors default to the truth's
    (``errors.sigma3_dv_pct``, ``errors.sigma3_att_deg``)."""
    table = validate({k: v for k, v in config.get("navigation", {}).items() if v is not None})
    if table["model"] == "gaussian_fix":
        for key, field in FIELDS.items():
            if key != "model" and table[key] != field.default:
                raise ValueError(f"navigation.{key}: read only where navigation.model = \"ekf\", got {table[key]!r}; "
                                 f"set navigation.model = \"ekf\" or leave it out")
        return table
    errors = config["errors"]
    for key in ("h_rv", "sigma3_r_m", "sigma3_v_mps"):
        if errors[key]:
            raise ValueError(f"errors.{key}: must be 0 with navigation.model = \"ekf\" (the filter's estimate "
                             f"replaces the Gaussian fix), got {errors[key]!r}")
    for key, truth in (("assumed_sigma3_dv_pct", "sigma3_dv_pct"), ("assumed_sigma3_att_deg", "sigma3_att_deg")):
        if table[key] is None:
            table[key] = errors[truth]
    return table
