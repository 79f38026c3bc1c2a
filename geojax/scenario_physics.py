"""What a validated scenario table sets in the physics: the initial state (``initial_mee``, from MEE, Keplerian
elements or an offset from the station) and the force model (``force_model``)."""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from geojax.control.predictor import station_mee
from geojax.physics import constants as c
from geojax.physics.elements import cartesian_to_mee, kepler_to_mee, mee_to_cartesian
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
        return station_target_mee(config, float(angle))
    # station_offset: Katz 2025, Sec. 3.1: "a deviation of 2 km in each ECEF
    # axis from the desired station, and the correct velocity of the desired
    # orbit", read as the station's own inertial velocity omega x r_station.
    lon = math.radians(station["lon_deg"])
    radius_m = station["radius_km"] * 1e3
    station_ecef = np.array([radius_m * math.cos(lon), radius_m * math.sin(lon), 0.0])
    r_eci = ecef_to_eci(jnp.asarray(station_ecef + np.array(orbit["offset_ecef_km"]) * 1e3), angle)
    v_eci = jnp.cross(jnp.array([0.0, 0.0, c.OMEGA_EARTH_RAD_S]), ecef_to_eci(jnp.asarray(station_ecef), angle))
    return np.asarray(cartesian_to_mee(r_eci, v_eci, c.MU_EARTH_M3_S2))


def station_target_mee(config: dict, earth_angle_rad: float) -> np.ndarray:
    """MEE [6] on the station's targets at an Earth angle: the target e vector (f, g) and inclination vector
    (h, k), the mean longitude at the station's longitude (the predictor's ``station_mee``), at the synchronous
    radius of the field's J2 (``synchronous_radius_m``: no mean longitude drift), the velocity raised by its
    J2 term (a circular orbit in a J2 field moves sqrt(1 + 3/2 J2 (R/r)^2) faster than a Keplerian one).  The
    targets are mean elements, taken here as osculating but for that J2 term (3.7e-5 in e at GEO): the Sun's,
    the Moon's and the SRP's short-period terms (~1e-6) are the same for satellites of one slot and cancel in
    their separation; the controllers correct the rest from the first cycle."""
    station, forces = config["station"], config["forces"]
    j2 = c.J2 if forces["j2"] or (forces.get("gravity_degree") or 0) >= 2 else 0.0
    radius_m = synchronous_radius_m(j2)
    e2 = station["ex"] ** 2 + station["ey"] ** 2
    targets = {"lon_rad": math.radians(station["lon_deg"]), **{k: station[k] for k in ("ex", "ey", "ix", "iy")}}
    rv = mee_to_cartesian(station_mee(targets, radius_m * (1 - e2), earth_angle_rad), c.MU_EARTH_M3_S2)
    speed_up = math.sqrt(1 + 1.5 * j2 * (c.R_EARTH_M / radius_m) ** 2)
    return np.asarray(cartesian_to_mee(rv[0], rv[1] * speed_up, c.MU_EARTH_M3_S2))


def synchronous_radius_m(j2: float) -> float:
    """The radius of the circular equatorial orbit whose angular rate is the Earth's in a field of ``j2``:
    omega^2 r^3 = mu (1 + 3/2 J2 (R/r)^2) (42164.17 km without J2, 42164.70 with the Earth's)."""
    r = (c.MU_EARTH_M3_S2 / c.OMEGA_EARTH_RAD_S**2) ** (1 / 3)
    for _ in range(4):  # fixed point: the J2 term changes r by 1e-5 of itself
        r = (c.MU_EARTH_M3_S2 * (1 + 1.5 * j2 * (c.R_EARTH_M / r) ** 2) / c.OMEGA_EARTH_RAD_S**2) ** (1 / 3)
    return r


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
