"""Scenarios: TOML files (shipped ones by name, or any path), validated on load.

A scenario file has the tables ``epoch``, ``orbit``, ``station``, ``spacecraft``,
``thrusters``, ``forces``, ``integration`` and ``duration`` (see
``geojax/scenarios/li2022.toml`` for every key, with comments).  Every problem
is reported as a ``ValueError`` whose message names the field and what is
allowed, e.g. ``spacecraft.mass_kg: must be > 0, got -1.0``; the CLI prints that
line and exits with status 2.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from geojax.physics import constants as c
from geojax.physics.elements import cartesian_to_mee, kepler_to_mee
from geojax.physics.forces import ForceModel
from geojax.physics.geopotential import MAX_DEGREE as MAX_GRAVITY_DEGREE, egm2008
from geojax.physics.frames import ecef_to_eci, earth_rotation_angle_rad
from geojax.params import LOG, REQUIRED, Field, check_table, degrees
from geojax.physics.propulsion import arm_limits_deg
from geojax.physics.time import TT_MINUS_TAI_S, parse_utc, tai_minus_utc_s, tt_seconds_from_utc

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from geojax.params import NUMBER as _NUMBER  # noqa: E402



MAX_ORBIT_KM = 2.0e6  # beyond Earth's Hill sphere (1.5e6 km)
MAX_ANGLE_RAD, MAX_ANGLE_DEG = 1.0e3, 1.0e5  # about 160 and 280 turns: more is a unit slip
MAX_MASS_KG = 1.0e6  # twice the ISS
MAX_DAYS = 36526.0  # a hundred years
# The UTC dates a run may span, by ephemeris: from the leap-second table's start (``physics.time``) to the end of
# the years the Meeus series are checked over against ERFA (tests/test_ephemeris.py, 2000-2050), or to the end of
# the DE421 kernel (JD 2524624.5, 2200-02-02).
EPHEMERIS_UTC_RANGE = {"meeus": ("1999-01-01", "2051-01-01"), "de421": ("1999-01-01", "2200-02-01")}

SCHEMA: dict[str, dict[str, Field]] = {
    "": {"name": Field(str, REQUIRED), "description": Field(str, "")},
    "epoch": {
        "utc": Field(str, REQUIRED, symbol="epoch", unit="year"),  # a sweep axis of dates is drawn in years
        "ut1_minus_utc_s": Field(_NUMBER, 0.0, lower=-0.9, upper=0.9),
    },
    "orbit": {
        "elements": Field(str, REQUIRED, choices=("mee", "kepler", "station_offset")),
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
        "count": Field(int, 2, lower=1, upper=65, lower_inclusive=True),
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
    # The [controller] table: `kind` here, the other keys from the controller's module (control.REGISTRY).
    "controller": {"kind": Field(str, "none")},
    # Li 2022, eqs. (47)-(48): multiples H of the nominal 3-sigma errors (0.3 m, 5e-5 m/s, 0.05 deg).
    "errors": {
        "h_rv": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, si="h_rv", symbol="H_rv"),
        "h_att": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=1e6, si="h_att", symbol="H_att"),
        # How the attitude error enters (control.burns; studies/ablation/li_attitude_error.py): its yaw and pitch
        # parts scaled (1: eq. (47) as printed), one draw shared by a cycle's two burns instead of one each, and
        # the burns' magnitudes re-fitted to the directions flown (the plan knows the error) instead of kept.
        "att_yaw": Field(_NUMBER, 1.0, lower=0.0, lower_inclusive=True, upper=1e6, si="att_yaw"),
        "att_pitch": Field(_NUMBER, 1.0, lower=0.0, lower_inclusive=True, upper=1e6, si="att_pitch"),
        "att_shared": Field(bool, False, si="att_shared"),
        "att_known": Field(bool, False, si="att_known"),
        # How the determination error enters (loop.simulate.measured_mee; studies/ablation/li_fig17_width.py): its
        # position and velocity parts scaled (1: eq. (48) as printed, 3 sigma per component).
        "rv_r": Field(_NUMBER, 1.0, lower=0.0, lower_inclusive=True, upper=1e6, si="rv_r"),
        "rv_v": Field(_NUMBER, 1.0, lower=0.0, lower_inclusive=True, upper=1e6, si="rv_v"),
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
        "moon_shadow": Field(bool, False),
        # Sun and Moon: "meeus" (analytic series, geojax.physics.ephemeris) or "de421" (JPL DE421 through
        # jplephem), evaluated once per scenario on the environment grid.
        "ephemeris": Field(str, "meeus", choices=("meeus", "de421")),
        "srp_pressure_n_m2": Field(_NUMBER, ForceModel._field_defaults["srp_pressure_1au_n_m2"], lower=0.0, lower_inclusive=True, upper=1e-2),
        # The Earth's field to degree and order N (EGM2008, tide-free, shipped to degree 20): replaces `j2` and
        # `c22_s22` where given (those stay for the papers' models).  Order: default the degree, 0 <= M <= N.
        "gravity_degree": Field(int, None, lower=2, upper=MAX_GRAVITY_DEGREE + 1, lower_inclusive=True),
        "gravity_order": Field(int, None, lower=0, upper=MAX_GRAVITY_DEGREE + 1, lower_inclusive=True),
    },
    "integration": {
        "step_s": Field(_NUMBER, 900.0, lower=0.0, upper=c.SIDEREAL_DAY_S + 1.0),
        "dynamics": Field(str, "mee", choices=("mee", "cartesian")),
    },
    "duration": {"days": Field(_NUMBER, 365.25, lower=0.0, upper=MAX_DAYS)},
}

_ORBIT_KEYS = {
    "mee": ("p_km", "f", "g", "h", "k", "L_rad"),
    "kepler": ("a_km", "e", "i_deg", "raan_deg", "argp_deg", "true_anomaly_deg"),
    "station_offset": ("offset_ecef_km",),
}


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A validated scenario.  ``config`` is the full table, defaults filled in."""

    config: dict
    epoch_tt_s: float
    tt_minus_ut1_s: float
    initial_mee: np.ndarray  # [6], ECI of the epoch
    force_model: ForceModel

    @property
    def name(self) -> str:
        return self.config["name"]

    @property
    def mass_kg(self) -> float:
        return float(self.config["spacecraft"]["mass_kg"])

    @property
    def step_s(self) -> float:
        return float(self.config["integration"]["step_s"])

    @property
    def days(self) -> float:
        return float(self.config["duration"]["days"])

    @property
    def dynamics(self) -> str:
        return self.config["integration"]["dynamics"]

    @property
    def controller(self) -> str:
        return self.config["controller"]["kind"]

    @property
    def station_lon_deg(self) -> float:
        return float(self.config["station"]["lon_deg"])


def available() -> list[str]:
    """Names of the station-keeping scenarios shipped with geojax (a file with a ``[transfer]`` table is a
    transfer: ``geojax.transfer.scenario.available``)."""
    folder = importlib.resources.files("geojax") / "scenarios"
    return sorted(p.name[:-5] for p in folder.iterdir()
                  if p.name.endswith(".toml") and not isinstance(tomllib.loads(p.read_text()).get("transfer"), dict))


def load(name_or_path: str | Path, overrides: dict | None = None, controller=None) -> Scenario:
    """Load a shipped scenario by name, or a TOML file by path, and validate it.

    ``overrides`` maps dotted keys to values (``{"duration.days": 30}``) and is
    applied before validation.  ``controller`` (a ``control.Controller`` of the
    user's) validates the ``[controller]`` table against its ``fields`` instead
    of those of the registered controller that ``controller.kind`` names.
    """
    text = read_text(name_or_path)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{name_or_path}: not valid TOML ({err})") from None
    return from_dict(with_overrides(raw, overrides), controller)


def started_at(name_or_path: str | Path, utc: str, overrides: dict | None = None, controller=None) -> Scenario:
    """Scenario ``name_or_path`` (with ``overrides``; ``controller`` as in ``load``) started at ``utc`` instead
    of its epoch, from the same orbit relative to the Earth: the same geographic longitude, so the same slot in
    another year.  An MEE initial state keeps its elements but the true longitude, moved by the Earth's rotation
    between the two epochs; a ``station_offset`` one is already given in the Earth-fixed frame and needs no
    move; a Keplerian one is refused (its angles are inertial: give it as MEE).  A fresh run of a later year."""
    base = load(name_or_path, overrides, controller)
    kind = base.config["orbit"]["elements"]
    moved = load(name_or_path, {**(overrides or {}), "epoch.utc": utc}, controller)
    if kind == "station_offset":
        return moved
    if kind != "mee":
        raise ValueError(f"orbit.elements: moving a scenario to another epoch needs \"mee\" or \"station_offset\" "
                         f"elements, got {kind!r}")
    angle = lambda sc: float(earth_rotation_angle_rad(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s))  # noqa: E731
    l_rad = math.remainder(float(base.initial_mee[5]) + angle(moved) - angle(base), 2 * math.pi)
    return load(name_or_path, {**(overrides or {}), "epoch.utc": utc, "orbit.L_rad": l_rad}, controller)


def with_overrides(raw: dict, overrides: dict | None) -> dict:
    """``raw`` with dotted keys set (``{"thrusters.thrust_n": 0.3}``); a key must name a table and a field."""
    raw = {k: dict(v) if isinstance(v, dict) else v for k, v in raw.items()}
    for dotted, value in (overrides or {}).items():
        table, _, key = str(dotted).rpartition(".")
        if not table or table not in SCHEMA:
            raise ValueError(f"{dotted}: not a scenario key; write it as TABLE.KEY with a table of "
                             f"{', '.join(t for t in SCHEMA if t)} (e.g. \"duration.days\")")
        if not isinstance(raw.setdefault(table, {}), dict):
            raise ValueError(f"{table}: must be a table")
        raw[table][key] = value
    return raw


def read_toml_file(path: str | Path, kind: str) -> tuple[dict, str]:
    """(table, text) of a TOML file (a sweep or tuning file); ``ValueError`` naming the ``kind`` of file."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{kind} file {str(path)!r}: no such file")
    text = path.read_text()
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{kind} file {str(path)!r}: not valid TOML ({err})") from None


def read_text(name_or_path: str | Path) -> str:
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        if not path.is_file():
            raise ValueError(f"scenario {str(name_or_path)!r}: no such file")
        return path.read_text()
    shipped = importlib.resources.files("geojax") / "scenarios" / f"{name_or_path}.toml"
    if str(name_or_path) not in available() and shipped.is_file():
        raise ValueError(f"scenario {str(name_or_path)!r}: a transfer, not station keeping; run it with "
                         f"`geojax transfer {name_or_path}`")
    if str(name_or_path) not in available():
        raise ValueError(
            f"scenario {str(name_or_path)!r}: unknown; named scenarios: {', '.join(available())} "
            "(or give the path of a .toml file)"
        )
    return (importlib.resources.files("geojax") / "scenarios" / f"{name_or_path}.toml").read_text()


def from_dict(raw: dict, controller=None) -> Scenario:
    """Validate a scenario table and build the ``Scenario`` (``controller``: as in ``load``)."""
    config = _validate(raw, controller)
    utc = parse_utc(config["epoch"]["utc"])
    epoch_tt_s = tt_seconds_from_utc(utc)
    tt_minus_ut1_s = TT_MINUS_TAI_S + tai_minus_utc_s(utc.date()) - config["epoch"]["ut1_minus_utc_s"]
    _check_ephemeris_range(utc, config)
    initial_mee = _initial_mee(config, epoch_tt_s, tt_minus_ut1_s)
    return Scenario(config, epoch_tt_s, tt_minus_ut1_s, initial_mee, _force_model(config))


def _validate(raw: dict, controller=None) -> dict:
    config: dict = {}
    unknown_tables = [t for t in raw if t not in SCHEMA and isinstance(raw[t], dict)]
    if unknown_tables:
        tables = ", ".join(t for t in SCHEMA if t)
        raise ValueError(f"{unknown_tables[0]}: unknown table; allowed: {tables}")
    for table, fields in SCHEMA.items():
        given = raw if table == "" else raw.get(table, {})
        if not isinstance(given, dict):
            raise ValueError(f"{table}: must be a table")
        if table == "controller":
            fields = controller_fields(given, controller)
        out = check_table(f"{table}." if table else "", given, fields, ignore=SCHEMA if table == "" else ())
        if table:
            config[table] = out
        else:
            config.update(out)
    _check_orbit(config["orbit"])
    _check_gravity(config["forces"])
    module = None if controller is not None else _lookup(config["controller"]["kind"])
    validate = getattr(module, "validate", None)
    if validate is not None:
        validate(config)
    t = config["thrusters"]
    arm_limits_deg(t["beta_max_deg"], t["beta_min_deg"], t["alpha_max_deg"], t["alpha_min_deg"])
    _check_propellant(config)
    return config


def _check_ephemeris_range(utc, config: dict) -> None:
    """The run (epoch to epoch + duration) within the dates of ``EPHEMERIS_UTC_RANGE`` for its ephemeris."""
    import datetime as dt

    ephemeris, days = config["forces"]["ephemeris"], config["duration"]["days"]
    first, last = (dt.datetime.fromisoformat(d) for d in EPHEMERIS_UTC_RANGE[ephemeris])
    start = utc.astimezone(dt.timezone.utc).replace(tzinfo=None) if utc.tzinfo is not None else utc
    if not first <= start <= start + dt.timedelta(days=days) <= last:
        raise ValueError(f"epoch.utc: a run of {days:g} days from {config['epoch']['utc']} leaves the dates of the "
                         f"{ephemeris} ephemeris, {first.date()} to {last.date()} (forces.ephemeris)")


def _check_gravity(forces: dict) -> None:
    degree, order = forces["gravity_degree"], forces["gravity_order"]
    if order is not None and degree is None:
        raise ValueError(f"forces.gravity_order: needs forces.gravity_degree (got order {order} without a degree)")
    if order is not None and order > degree:
        raise ValueError(f"forces.gravity_order: must be <= forces.gravity_degree = {degree}, got {order}")


def _check_propellant(config: dict) -> None:
    """The propellant (mass less dry mass) must last at least one step of every thruster at full thrust: a run
    that cannot is a typo (an Isp in hours, a mass in tonnes), not a scenario.  Running out later is data
    (status 5, the thrusters stop)."""
    craft, t = config["spacecraft"], config["thrusters"]
    propellant_kg = craft["mass_kg"] - craft["dry_mass_kg"]
    if propellant_kg <= 0:
        raise ValueError(f"spacecraft.dry_mass_kg: must be less than spacecraft.mass_kg = {craft['mass_kg']:g}, "
                         f"got {craft['dry_mass_kg']:g}")
    per_step_kg = t["count"] * t["thrust_n"] * config["integration"]["step_s"] / (t["isp_s"] * c.G0_MPS2)
    if per_step_kg >= propellant_kg:
        raise ValueError(f"thrusters.isp_s: {t['count']} thrusters of {t['thrust_n']:g} N at Isp {t['isp_s']:g} s "
                         f"burn {per_step_kg:.4g} kg in one {config['integration']['step_s']:g} s step, more than the "
                         f"{propellant_kg:.4g} kg of propellant (spacecraft.mass_kg - spacecraft.dry_mass_kg)")


def _lookup(kind):
    from geojax.control import lookup  # the controllers import the parameter types, not the scenarios

    return lookup(kind)


def controller_fields(table, controller=None) -> dict[str, Field]:
    """The fields of a ``[controller]`` table: ``kind`` and those of the controller it names (or of ``controller``)."""
    if controller is not None:
        return {"kind": Field(str, "custom"), **controller.fields}
    kind = table.get("kind", "none") if isinstance(table, dict) else "none"
    return {"kind": Field(str, "none"), **_lookup(kind).FIELDS}


def _check_orbit(orbit: dict) -> None:
    kind = orbit["elements"]
    needed = _ORBIT_KEYS[kind]
    missing = [k for k in needed if orbit[k] is None]
    if missing:
        raise ValueError(f"orbit.{missing[0]}: missing (required when orbit.elements = {kind!r})")
    extra = [k for keys in _ORBIT_KEYS.values() for k in keys if k not in needed and orbit[k] is not None]
    if extra:
        raise ValueError(f"orbit.{extra[0]}: not used when orbit.elements = {kind!r}; give only {', '.join(needed)}")
    if kind == "mee" and math.hypot(orbit["f"], orbit["g"]) >= 1:
        raise ValueError(f"orbit.f, orbit.g: eccentricity sqrt(f^2 + g^2) must be < 1, got {math.hypot(orbit['f'], orbit['g']):g}")


def _initial_mee(config: dict, epoch_tt_s: float, tt_minus_ut1_s: float) -> np.ndarray:
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
    # station_offset: Katz 2025, Sec. 3.1: "a deviation of 2 km in each ECEF
    # axis from the desired station, and the correct velocity of the desired
    # orbit", read as the station's own inertial velocity omega x r_station.
    lon = math.radians(station["lon_deg"])
    radius_m = station["radius_km"] * 1e3
    station_ecef = np.array([radius_m * math.cos(lon), radius_m * math.sin(lon), 0.0])
    angle = earth_rotation_angle_rad(epoch_tt_s, epoch_tt_s, tt_minus_ut1_s)
    r_eci = ecef_to_eci(jnp.asarray(station_ecef + np.array(orbit["offset_ecef_km"]) * 1e3), angle)
    v_eci = jnp.cross(jnp.array([0.0, 0.0, c.OMEGA_EARTH_RAD_S]), ecef_to_eci(jnp.asarray(station_ecef), angle))
    return np.asarray(cartesian_to_mee(r_eci, v_eci, c.MU_EARTH_M3_S2))


def _force_model(config: dict) -> ForceModel:
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


def to_toml(config: dict) -> str:
    """Serialise a validated scenario table back to TOML (for HDF5 ``config_toml``)."""
    lines = [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in config.items() if not isinstance(v, dict)]
    for table, values in config.items():
        if isinstance(values, dict):
            lines.append(f"\n[{_toml_key(table)}]")
            lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in values.items() if v is not None]
    return "\n".join(lines) + "\n"


def _toml_key(key: str) -> str:
    """A bare key where TOML allows one, else quoted (``"thrusters.beta_max_deg"`` is one key, not a path)."""
    return key if key and all(c.isalnum() or c in "_-" for c in key) else _toml_value(key)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)
