"""What a validated scenario table sets in the physics: the initial state (``initial_mee``, from MEE, Keplerian
elements or an offset from the station) and the force model (``force_model``)."""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from geojax.control.predictor import station_mee
from geojax.physics import constants as c
from geojax.physics.elements import cartesian_to_mee, kepler_to_mee
from geojax.physics.forces import ForceModel
from geojax.physics.frames import ecef_to_eci, earth_rotation_angle_rad
from geojax.physics.geopotential import egm2008


def initial_mee(config: dict, epoch_tt_s: float, tt_minus_ut1_s: float) -> np.ndarray:
    """The initial MEE [6] (p in m, f, g, h, k, L in rad; ECI of the epoch) of a validated scenario table, from its
    ``orbit`` (and, for ``station_offset``, its ``station``) at ``epoch_tt_s`` (TT seconds) and
    ``tt_minus_ut1_s`` (s)."""
    orbit, station = config["orbit"], config["station"]
    kind = orbit["elements"]
    if kind == "mee":
        return np.array([orbit["p_km"] * 1e3, orbit["f"], orbit["g"], orbit["h"], orbit["k"], orbit["L_rad"]])
    if kind == "kepler":
        return np.asarray(
            kepler_to_mee(
                orbit["a_km"] * 1e3, orbit["e"], math.radians(orbit["i_deg"]), math.radians(orbit["raan_deg"]),
                math.radians(orbit["argp_deg"]), math.radians(orbit["true_anomaly_deg"]),
            )
        )
    angle = earth_rotation_angle_rad(epoch_tt_s, epoch_tt_s, tt_minus_ut1_s)
    if kind == "station":
        return station_target_mee(station, float(angle))
    # station_offset: Katz 2025, Sec. 3.1: "a deviation of 2 km in each ECEF
    # axis from the desired station, and the correct velocity of the desired
    # orbit", read as the station's own inertial velocity omega x r_station.
    lon = math.radians(station["lon_deg"])
    radius_m = station["radius_km"] * 1e3
    station_ecef = np.array([radius_m * math.cos(lon), radius_m * math.sin(lon), 0.0])
    r_eci = ecef_to_eci(jnp.asarray(station_ecef + np.array(orbit["offset_ecef_km"]) * 1e3), angle)
    v_eci = jnp.cross(jnp.array([0.0, 0.0, c.OMEGA_EARTH_RAD_S]), ecef_to_eci(jnp.asarray(station_ecef), angle))
    return np.asarray(cartesian_to_mee(r_eci, v_eci, c.MU_EARTH_M3_S2))


def station_target_mee(station: dict, earth_angle_rad: float) -> np.ndarray:
    """MEE [6] on the station's targets at an Earth angle: the target e vector (f, g) and inclination vector
    (h, k), the semi-major axis at the station's radius, the mean longitude at the station's longitude (the
    predictor's ``station_mee``).  The targets are mean elements, taken here as osculating: the short-period
    terms (the Sun's, the Moon's and the SRP's, ~1e-6 in e) are the same for satellites of one slot and cancel in
    their separation; the controllers correct the rest from the first cycle."""
    e2 = station["ex"] ** 2 + station["ey"] ** 2
    targets = {"lon_rad": math.radians(station["lon_deg"]), **{k: station[k] for k in ("ex", "ey", "ix", "iy")}}
    return np.asarray(station_mee(targets, station["radius_km"] * 1e3 * (1 - e2), earth_angle_rad))


def force_model(config: dict) -> ForceModel:
    """The ``ForceModel`` of the ``forces`` and ``spacecraft`` tables of ``config`` (all it reads: a transfer's
    tables serve too)."""
    forces, craft = config["forces"], config["spacecraft"]
    on = lambda flag: float(bool(flag))  # noqa: E731
    return ForceModel(
        j2_on=on(forces["j2"]),
        c22_on=on(forces["c22_s22"]),
        sun_on=on(forces["sun"]),
        moon_on=on(forces["moon"]),
        srp_on=on(forces["srp"]),
        srp_pressure_1au_n_m2=forces["srp_pressure_n_m2"],
        reflectivity=craft["reflectivity"],
        srp_area_m2=craft["srp_area_m2"],
        shadow_on=on(forces["shadow"] == "conical"),
        moon_radius_m=c.R_MOON_M if forces.get("moon_shadow") else None,
        gravity=None if forces.get("gravity_degree") is None else egm2008(forces["gravity_degree"],
                                                                         forces.get("gravity_order")),
    )
