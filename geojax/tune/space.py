"""The parameter space of a tuning: which scenario keys are tuned, and the unconstrained vector theta they map to.

A tuned key is any scenario key whose ``Field`` declares a ``transform`` (``params.Transform``): the
scenario tables' own (``thrusters.thrust_n``) and those the scenario's controller declares in its
``fields``.  A key is named ``"table.key"`` or by its field's ``alias`` (``"k_h"``), the same in a tuning file
and in Python (``resolve``).  Each key's transform maps its SI leaf to a slice of theta (the natural log of a
positive gain, a scaled offset, three log-weights for thresholds of fixed norm), so the optimisers move in an
unbounded space where a unit step is a sensible change.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from geojax import scenario as scenario_mod
from geojax.control.base import Controller
from geojax import states as parts
from geojax.params import LEAF_TABLES, Field, Params, degrees

# Iterates are kept within this many natural-log units of their start (about 3 decades).
LOG_BOUND = 3 * math.log(10)


class Tuned(NamedTuple):
    """A tuned scenario key: its ``Params`` table, its field and its TOML name."""

    name: str  # "controller.k_h_per_km2_s"
    table: str
    field: Field
    part: str | None = None  # the part whose table it is (its leaves under ``Params.states[part]``); None: the loop's

    def leaves_in(self, params: Params) -> dict:
        """The SI leaves of its table in ``params``."""
        return params.states[self.part] if self.part is not None else getattr(params, self.table)


def fields_of(sc: scenario_mod.Scenario, controller: Controller | None) -> dict[str, dict[str, Field]]:
    """{table: {key: Field}} of the scenario's leaf tables, ``[controller]`` from its controller."""
    fields = {t: scenario_mod.SCHEMA[t] for t in LEAF_TABLES if t != "controller"}
    fields["controller"] = scenario_mod.controller_fields(sc.config["controller"], controller)
    fields.update({p.table: p.fields for p, _ in parts.selected(sc.config) if p.table is not None})
    return fields


def _part_of_table(sc: scenario_mod.Scenario, table: str) -> str | None:
    """The name of the carried part whose table ``table`` is (None: one of the loop's)."""
    return next((model.name for p, model in parts.selected(sc.config) if p.table == table), None)


def tunable(sc: scenario_mod.Scenario, controller: Controller | None) -> list[str]:
    """The keys of ``sc`` a tuning may name ("table.key")."""
    return [f"{t}.{k}" for t, table in fields_of(sc, controller).items() for k, f in table.items()
            if f.transform is not None]


def resolve(sc: scenario_mod.Scenario, controller: Controller | None, names) -> list[str]:
    """``names`` as "table.key", each alias replaced by the key it names (any other name is kept, for
    ``tuned`` to refuse)."""
    aliases = {f.alias: f"{t}.{k}" for t, table in fields_of(sc, controller).items() for k, f in table.items()
               if f.alias is not None}
    return [aliases.get(name, name) for name in names]


def tuned(sc: scenario_mod.Scenario, controller: Controller | None, names) -> list[Tuned]:
    """The declarations of the tuned keys (names or aliases); ``ValueError`` for a key that is not tunable or
    not set."""
    fields = fields_of(sc, controller)
    out = []
    for name in resolve(sc, controller, names):
        table, _, key = name.rpartition(".")
        field = fields.get(table, {}).get(key)
        if field is None or field.transform is None:
            raise ValueError(f"parameters: {name!r} is not tunable here; tunable: {', '.join(tunable(sc, controller))}")
        if sc.config[table].get(key) is None:
            raise ValueError(f"parameters: {name!r} is not set in scenario {sc.name} (it is not used there)")
        out.append(Tuned(name, table, field, _part_of_table(sc, table)))
    return out


def to_theta(params: Params, entries: list[Tuned]) -> np.ndarray:
    """The unconstrained vector of the tuned leaves (each by its declared transform)."""
    parts = []
    for e in entries:
        leaves = {k: np.asarray(v) for k, v in e.leaves_in(params).items()}
        parts.append(np.atleast_1d(e.field.transform.to_theta(leaves[e.field.si], leaves)))
    return np.concatenate(parts).astype(float)


def from_theta(theta, base: Params, entries: list[Tuned]) -> Params:
    """``base`` with the tuned leaves replaced by those of ``theta`` (jax-traceable)."""
    tables = {t: dict(getattr(base, t)) for t in LEAF_TABLES}
    states = {name: dict(leaves) for name, leaves in base.states.items()}
    i = 0
    for e in entries:
        leaves = states[e.part] if e.part is not None else tables[e.table]
        size = int(np.size(leaves[e.field.si]))
        value = e.field.transform.from_theta(theta[i:i + size] if np.ndim(leaves[e.field.si]) else theta[i], leaves)
        leaves[e.field.si] = value
        i += size
    return base._replace(**tables, states=states)


def toml_value(field: Field, leaf):
    """The TOML value of an SI leaf, in the key's own unit (degrees for the angle keys)."""
    leaf = np.asarray(leaf, dtype=float)
    return np.degrees(leaf).tolist() if field.to_si is degrees else field.from_si(leaf)


def reported(params: Params, fields: dict[str, Field]) -> dict[str, float]:
    """Values of a controller's keys (its ``fields``) in their TOML units, for reports (list keys by component:
    ``sigma_km_per_s2`` -> ``sigma_x_km_per_s2`` ...); keys without a leaf or an inverse unit are left out."""
    out = {}
    for key, field in fields.items():
        if field.si is None or field.si not in params.controller:
            continue
        if callable(field.to_si) and field.to_si is not degrees:
            continue
        value = toml_value(field, params.controller[field.si])
        if isinstance(value, list):
            stem, _, unit = key.partition("_km") if "_km" in key else (key, "", "")
            for axis, x in zip("xyz", value):
                out[f"{stem}_{axis}{'_km' + unit if unit else ''}"] = x
        else:
            out[key] = value
    return out


def reported_entries(params: Params, entries: list[Tuned]) -> dict[str, float]:
    """The tuned keys outside ``[controller]`` by their dotted names ("attitude.dump_gain_per_s"), in their TOML
    units (a list key's first component where it has several)."""
    out = {}
    for entry in entries:
        if entry.table != "controller":
            value = toml_value(entry.field, entry.leaves_in(params)[entry.field.si])
            out[entry.name] = value if not isinstance(value, list) else value[0]
    return out


def start_points(spec, center: np.ndarray, entries: list[Tuned], sizes: list[int]) -> np.ndarray:
    """[starts, P]: start 0 at ``center`` (the scenario's values), the rest uniform around it (``spec``'s
    ``spread_decades`` for the keys tuned on a log scale, ``spread_scaled`` for the others)."""
    rng = np.random.default_rng(spec.seed)
    half = np.concatenate([
        [spec.spread_decades * math.log(10) if e.field.transform.name.startswith("log") else spec.spread_scaled] * n
        for e, n in zip(entries, sizes)
    ])
    starts = center + rng.uniform(-1.0, 1.0, (spec.starts, center.size)) * half
    starts[0] = center
    return starts
