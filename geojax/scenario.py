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
from typing import Any

import jax.numpy as jnp
import numpy as np

from geojax import constants as c
from geojax.elements import cartesian_to_mee, kepler_to_mee
from geojax.forces import ForceModel
from geojax.frames import ecef_to_eci, earth_rotation_angle_rad
from geojax.propulsion import arm_limits_deg
from geojax.thrust_laws import MODES as THRUST_MODES
from geojax.thrust_laws import check_thresholds
from geojax.time import TT_MINUS_TAI_S, parse_utc, tai_minus_utc_s, tt_seconds_from_utc

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

_NUMBER = (int, float)


@dataclasses.dataclass(frozen=True)
class Field:
    """One allowed key: its type(s), an optional default, an optional open/closed range, allowed choices."""

    kind: type | tuple
    default: Any = None
    lower: float | None = None  # exclusive unless lower_inclusive
    upper: float | None = None  # exclusive
    lower_inclusive: bool = False
    choices: tuple = ()
    length: int | None = None  # for lists of numbers

    def describe(self) -> str:
        if self.choices:
            return "one of " + ", ".join(repr(x) for x in self.choices)
        parts = []
        if self.lower is not None:
            parts.append(f"{'>=' if self.lower_inclusive else '>'} {self.lower:g}")
        if self.upper is not None:
            parts.append(f"< {self.upper:g}")
        return " and ".join(parts)


REQUIRED = object()

SCHEMA: dict[str, dict[str, Field]] = {
    "": {"name": Field(str, REQUIRED), "description": Field(str, "")},
    "epoch": {
        "utc": Field(str, REQUIRED),
        "ut1_minus_utc_s": Field(_NUMBER, 0.0, lower=-0.9, upper=0.9),
    },
    "orbit": {
        "elements": Field(str, REQUIRED, choices=("mee", "kepler", "station_offset")),
        # elements = "mee": Li 2022, eq. (5)
        "p_km": Field(_NUMBER, None, lower=0.0),
        "f": Field(_NUMBER, None), "g": Field(_NUMBER, None),
        "h": Field(_NUMBER, None), "k": Field(_NUMBER, None),
        "L_rad": Field(_NUMBER, None),
        # elements = "kepler"
        "a_km": Field(_NUMBER, None, lower=0.0),
        "e": Field(_NUMBER, None, lower=0.0, upper=1.0, lower_inclusive=True),
        "i_deg": Field(_NUMBER, None, lower=0.0, upper=180.0, lower_inclusive=True),
        "raan_deg": Field(_NUMBER, None), "argp_deg": Field(_NUMBER, None),
        "true_anomaly_deg": Field(_NUMBER, None),
        # elements = "station_offset": at the station, displaced in ECEF, with the station's inertial velocity
        "offset_ecef_km": Field(list, None, length=3),
    },
    "station": {
        "lon_deg": Field(_NUMBER, REQUIRED, lower=-180.0, upper=360.0, lower_inclusive=True),
        "radius_km": Field(_NUMBER, 42164.16, lower=0.0),
        "ex": Field(_NUMBER, 0.0), "ey": Field(_NUMBER, 0.0),
        "ix": Field(_NUMBER, 0.0), "iy": Field(_NUMBER, 0.0),
        "box_half_width_deg": Field(_NUMBER, 0.05, lower=0.0),
    },
    "spacecraft": {
        "mass_kg": Field(_NUMBER, REQUIRED, lower=0.0),
        "srp_area_m2": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True),
        "reflectivity": Field(_NUMBER, 0.0, lower=0.0, upper=1.0 + 1e-12, lower_inclusive=True),
    },
    "thrusters": {
        "count": Field(int, 2, lower=1, lower_inclusive=True),
        "thrust_n": Field(_NUMBER, REQUIRED, lower=0.0),
        "isp_s": Field(_NUMBER, REQUIRED, lower=0.0),
        # Robotic-arm limits, Li 2022 eq. (1); defaults: the "normal" level of Table 1.
        "beta_max_deg": Field(_NUMBER, 70.0),
        "beta_min_deg": Field(_NUMBER, 0.0),
        "alpha_max_deg": Field(_NUMBER, 60.0),
        "alpha_min_deg": Field(_NUMBER, 30.0),
        "min_burn_s": Field(_NUMBER, 30.0, lower=0.0, lower_inclusive=True),
    },
    "controller": {
        "kind": Field(str, "none", choices=("none", "qffc", "fompc", "lyapunov")),
        # Start V_DT from the estimate of Li 2022, eqs. (37)-(39), instead of the drift target.
        "vdt_estimate": Field(bool, False),
        # FOMPC (Li 2022, eqs. (40)-(42)): horizon N <= 10 cycles, Delta i_max in MEE (h, k), penalty P in
        # (m/s)^2 per unit (h, k)^2; simulated annealing with `chains` chains of `iterations` moves.
        "horizon": Field(int, 6, lower=1, upper=11, lower_inclusive=True),
        "di_max": Field(_NUMBER, 8e-5, lower=0.0),
        "penalty": Field(_NUMBER, 1e8, lower=0.0),
        "chains": Field(int, 8, lower=1, upper=1025, lower_inclusive=True),
        "iterations": Field(int, 64, lower=0, upper=100001, lower_inclusive=True),
        # Milankovitch-Lyapunov feedback (Katz 2025, eqs. (1)-(7)), in the paper's units (see
        # geojax/control/lyapunov.py for the reading of each): gains > 0, lambda_b any sign.
        "k_h_per_km2_s": Field(_NUMBER, None, lower=0.0),
        "k_e_km2_per_s3": Field(_NUMBER, None, lower=0.0),
        "k_lambda_km_per_rad": Field(_NUMBER, None, lower=0.0),
        "lambda_b_deg": Field(_NUMBER, None),
        "thrust_mode": Field(str, "continuous-clipped", choices=THRUST_MODES),
        # u0: largest acceleration; default thrusters.thrust_n / spacecraft.mass_kg.
        "u0_km_per_s2": Field(_NUMBER, None, lower=0.0),
        # Discrete thresholds (eq. (6)) along ECEF x, y, z; their norm must be u0.
        "sigma_km_per_s2": Field(list, None, length=3),
    },
    # Li 2022, eqs. (47)-(48): multiples H of the nominal 3-sigma errors (0.3 m, 5e-5 m/s, 0.05 deg).
    "errors": {
        "h_rv": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True),
        "h_att": Field(_NUMBER, 0.0, lower=0.0, lower_inclusive=True),
    },
    "forces": {
        "j2": Field(bool, True),
        "c22_s22": Field(bool, False),
        "sun": Field(bool, True),
        "moon": Field(bool, True),
        "srp": Field(bool, True),
        "shadow": Field(str, "conical", choices=("conical", "none")),
        "srp_pressure_n_m2": Field(_NUMBER, 4.5605e-6, lower=0.0, lower_inclusive=True),
    },
    "integration": {
        "step_s": Field(_NUMBER, 900.0, lower=0.0, upper=c.SIDEREAL_DAY_S + 1.0),
        "dynamics": Field(str, "mee", choices=("mee", "cartesian")),
    },
    "duration": {"days": Field(_NUMBER, 365.25, lower=0.0)},
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
    """Names of the scenarios shipped with geojax."""
    folder = importlib.resources.files("geojax") / "scenarios"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def load(name_or_path: str | Path, overrides: dict | None = None) -> Scenario:
    """Load a shipped scenario by name, or a TOML file by path, and validate it.

    ``overrides`` maps dotted keys to values (``{"duration.days": 30}``) and is
    applied before validation.
    """
    text = read_text(name_or_path)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{name_or_path}: not valid TOML ({err})") from None
    for dotted, value in (overrides or {}).items():
        table, _, key = dotted.rpartition(".")
        raw.setdefault(table, {})[key] = value
    return from_dict(raw)


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
    if str(name_or_path) not in available():
        raise ValueError(
            f"scenario {str(name_or_path)!r}: unknown; named scenarios: {', '.join(available())} "
            "(or give the path of a .toml file)"
        )
    return (importlib.resources.files("geojax") / "scenarios" / f"{name_or_path}.toml").read_text()


def from_dict(raw: dict) -> Scenario:
    """Validate a scenario table and build the ``Scenario``."""
    config = _validate(raw)
    utc = parse_utc(config["epoch"]["utc"])
    epoch_tt_s = tt_seconds_from_utc(utc)
    tt_minus_ut1_s = TT_MINUS_TAI_S + tai_minus_utc_s(utc.date()) - config["epoch"]["ut1_minus_utc_s"]
    initial_mee = _initial_mee(config, epoch_tt_s, tt_minus_ut1_s)
    return Scenario(config, epoch_tt_s, tt_minus_ut1_s, initial_mee, _force_model(config))


def _validate(raw: dict) -> dict:
    config: dict = {}
    unknown_tables = [t for t in raw if t not in SCHEMA and isinstance(raw[t], dict)]
    if unknown_tables:
        tables = ", ".join(t for t in SCHEMA if t)
        raise ValueError(f"{unknown_tables[0]}: unknown table; allowed: {tables}")
    for table, fields in SCHEMA.items():
        given = raw if table == "" else raw.get(table, {})
        if not isinstance(given, dict):
            raise ValueError(f"{table}: must be a table")
        out = check_table(f"{table}." if table else "", given, fields, ignore=SCHEMA if table == "" else ())
        if table:
            config[table] = out
        else:
            config.update(out)
    _check_orbit(config["orbit"])
    if config["controller"]["kind"] == "lyapunov":
        _check_lyapunov(config)
    t = config["thrusters"]
    arm_limits_deg(t["beta_max_deg"], t["beta_min_deg"], t["alpha_max_deg"], t["alpha_min_deg"])
    return config


def check_table(prefix: str, given: dict, fields: dict[str, Field], ignore=()) -> dict:
    """Validate one table against its fields (names reported as ``prefix + key``); defaults filled in."""
    for key in given:
        if key not in fields and key not in ignore:
            raise ValueError(f"{prefix}{key}: unknown key; allowed: {', '.join(fields)}")
    out = {}
    for key, field in fields.items():
        name = f"{prefix}{key}"
        if key not in given:
            if field.default is REQUIRED:
                raise ValueError(f"{name}: missing (required)")
            out[key] = field.default
            continue
        out[key] = _check(name, given[key], field)
    return out


def _check(name: str, value: Any, field: Field) -> Any:
    kinds = field.kind if isinstance(field.kind, tuple) else (field.kind,)
    if isinstance(value, bool) and bool not in kinds:
        raise ValueError(f"{name}: must be {_kind_name(kinds)}, got {value!r}")
    if not isinstance(value, kinds):
        raise ValueError(f"{name}: must be {_kind_name(kinds)}, got {type(value).__name__} {value!r}")
    if field.length is not None:
        if len(value) != field.length or not all(isinstance(x, _NUMBER) and not isinstance(x, bool) for x in value):
            raise ValueError(f"{name}: must be a list of {field.length} numbers, got {value!r}")
        return [float(x) for x in value]
    if field.choices and value not in field.choices:
        raise ValueError(f"{name}: must be {field.describe()}, got {value!r}")
    if isinstance(value, _NUMBER) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise ValueError(f"{name}: must be a finite number, got {value!r}")
        low_bad = field.lower is not None and (value < field.lower or (value == field.lower and not field.lower_inclusive))
        high_bad = field.upper is not None and value >= field.upper
        if low_bad or high_bad:
            raise ValueError(f"{name}: must be {field.describe()}, got {value!r}")
        if float in kinds:
            return float(value)
    return value


def _kind_name(kinds) -> str:
    if float in kinds:
        return "a number"
    names = {int: "an integer", str: "a string", bool: "true or false", list: "a list"}
    return " or ".join(names[k] for k in kinds)


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


LYAPUNOV_GAINS = ("k_h_per_km2_s", "k_e_km2_per_s3", "k_lambda_km_per_rad", "lambda_b_deg")


def _check_lyapunov(config: dict) -> None:
    ctl = config["controller"]
    missing = [k for k in LYAPUNOV_GAINS if ctl[k] is None]
    if missing:
        raise ValueError(f"controller.{missing[0]}: missing (required when controller.kind = 'lyapunov')")
    if ctl["u0_km_per_s2"] is None:
        ctl["u0_km_per_s2"] = config["thrusters"]["thrust_n"] / config["spacecraft"]["mass_kg"] / 1e3
    if ctl["thrust_mode"] == "discrete":
        if ctl["sigma_km_per_s2"] is None:
            raise ValueError("controller.sigma_km_per_s2: missing (required when controller.thrust_mode = 'discrete')")
        check_thresholds(ctl["u0_km_per_s2"], ctl["sigma_km_per_s2"])


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
