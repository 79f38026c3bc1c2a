"""The parts the closed loop carries beyond the orbit and the mass, one module each on the protocol of
``states.base`` (a ``StateModel`` and the ``Part`` that declares its keys, leaves, validation, statuses and
descriptions).  ``REGISTRY`` lists the shipped parts, one line each; everything else here is derived from it:
the parts' scenario tables, the models a scenario turns on, their ``Params`` leaves and the status codes."""

from __future__ import annotations

import importlib

from geojax.params import table_leaves
from geojax.states import faults, momentum, navigation, wear
from geojax.states.base import QUANTITIES, Part, StateModel, part_of

REGISTRY: tuple[Part, ...] = (
    momentum.PART,  # the reaction wheels' momentum ([attitude] wheels = true)
    navigation.PART,  # the orbit-determination filter ([navigation] model = "ekf")
    wear.PART,  # the thrusters' firing hours and starts ([wear] enabled = true)
    faults.PART,  # burns lost, a thruster out, thrust degraded ([faults]: any key)
)
# The loop's own status codes; the parts' follow in the registry's order, then a user's own parts' in theirs.
CORE_STATUSES = ("ok", "cycles without a solution", "left the longitude box", "left the latitude box",
                 "non-finite or non-physical state", "propellant exhausted")


def tables() -> dict:
    """{table: {key: Field}} of the registered parts' scenario tables, in the registry's order."""
    return {p.table: p.fields for p in REGISTRY if p.table is not None}


def status_meanings(extra: tuple = ()) -> tuple[str, ...]:
    """The meaning of every status code: the loop's, the registered parts', then those of ``extra`` (a user's own
    parts, ``StateModel`` s or ``Part`` s) not among them."""
    out = list(CORE_STATUSES)
    for p in (*REGISTRY, *(part_of(e) for e in extra)):
        out.extend(s for s in p.statuses if s not in out)
    return tuple(out)


def descriptions() -> dict:
    """{metric or column name: description} the registered parts declare."""
    return {k: v for p in REGISTRY for k, v in p.descriptions.items()}


def imported(path: str):
    """The ``StateModel`` or ``Part`` a scenario names by its import path (``"package.module:NAME"``);
    ``ValueError`` naming the path where it cannot be imported or is neither."""
    module, _, name = path.partition(":") if isinstance(path, str) else ("", "", "")
    if not module or not name:
        raise ValueError(f"states: {path!r} is not an import path 'package.module:NAME'")
    try:
        entry = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as err:
        raise ValueError(f"states: cannot import {path!r} ({err})") from None
    try:
        part_of(entry)
    except TypeError:
        raise ValueError(f"states: {path!r} is a {type(entry).__name__}, not a geojax.StateModel or Part") from None
    return entry


def named(config: dict) -> tuple:
    """The parts of one's own a scenario names (its top-level ``states``), imported."""
    return tuple(imported(path) for path in config.get("states", ()))


def selected(config: dict, extra: tuple = ()) -> tuple[tuple[Part, StateModel], ...]:
    """(part, model) of every part a validated scenario turns on, in the registry's order, then the parts of
    one's own it names (``states = ["package.module:NAME"]``) and ``extra`` (given in Python: ``StateModel`` s or
    ``Part`` s), always on.  Static: they shape the compiled loop."""
    extra = (*named(config), *extra)
    out = []
    for p in REGISTRY:
        model = p.select(config[p.table]) if p.select is not None else p.model
        if model is not None:
            out.append((p, model))
    for entry in extra:
        p = part_of(entry)
        model = p.model if p.select is None else p.select(config.get(p.table, {}))
        if model is not None:
            out.append((p, model))
    return tuple(out)


def told(config: dict, extra: tuple = ()) -> set[str]:
    """The quantities (``states.base.QUANTITIES``) the parts a validated scenario turns on tell the controller."""
    out = set()
    for p, _ in selected(config, extra):
        if p.tells is not None:
            out.update(p.tells(config.get(p.table, {}) if p.table is not None else {}))
    return out


def check_needs(config: dict, needs: dict) -> None:
    """``ValueError`` where the controller plans with a quantity (``needs``: {quantity: why}, its ``Spec.needs``)
    that no part of the scenario tells, saying what turns on a part that does."""
    have = told(config)
    for quantity, why in needs.items():
        if quantity not in have:
            how = [p.tells_how[quantity] for p in REGISTRY if quantity in p.tells_how]
            raise ValueError(f"{why}, so it needs {QUANTITIES.get(quantity, quantity)} ({quantity!r}), which no part "
                             f"of this scenario tells" + (f": set {' or '.join(how)}" if how else ""))


def of_config(config: dict, extra: tuple = ()) -> tuple[StateModel, ...]:
    """The models a validated scenario asks for (``selected``)."""
    return tuple(model for _, model in selected(config, extra))


def leaves_of(config: dict, extra: tuple = ()) -> dict:
    """``Params.states``: {model name: its SI leaves} of every part the scenario turns on (a part without a table
    or leaves: none)."""
    out = {}
    for p, model in selected(config, extra):
        table = config.get(p.table, {}) if p.table is not None else {}
        if p.leaves is not None:
            out[model.name] = p.leaves(table)
        else:
            out[model.name] = table_leaves(table, p.fields) if p.table is not None else {}
    return out


def validate(config: dict) -> None:
    """Each registered part's checks across a validated scenario (in place: a part may complete its table): where
    its ``switch`` is off, every other key of its table keeps its default; then its own ``validate``; the parts
    of one's own the scenario names are imported (one line naming a path that is not one)."""
    named(config)
    for p in REGISTRY:
        table = config.get(p.table, {})
        if p.switch is not None and not table[p.switch]:
            for key, field in p.fields.items():
                if key != p.switch and table[key] != field.default:
                    raise ValueError(f"{p.table}.{key}: read only where {p.table}.{p.switch} = true, got "
                                     f"{table[key]!r}; set {p.table}.{p.switch} = true or leave it out")
        if p.validate is not None:
            table = p.validate(config)
            if table is not None:
                config[p.table] = table


def parts_of(models: tuple, extra: tuple = ()) -> tuple[Part, ...]:
    """The ``Part`` of each model the loop carries: a user's own given in ``extra`` (``Part`` s or ``StateModel`` s),
    else a registered part, by its name, else the model's defaults."""
    known = {p.name: p for p in REGISTRY}
    known.update({part_of(e).name: part_of(e) for e in extra})
    return tuple(known.get(m.name, part_of(m)) for m in models)


__all__ = ["CORE_STATUSES", "Part", "REGISTRY", "StateModel", "descriptions", "leaves_of", "of_config", "parts_of",
           "selected", "status_meanings", "tables", "validate"]
