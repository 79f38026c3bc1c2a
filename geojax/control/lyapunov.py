"""Milankovitch-Lyapunov station-keeping feedback (Gurfil 2024, as written by Katz 2025, eqs. (1)-(4)).

The law acts on the Milankovitch elements (angular momentum h and eccentricity
vector e) of the satellite, in the Earth-fixed (ECEF) frame:

    u = -[k_h dh^T r~ + (k_e / mu) e^T (v~ r~ - h~)]^T                 (1)
      = -k_h (dh x r) - (k_e / mu) (r x (v x e) + h x e),
    dh = h - h_d,  h_d = (0, 0, R_d^2 omega),                          (2)-(3)
    R_d = R + k_lambda (lambda - lambda_d - lambda_b),                  (4)

with a~ the cross-product matrix (a~ b = a x b).  The first term is minus the
gradient, with respect to the velocity, of V_h = |dh|^2 / 2 (dh/dt = r x u, so
dV_h/dt = -k_h |dh x r|^2 for a fixed h_d); the second that of V_e = |e|^2 / 2
(mu de/dt = u x h + v x (r x u) = (v~ r~ - h~) u), so dV_e/dt =
-(k_e / mu^2) |r x (v x e) + h x e|^2.

Readings of the paper (Katz 2025 is terse; each choice is tested):

- **v** is written (x' - omega y, y' + omega x, z'): the ECEF velocity plus
  omega x r, i.e. the *inertial* velocity in ECEF axes.  So h = r x v and e are
  the inertial Milankovitch elements in ECEF axes; h_d = R_d^2 omega z (eq. 3)
  is indeed the inertial angular momentum of a synchronous circular orbit
  (with the ECEF-relative velocity h would be about zero).
- **Units** (the paper's, km and s, and SI here): k_h in 1/(km^2 s) =
  1e-6 1/(m^2 s); k_e in km^2/s^3 = 1e6 m^2/s^3 (both as the paper states and
  dimensionally consistent with eq. (1)).  k_lambda is printed as "km^2/rad",
  which cannot be: R_d in eq. (4) is a length, so k_lambda is in km/rad
  (= 1e3 m/rad); with 3200 km/rad and lambda - lambda_d - lambda_b ~ 1e-3 rad
  the desired radius moves by about 3 km, a drift of ~0.04 deg/day, the scale a
  longitude loop needs (3200 km^2/rad would move it by 4 cm).
- **lambda** is the geocentric sub-satellite longitude atan2(y, x) of the ECEF
  position; lambda - lambda_d - lambda_b is wrapped to [-pi, pi).

The law is a pure function of the ECEF state; time enters only through the
frame rotation.  As a controller (``CONTROLLER`` / ``make``) it has no plan:
at the start of each step it reads the true state, rotated into ECEF
(position, and the inertial velocity in ECEF axes), commands u, the thrust
implementation delivers part of it (``thrust_laws``), and the delivered
acceleration is held constant in the orbit (RSW) frame for the step -- a
sample-and-hold at the integration step, as a flight computer would apply it.
For a synchronous orbit the RSW frame turns with the Earth, so this is also a
hold in ECEF.  Holding the command makes the discontinuous laws (eqs.
(5)-(7)) well defined within an RK4 step, and the delivered Delta-V is exactly
sum |u_k| h.  The mass decreases with the scenario's Isp; the law commands
accelerations, so the mass only enters the thrust bookkeeping.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from geojax.control.burns import one_thruster
from geojax.physics import thrust_laws
from geojax.states.base import THRUSTER_LEVELS
from geojax.physics.constants import OMEGA_EARTH_RAD_S
from geojax.control.base import (ARM_LIMIT_KEYS, BURN_KEYS, SURROGATE_TEMPERATURE, Controller, Spec, no_plan,
                                 stateless_init)
from geojax.physics.dynamics import Thrust
from geojax.physics.elements import wrap_angle
from geojax.physics.frames import rotate_z, rsw_basis
from geojax.params import LOG, NUMBER, REQUIRED, Field, Transform, scaled


LAMBDA_B_SCALE_RAD = math.radians(0.1)  # lambda_b enters the tuner in units of 0.1 deg


def _sigma_to_theta(sigma_mps2, leaves):
    return np.log(np.asarray(sigma_mps2) / float(leaves["u0_mps2"]))


def _sigma_from_theta(theta, leaves):
    w = jnp.exp(theta)
    return leaves["u0_mps2"] * w / jnp.linalg.norm(w)


# The thresholds as three log-weights s, sigma = u0 exp(s) / |exp(s)|: |sigma| = u0 holds by construction.
SIGMA_WEIGHTS = Transform("log-weights", _sigma_to_theta, _sigma_from_theta)

# The [controller] table, in the paper's units (see the module docstring for the reading of each).
# What ``geojax.scenario`` holds a scenario of this law to (``control.base``): one thrust vector of any direction,
# flown every step; no arms, no planned burns.
THRUSTERS = (1, "one gimbaled thruster, Katz 2025")
REDUNDANT_THRUSTERS = 2  # or a spare beside it, flown where the first is known out (``told_plan``)
REDUNDANT_WHY = "a spare beside it, flown where the first is known out"
UNREAD = ARM_LIMIT_KEYS + BURN_KEYS

FIELDS = {
    "k_h_per_km2_s": Field(NUMBER, REQUIRED, lower=0.0, si="k_h_per_m2_s", to_si=1e-6, transform=LOG,
                           symbol="k_h", unit="1/(km² s)", alias="k_h", doc="angular-momentum gain, eq. (1)"),
    "k_e_km2_per_s3": Field(NUMBER, REQUIRED, lower=0.0, si="k_e_m2_per_s3", to_si=1e6, transform=LOG,
                            symbol="k_e", unit="km²/s³", alias="k_e", doc="eccentricity gain, eq. (1)"),
    "k_lambda_km_per_rad": Field(NUMBER, REQUIRED, lower=0.0, lower_inclusive=True, si="k_lambda_m_per_rad", to_si=1e3,
                                 transform=LOG, symbol="k_λ", unit="km/rad", alias="k_lambda",
                                 doc="longitude gain of the desired radius, eq. (4)"),
    "lambda_b_deg": Field(NUMBER, REQUIRED, si="lambda_b_rad", to_si=math.pi / 180,
                          transform=scaled(LAMBDA_B_SCALE_RAD, "0.1 deg"), symbol="λ_b", alias="lambda_b",
                          doc="longitude bias, eq. (4)"),
    "thrust_mode": Field(str, "continuous-clipped", choices=thrust_laws.MODES, static=True,
                         doc="thrust implementation, eqs. (5)-(7) (thrust_laws)"),
    # u0: largest acceleration; default thrusters.thrust_n / spacecraft.mass_kg.
    "u0_km_per_s2": Field(NUMBER, None, lower=0.0, si="u0_mps2", to_si=1e3, symbol="u_0", unit="km/s²",
                          doc="largest acceleration; default thrusters.thrust_n / spacecraft.mass_kg"),
    # Discrete thresholds (eq. (6)) along ECEF x, y, z; their norm must be u0.
    "sigma_km_per_s2": Field(list, None, length=3, si="sigma_mps2", to_si=1e3, transform=SIGMA_WEIGHTS, alias="sigma",
                             doc="discrete thresholds along ECEF x, y, z, eq. (6); their norm is u0"),
    # Temperature of the sigmoid surrogate the tuner differentiates (``thrust_laws``; exact runs ignore it).
    "surrogate_temperature": Field(NUMBER, 0.05, lower=0.0, si=SURROGATE_TEMPERATURE,
                                   doc="temperature of the sigmoid surrogate the tuner differentiates"),
}


def validate(config: dict) -> None:
    """Checks across tables, at load: u0 defaults to F / m; the discrete law needs thresholds of norm u0."""
    ctl = config["controller"]
    if ctl["u0_km_per_s2"] is None:
        ctl["u0_km_per_s2"] = config["thrusters"]["thrust_n"] / config["spacecraft"]["mass_kg"] / 1e3
    if ctl["thrust_mode"] == "discrete":
        if ctl["sigma_km_per_s2"] is None:
            raise ValueError("controller.sigma_km_per_s2: missing (required when controller.thrust_mode = 'discrete')")
        thrust_laws.check_thresholds(ctl["u0_km_per_s2"], ctl["sigma_km_per_s2"])


# Katz 2025 tunes (k_h, k_e) (Sec. 3, fmincon), k_lambda and lambda_b fixed at Sec. 3.1's values.
SPEC = Spec(FIELDS, validate, THRUSTERS, REDUNDANT_THRUSTERS, redundant_why=REDUNDANT_WHY, unread=UNREAD,
            tuned_fields=("k_h_per_km2_s", "k_e_km2_per_s3"), bound_geometry="gimbal")


def make(tables: list[dict], smooth: bool = False) -> Controller:
    """The feedback law for ``[controller]`` tables sharing one thrust mode; ``smooth``: the sigmoid surrogate
    of the on/off laws (the continuous-clipped law is smooth already and is its own surrogate)."""
    modes = {t["thrust_mode"] for t in tables}
    if len(modes) > 1:
        raise ValueError(f"controller.thrust_mode: one value per sweep (it selects the compiled law), got {sorted(modes)}")
    return controller(modes.pop(), smooth)


@functools.lru_cache(maxsize=None)
def controller(mode: str, smooth: bool = False) -> Controller:
    """The feedback law with thrust implementation ``mode`` (``thrust_laws.MODES``), exact or its surrogate."""
    deliver = thrust_laws.law(mode)

    def thrust(params, plan, t, state, environment) -> Thrust:
        c = params.controller
        angle = environment.env.earth_angle_rad[0]
        r_eci, v_eci = environment.r_eci_m, environment.v_eci_mps
        r_ecef = rotate_z(r_eci, angle)
        u_cmd = accel(gains(c), station(params, angle), r_ecef, rotate_z(v_eci, angle))
        limits = thrust_laws.ThrustLimits(c["u0_mps2"], c.get("sigma_mps2", jnp.zeros(3)))
        if isinstance(plan, Told):  # the thruster's level as told: the acceleration it can give, scaled by it
            limits = thrust_laws.ThrustLimits(limits.u0_mps2 * plan.level, limits.sigma_mps2 * plan.level)
        u_ecef = deliver(u_cmd, limits, smooth, c[SURROGATE_TEMPERATURE])
        u_rsw = rsw_basis(r_eci, v_eci) @ rotate_z(u_ecef, -angle)
        u_norm = thrust_laws.safe_norm(u_rsw)
        if not isinstance(plan, Told):
            return Thrust(u_rsw / u_norm, u_norm * state.mass_kg, params.thrusters["isp_s"], jnp.asarray(1.0))
        # commanded at 1 / level of the acceleration wanted, so that the thruster delivers it; none known working:
        # nothing commanded
        working = plan.level > 0
        return Thrust(u_rsw / u_norm, u_norm * state.mass_kg / jnp.where(working, plan.level, 1.0),
                      params.thrusters["isp_s"], jnp.where(working, 1.0, 0.0), thruster=plan.thruster)

    surrogate = None if smooth or mode == "continuous-clipped" else controller(mode, smooth=True)
    spec = dataclasses.replace(SPEC, bound_geometry="axes") if mode == "discrete" else SPEC  # eq. (6): per axis
    return Controller(stateless_init, told_plan, thrust, spec, surrogate=surrogate)


class Told(NamedTuple):
    """What the law knows of its thrusters at a cycle start where the faults part tells it (``states.faults``)."""

    thruster: jnp.ndarray  # [] int: the one it flies (``burns.one_thruster``: the best known working)
    level: jnp.ndarray  # [] its level as told (0: none works)


def told_plan(params, controller_state, estimate, context, key):
    """``plan`` of the law: nothing planned (``no_plan``), or, told of the thrusters' levels, the one to fly."""
    if THRUSTER_LEVELS not in estimate.states:
        return no_plan(params, controller_state, estimate, context, key)
    return Told(*one_thruster(estimate.states[THRUSTER_LEVELS], params.thrusters.get("count"))), controller_state


def gains(controller: dict) -> "LyapunovGains":
    """The ``LyapunovGains`` of a ``Params.controller`` table."""
    return LyapunovGains(controller["k_h_per_m2_s"], controller["k_e_m2_per_s3"], controller["k_lambda_m_per_rad"],
                         controller["lambda_b_rad"])


def station(params, earth_angle_rad=None) -> "Station":
    """The slot of eq. (4) from a sample's ``Params``; with the Earth angle, the station's e-vector and
    inclination-vector targets too (``Station.e_target``, ``normal_target``, in ECEF axes then)."""
    s = params.station
    out = Station(s["lon_rad"], s["radius_m"], jnp.asarray(OMEGA_EARTH_RAD_S), params.forces.mu_m3_s2)
    if earth_angle_rad is None:
        return out
    # MEE targets: e vector (f, g) in the equator; orbit normal (2k, -2h, 1 - h^2 - k^2) / (1 + h^2 + k^2)
    h, k = s["ix"], s["iy"]
    normal = jnp.stack([2 * k, -2 * h, 1 - h * h - k * k]) / (1 + h * h + k * k)
    e_target = jnp.stack([s["ex"], s["ey"], 0.0 * s["ex"]])
    return out._replace(e_target=rotate_z(e_target, earth_angle_rad), normal_target=rotate_z(normal, earth_angle_rad))


class LyapunovGains(NamedTuple):
    """Gains of Katz 2025, eqs. (1)-(4), SI units (array leaves: differentiable, sweepable)."""

    k_h_per_m2_s: jnp.ndarray  # > 0
    k_e_m2_per_s3: jnp.ndarray  # > 0
    k_lambda_m_per_rad: jnp.ndarray  # > 0
    lambda_b_rad: jnp.ndarray  # station-dependent longitude bias, any sign


class Station(NamedTuple):
    """The slot the law holds: desired longitude lambda_d and the radius R of eq. (4), and the station's e-vector
    and orbit-normal targets (ECEF axes; None: Katz's e = 0 and h along the pole), so that a satellite of a
    collocated cluster holds its own e and i vectors: the law descends |h - h_d|^2 / 2 and |e - e_d|^2 / 2, whose
    gradients in the control are eq. (1)'s with e - e_d for e (de/du does not depend on the target)."""

    lon_rad: jnp.ndarray
    radius_m: jnp.ndarray
    omega_rad_s: jnp.ndarray
    mu_m3_s2: jnp.ndarray
    e_target: jnp.ndarray | None = None
    normal_target: jnp.ndarray | None = None


def accel(gains: LyapunovGains, station: Station, r_ecef_m, v_ecef_mps):
    """Commanded acceleration [3] (m/s^2, ECEF axes) of eq. (1).

    ``r_ecef_m`` [3] is the ECEF position and ``v_ecef_mps`` [3] the inertial
    velocity in ECEF axes, (x' - omega y, y' + omega x, z').
    """
    mu = station.mu_m3_s2
    h, e = milankovitch(r_ecef_m, v_ecef_mps, mu)
    lon = jnp.arctan2(r_ecef_m[1], r_ecef_m[0])
    radius_d = station.radius_m + gains.k_lambda_m_per_rad * wrap_angle(lon - station.lon_rad - gains.lambda_b_rad)
    dh = h - desired_h(station, radius_d)
    de = e if station.e_target is None else e - station.e_target
    return -gains.k_h_per_m2_s * jnp.cross(dh, r_ecef_m) - gains.k_e_m2_per_s3 / mu * (
        jnp.cross(r_ecef_m, jnp.cross(v_ecef_mps, de)) + jnp.cross(h, de)
    )


def desired_h(station: Station, radius_d_m):
    """The desired angular momentum h_d of eq. (4): R_d^2 omega along the pole, or the target orbit normal."""
    if station.normal_target is None:
        return jnp.stack([0.0, 0.0, radius_d_m**2 * station.omega_rad_s])
    return radius_d_m**2 * station.omega_rad_s * station.normal_target


def lyapunov_terms(station: Station, r_ecef_m, v_ecef_mps, radius_d_m):
    """(|h - h_d|^2 / 2, |e|^2 / 2) for a fixed desired radius: the functions eq. (1) descends."""
    h, e = milankovitch(r_ecef_m, v_ecef_mps, station.mu_m3_s2)
    dh = h - desired_h(station, radius_d_m)
    de = e if station.e_target is None else e - station.e_target
    return 0.5 * jnp.sum(dh**2), 0.5 * jnp.sum(de**2)


def milankovitch(r_m, v_mps, mu):
    """Angular momentum h = r x v (m^2/s) and eccentricity vector e = v x h / mu - r / |r| [3]."""
    h = jnp.cross(r_m, v_mps)
    return h, jnp.cross(v_mps, h) / mu - r_m / jnp.linalg.norm(r_m)
