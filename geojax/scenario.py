"""Scenarios: TOML files (shipped ones by name, or any path), validated on load.

A scenario file has the tables ``epoch``, ``orbit``, ``station``, ``spacecraft``,
``thrusters``, ``forces``, ``integration`` and ``duration`` (see
``geojax/scenarios/li2022.toml`` for every key, with comments).  Every problem
is reported as a ``ValueError`` whose message names the field and what is
allowed, e.g. ``spacecraft.mass_kg: must be > 0, got -1.0``; the CLI prints that
line and exits with status 2.

The keys and their bounds are declared in ``geojax.scenario_schema``, the initial state and force model a
scenario sets are built by ``geojax.scenario_physics``, and ``geojax.scenario_toml`` writes a table back as TOML.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
import re
from pathlib import Path

import numpy as np

from geojax import nominal_errors, scenario_cluster, scenario_physics
from geojax.physics import constants as c
from geojax.physics.forces import ForceModel
from geojax.physics.frames import earth_rotation_angle_rad
from geojax.params import Field, check_table
from geojax.physics.propulsion import arm_limits_deg
from geojax.physics.time import TT_MINUS_TAI_S, parse_utc, tai_minus_utc_s, tt_seconds_from_utc
from geojax.control.base import ARM_LIMIT_KEYS
from geojax.scenario_schema import EPHEMERIS_UTC_RANGE, ORBIT_KEYS
from geojax.scenario_schema import SCHEMA as CORE_SCHEMA
from geojax.scenario_toml import to_toml
from geojax import states as parts
from geojax.control import recovery

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

# Every table of a scenario: the loop's own (``scenario_schema``), then each registered part's (``geojax.states``).
SCHEMA = {**CORE_SCHEMA, "controller": {**CORE_SCHEMA["controller"], "recovery": recovery.FIELD}, **parts.tables()}

__all__ = ["SCHEMA", "Scenario", "ScenarioFile", "available", "controller_fields", "from_dict", "load", "read_text",
           "read_toml_file", "started_at", "to_toml", "with_overrides"]


@dataclasses.dataclass(frozen=True)
class ScenarioFile:
    """A validated scenario file, station keeping (``Scenario``) or transfer (``transfer.TransferScenario``):
    ``config`` is its full table, defaults filled in; its epoch as TT seconds (``epoch_tt_s``) and the TT - UT1
    offset there (``tt_minus_ut1_s``, s)."""

    config: dict
    epoch_tt_s: float
    tt_minus_ut1_s: float

    @property
    def name(self) -> str:
        return self.config["name"]

    @property
    def step_s(self) -> float:
        return float(self.config["integration"]["step_s"])

    @property
    def days(self) -> float:
        return float(self.config["duration"]["days"])


@dataclasses.dataclass(frozen=True)
class Scenario(ScenarioFile):
    """A validated station-keeping scenario: the file's table and epoch, its initial state and force model."""

    initial_mee: np.ndarray  # [6], ECI of the epoch
    force_model: ForceModel
    # a cluster's satellites (``[[satellites]]``, ``scenario_cluster``), each a full scenario; () for one satellite
    satellites: tuple = ()

    @property
    def mass_kg(self) -> float:
        return float(self.config["spacecraft"]["mass_kg"])

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
    if kind in ("station_offset", "station"):
        return moved
    if kind != "mee":
        raise ValueError(f"orbit.elements: moving a scenario to another epoch needs \"mee\" or \"station_offset\" "
                         f"elements, got {kind!r}")
    angle = lambda sc: float(earth_rotation_angle_rad(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s))  # noqa: E731
    l_rad = math.remainder(float(base.initial_mee[5]) + angle(moved) - angle(base), 2 * math.pi)
    return load(name_or_path, {**(overrides or {}), "epoch.utc": utc, "orbit.L_rad": l_rad}, controller)


def with_overrides(raw: dict, overrides: dict | None) -> dict:
    """``raw`` with dotted keys set (``{"thrusters.thrust_n": 0.3}``); a key must name a table and a field.  One
    element of a list key is set as ``TABLE.KEY[i]`` (``{"attitude.srp_offset_array_m[0]": 0.2}``: the others are
    the file's, or the key's defaults), so that a sweep can vary it as an axis; a key of a sub-table as
    ``TABLE.LIST[i].KEY`` (``{"navigation.stations[0].range_sigma_m": 20.0}``) or ``TABLE.SUB.KEY``
    (``{"navigation.gnss.sigma_m": 5.0}``); a top-level key by its name alone (``{"name": "mine"}``); in a cluster,
    one satellite's key as ``satellites.NAME.TABLE.KEY`` and the ``[collocation]`` table's as ``collocation.KEY``."""
    raw = {k: dict(v) if isinstance(v, dict) else v for k, v in raw.items()}
    for dotted, value in (overrides or {}).items():
        if scenario_cluster.sets_cluster(raw, str(dotted), value):  # satellites.NAME.TABLE.KEY, collocation.KEY
            continue
        table, _, key = str(dotted).rpartition(".")
        if not table and key in SCHEMA[""]:  # a top-level key: the name, the description
            raw[key] = value
            continue
        sub = _SUB_TABLE.fullmatch(table)
        if sub:
            _set_in_sub_table(raw, dotted, sub, key, value)
            continue
        if not table or table not in SCHEMA:
            raise ValueError(f"{dotted}: not a scenario key; write it as TABLE.KEY with a table of "
                             f"{', '.join(t for t in SCHEMA if t)} (e.g. \"duration.days\"), or one of "
                             f"{', '.join(SCHEMA[''])}")
        if not isinstance(raw.setdefault(table, {}), dict):
            raise ValueError(f"{table}: must be a table")
        element = _ELEMENT.fullmatch(key)
        if element:
            key, index = element.group(1), int(element.group(2))
            field = SCHEMA[table].get(key)
            if field is None or field.kind is not list or not field.length:
                raise ValueError(f"{dotted}: {table}.{key} is not a list key of the [{table}] table")
            if index >= field.length:
                raise ValueError(f"{dotted}: {table}.{key} has {field.length} elements (indices 0 to "
                                 f"{field.length - 1})")
            values = list(raw[table].get(key, field.default))
            if len(values) != field.length:
                raise ValueError(f"{table}.{key}: must be a list of {field.length} finite numbers, got {values!r}")
            values[index] = value
            value = values
        raw[table][key] = value
    return raw


_ELEMENT = re.compile(r"(\w+)\[(\d+)\]")
_SUB_TABLE = re.compile(r"(\w+)\.(\w+)(?:\[(\d+)\])?")


def _set_in_sub_table(raw: dict, dotted: str, sub: re.Match, key: str, value) -> None:
    """``raw`` with ``TABLE.SUB[i].KEY`` or ``TABLE.SUB.KEY`` set (the sub-table must exist in the file)."""
    table, name, index = sub.group(1), sub.group(2), sub.group(3)
    if table not in SCHEMA or name not in SCHEMA[table]:
        raise ValueError(f"{dotted}: not a scenario key; {table}.{name} is not a key of a scenario table")
    if not isinstance(raw.setdefault(table, {}), dict):
        raise ValueError(f"{table}: must be a table")
    current = raw[table].get(name)
    if index is None:
        if not isinstance(current, dict):
            raise ValueError(f"{dotted}: the scenario has no [{table}.{name}] table to set {key} in")
        raw[table][name] = {**current, key: value}
        return
    i = int(index)
    if not isinstance(current, list) or i >= len(current) or not isinstance(current[i], dict):
        count = len(current) if isinstance(current, list) else 0
        raise ValueError(f"{dotted}: the scenario has {count} [[{table}.{name}]] table{'s' * (count != 1)}"
                         f" (indices 0 to {count - 1})" if count else
                         f"{dotted}: the scenario has no [[{table}.{name}]] table")
    items = [dict(item) for item in current]
    items[i][key] = value
    raw[table][name] = items


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
    if "satellites" in raw or "collocation" in raw:
        return _cluster(raw, controller)
    config = _validate(raw, controller)
    utc = parse_utc(config["epoch"]["utc"])
    epoch_tt_s = tt_seconds_from_utc(utc)
    tt_minus_ut1_s = TT_MINUS_TAI_S + tai_minus_utc_s(utc.date()) - config["epoch"]["ut1_minus_utc_s"]
    _check_ephemeris_range(utc, config)
    initial_mee = scenario_physics.initial_mee(config, epoch_tt_s, tt_minus_ut1_s)
    return Scenario(config, epoch_tt_s, tt_minus_ut1_s, initial_mee, scenario_physics.force_model(config))


def _cluster(raw: dict, controller=None) -> Scenario:
    """A cluster's scenario: the file's keys as the first satellite would have them without its overrides, and
    every satellite's own (``Scenario.satellites``), each validated as a scenario of its own."""
    raw = dict(raw)
    satellites, collocation = raw.pop("satellites", None), raw.pop("collocation", None)
    if satellites is None:
        raise ValueError("collocation: a table of a cluster; give the satellites as [[satellites]] tables")
    members, table = scenario_cluster.member_overrides(satellites, collocation)
    base = from_dict(raw, controller)
    flown = []
    for i, (name, overrides) in enumerate(members):
        try:
            flown.append(from_dict({**with_overrides(raw, overrides), "name": name}, controller))
        except ValueError as err:
            raise scenario_cluster.with_satellite_prefix(i, name, err) from None
    scenario_cluster.check_coordinated(table, base.config["controller"]["kind"])
    config = {**base.config, "satellites": [dict(s) for s in satellites], "collocation": table}
    return dataclasses.replace(base, config=config, satellites=tuple(flown))


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
    nominal_errors.sigma3(config["errors"])  # a size and its preset agree
    spec = controller.spec if controller is not None else _lookup(config["controller"]["kind"]).SPEC
    if spec.validate is not None:
        spec.validate(config)
    _check_honoured(config, spec)
    parts.validate(config)
    if spec.needs is not None:
        parts.check_needs(config, spec.needs(config))
    t = config["thrusters"]
    arm_limits_deg(t["beta_max_deg"], t["beta_min_deg"], t["alpha_max_deg"], t["alpha_min_deg"])
    _check_propellant(config, spec)
    return config


def _check_honoured(config: dict, spec) -> None:
    """Every key is honoured or refused: ``thrusters.count`` equals the number of thrusters the controller flies
    (its ``Spec.thrusters``; None: not checked), and a key its rollout never reads (``Spec.unread``) keeps its
    default -- the arms' limits excepted where ``thrusters.layout = "arms"``, as ``geojax bound`` then reads them."""
    kind, count = config["controller"]["kind"], config["thrusters"]["count"]
    flown, why = spec.thrusters or (None, "")
    redundant = spec.redundant_thrusters  # e.g. 4: two per arm, one flown per arm
    if count is not None and flown is not None and count not in (flown, redundant):
        also = f" or {redundant} ({spec.redundant_why})" if redundant else ""
        raise ValueError(f"thrusters.count: the {kind} controller flies {flown} thruster{'s' * (flown > 1)} ({why}), "
                         f"got {count}; leave it out or set {flown}{also}")
    for key in spec.unread:
        table, name = key.split(".")
        if key in ARM_LIMIT_KEYS and config["thrusters"]["layout"] == "arms":
            continue
        if config[table][name] != SCHEMA[table][name].default:
            raise ValueError(f"{key}: the {kind} controller does not read it ({why}), got {config[table][name]!r}; "
                             f"leave it out")
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


def _check_propellant(config: dict, spec) -> None:
    """The propellant (mass less dry mass) must last at least one step of every thruster at full thrust: a run
    that cannot is a typo (an Isp in hours, a mass in tonnes), not a scenario.  Running out later is data
    (status 5, the thrusters stop)."""
    craft, t = config["spacecraft"], config["thrusters"]
    propellant_kg = craft["mass_kg"] - craft["dry_mass_kg"]
    if propellant_kg <= 0:
        raise ValueError(f"spacecraft.dry_mass_kg: must be less than spacecraft.mass_kg = {craft['mass_kg']:g}, "
                         f"got {craft['dry_mass_kg']:g}")
    count = t["count"] or (spec.thrusters or (1,))[0]
    per_step_kg = count * t["thrust_n"] * config["integration"]["step_s"] / (t["isp_s"] * c.G0_MPS2)
    if per_step_kg >= propellant_kg:
        raise ValueError(f"thrusters.isp_s: {count} thrusters of {t['thrust_n']:g} N at Isp {t['isp_s']:g} s "
                         f"burn {per_step_kg:.4g} kg in one {config['integration']['step_s']:g} s step, more than the "
                         f"{propellant_kg:.4g} kg of propellant (spacecraft.mass_kg - spacecraft.dry_mass_kg)")


def _lookup(kind):
    from geojax.control import lookup  # the controllers import the parameter types, not the scenarios

    return lookup(kind)


# The ``controller.kind`` of a table validated against a user's ``Controller`` that names no kind of its own.
OWN_KIND = "custom"


def controller_fields(table, controller=None) -> dict[str, Field]:
    """The fields of a ``[controller]`` table: ``kind`` and those of the controller it names (or of ``controller``).

    A table of a user's ``Controller`` (kind ``OWN_KIND``) read without it has ``kind`` alone: its keys are the
    ``Controller``'s, which the caller holds (a controller with no keys, ``fields={}``, has none to add)."""
    if controller is not None:
        return {"kind": Field(str, OWN_KIND), **controller.fields}
    kind = table.get("kind", "none") if isinstance(table, dict) else "none"
    if kind == OWN_KIND:
        return {"kind": Field(str, OWN_KIND)}
    return {**SCHEMA["controller"], **_lookup(kind).SPEC.fields}


def _check_orbit(orbit: dict) -> None:
    kind = orbit["elements"]
    needed = ORBIT_KEYS[kind]
    missing = [k for k in needed if orbit[k] is None]
    if missing:
        raise ValueError(f"orbit.{missing[0]}: missing (required when orbit.elements = {kind!r})")
    extra = [k for keys in ORBIT_KEYS.values() for k in keys if k not in needed and orbit[k] is not None]
    if extra:
        raise ValueError(f"orbit.{extra[0]}: not used when orbit.elements = {kind!r}; give only {', '.join(needed)}")
    if kind == "mee" and math.hypot(orbit["f"], orbit["g"]) >= 1:
        raise ValueError(f"orbit.f, orbit.g: eccentricity sqrt(f^2 + g^2) must be < 1, got {math.hypot(orbit['f'], orbit['g']):g}")
