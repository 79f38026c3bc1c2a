"""Parameters, declared once (docs/design.md "Parameters are declared once").

A ``Field`` is one key of a scenario table: its TOML type, default and bounds
(checked at load, the only place validation happens), and, for a key that
becomes an array leaf of the engine's ``Params`` pytree, its SI name and unit
conversion and, where it can be tuned, its transform to an unconstrained
variable.  The scenario tables of ``geojax.scenario_schema.SCHEMA`` and each
controller's ``FIELDS`` are made of them, and everything else follows from
them (with a key's ``alias``, ``unit`` and one-line ``doc``, read by the tuner, the figures and the
documentation's key tables, ``docs/hooks.py``): validation, the ``Params`` leaves, the leaf a sweep axis
(``"thrusters.beta_max_deg"``) or a tuned parameter (``"controller.k_h_per_km2_s"``)
names, and the units a tuned value is reported in.

``Params`` is the pytree one sample's rollout reads.  Its leaves are what a
sweep varies and what a gradient flows into; whatever sets the shapes of the
compiled loop (step, duration, dynamics, the FOMPC's annealing size, a thrust
law's kind) is static and lives in the ``Scenario``, not here.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable, NamedTuple

import jax.numpy as jnp
import numpy as np

from geojax.physics.dynamics import SpacecraftState
from geojax.physics.forces import ForceModel

NUMBER = (int, float)
REQUIRED = object()


@dataclasses.dataclass(frozen=True)
class Transform:
    """A map between a leaf value (SI) and the tuner's unconstrained variable: ``to_theta(value, leaves)``
    (numpy) and ``from_theta(theta, leaves)`` (traced by the tuner), ``leaves`` the table's other SI leaves."""

    name: str
    to_theta: Callable
    from_theta: Callable


LOG = Transform("log", lambda value, leaves: np.log(value), lambda theta, leaves: jnp.exp(theta))


def scaled(scale: float, name: str = "scaled") -> Transform:
    """An unbounded leaf, in units of ``scale`` (so a unit step of the tuner is a sensible change)."""
    return Transform(name, lambda value, leaves: np.asarray(value) / scale, lambda theta, leaves: theta * scale)


@dataclasses.dataclass(frozen=True)
class Field:
    """One allowed key of a scenario table (or of a controller's ``[controller]`` table):
    ``Field(kind, default, lower=..., upper=..., si=..., transform=...)``, e.g.
    ``Field(float, 1e-5, lower=0.0, si="k_inc", transform=LOG)`` for a gain that must be > 0, read by the
    controller as ``params.controller["k_inc"]`` and tuned in log space.  ``kind``: the TOML type (``float``,
    ``int``, ``bool``, ``str``, ``list`` or a tuple of them); ``default``: the value when the key is left out
    (``REQUIRED``: it must be given)."""

    kind: type | tuple
    default: Any = None
    # Bounds of a number, checked at load: strict, so ``lower=0.0`` means > 0 (zero refused) unless
    # ``lower_inclusive`` (then >= 0); ``upper`` is always exclusive.  None: unbounded on that side.
    lower: float | None = None
    upper: float | None = None
    lower_inclusive: bool = False
    choices: tuple = ()
    length: int | None = None  # for lists of numbers
    si: str | None = None  # name of the Params leaf (None: not a leaf; read from the config where needed)
    to_si: float | Callable = 1.0  # factor (or function) from the TOML unit to the leaf's SI unit
    transform: Transform | None = None  # how geojax.tune moves it (None: not tunable)
    static: bool = False  # sets the compiled loop's structure: equal across a sweep, never tuned
    # For a static key: what of its value fixes the compiled program (``integration.step_s``: the steps per
    # cycle); None: the value itself.  The static keys and the programs' identity are derived from these alone.
    identity: Callable | None = None
    # How figures and tables name it: a symbol ("β_max"; default: the key without its unit suffix) and the unit
    # of the TOML value ("km²/s³"; default: read from the key's unit suffix, ``_deg`` -> deg; "" for none).
    symbol: str | None = None
    unit: str | None = None
    alias: str | None = None  # a short name a tuning accepts for this key, in a file and in Python alike ("k_h")
    doc: str = ""  # one line: what the key means (the documentation's key tables, ``docs/hooks.py``)

    def identity_of(self, value):
        """What of a static key's validated value fixes the compiled program (hashable)."""
        return self.identity(value) if self.identity is not None else value

    def describe(self) -> str:
        if self.choices:
            return "one of " + ", ".join(repr(x) for x in self.choices)
        parts = []
        if self.lower is not None:
            parts.append(f"{'>=' if self.lower_inclusive else '>'} {self.lower:g}")
        if self.upper is not None:
            parts.append(f"< {self.upper:g}")
        return " and ".join(parts)

    def leaf(self, value):
        """The SI array leaf of a validated TOML value."""
        if callable(self.to_si):
            return jnp.asarray(self.to_si(value))
        if isinstance(value, bool):
            return jnp.asarray(float(value))
        if isinstance(value, int) and self.kind is int:
            return jnp.asarray(value)
        return jnp.asarray(np.asarray(value, dtype=float) * self.to_si) if self.to_si != 1.0 else \
            jnp.asarray(np.asarray(value, dtype=float))

    def from_si(self, leaf):
        """The TOML value of an SI leaf (reports, tuned scenario files); ``to_si`` factors only."""
        if callable(self.to_si):
            raise ValueError(f"{self.si}: no inverse unit conversion declared")
        value = np.asarray(leaf, dtype=float) / self.to_si
        return value.tolist() if value.ndim else float(value)


def degrees(value):
    return np.deg2rad(float(value))


class Params(NamedTuple):
    """One sample's parameters: every leaf is an array (vmapped over by a sweep, differentiated by a tuning).

    The table dicts hold the SI leaves declared by ``Field.si`` (``thrusters["beta_max_rad"]``,
    ``station["lon_rad"]``, ``errors["sigma3_r_m"]``, ``controller["k_h_per_m2_s"]``).
    """

    initial: SpacecraftState  # the initial state, in the scenario's orbit representation
    forces: ForceModel  # switches and coefficients (SRP area, reflectivity, ...)
    spacecraft: dict
    thrusters: dict
    station: dict
    errors: dict
    controller: dict
    # {part name: its leaves} of each part the loop carries (``geojax.states``: ``"wheels"``, ``"navigation"``, a
    # user's own), declared by the part; a part that is absent has no entry, so no leaf.
    states: dict = {}


# The loop's own tables of leaves (the parts' are under ``Params.states``).
LEAF_TABLES = ("spacecraft", "thrusters", "station", "errors", "controller")


def table_leaves(config_table: dict, fields: dict[str, Field]) -> dict:
    """The SI leaves of one validated table (keys with ``si``; unset optional keys are left out)."""
    return {f.si: f.leaf(config_table[key]) for key, f in fields.items()
            if f.si is not None and config_table.get(key) is not None}


def static_settings(config_table: dict, fields: dict[str, Field]) -> dict:
    """The static keys of one validated table."""
    return {key: config_table[key] for key, f in fields.items() if f.static}


def station_target(station: dict) -> jnp.ndarray:
    """[6] (lon rad, drift rad/s, e_x, e_y, i_x, i_y): the station's mean-element target, Li 2022 eq. (10)."""
    zero = jnp.zeros_like(station["lon_rad"])
    return jnp.stack([station["lon_rad"], zero, station["ex"], station["ey"], station["ix"], station["iy"]])


def check_table(prefix: str, given: dict, fields: dict[str, Field], ignore=()) -> dict:
    """Validate one table against its fields (names reported as ``prefix + key``); defaults filled in."""
    if not isinstance(given, dict):
        raise ValueError(f"{prefix.rstrip('.') or 'file'}: must be a table, got {type(given).__name__} {given!r}")
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
        out[key] = check_value(name, given[key], field)
    return out


# No quantity of geojax is this large in its unit (gains are 1e-15 to 1e8): a larger number is a typo.
MAX_MAGNITUDE = 1e20


def check_value(name: str, value: Any, field: Field) -> Any:
    kinds = field.kind if isinstance(field.kind, tuple) else (field.kind,)
    if isinstance(value, bool) and bool not in kinds:
        raise ValueError(f"{name}: must be {_kind_name(kinds)}, got {value!r}")
    if isinstance(value, float) and int in kinds and float not in kinds and value.is_integer():
        value = int(value)  # 6.0 from a list of numbers is the integer 6; 2.5 is refused below
    if not isinstance(value, kinds):
        raise ValueError(f"{name}: must be {_kind_name(kinds)}, got {type(value).__name__} {value!r}")
    if field.length is not None:
        if len(value) != field.length or not all(isinstance(x, NUMBER) and not isinstance(x, bool)
                                                 and math.isfinite(x) for x in value):
            raise ValueError(f"{name}: must be a list of {field.length} finite numbers, got {value!r}")
        return [float(x) for x in value]
    if field.choices and value not in field.choices:
        raise ValueError(f"{name}: must be {field.describe()}, got {value!r}")
    if isinstance(value, NUMBER) and not isinstance(value, bool):
        if not math.isfinite(value) or abs(value) > MAX_MAGNITUDE:
            raise ValueError(f"{name}: must be a finite number of magnitude at most {MAX_MAGNITUDE:g}, got {value!r}")
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
    names = {int: "an integer", str: "a string", bool: "true or false", list: "a list", dict: "a table"}
    return " or ".join(names[k] for k in kinds)
