"""Several satellites in one slot, in one scenario file: the ``[[satellites]]`` tables (each a ``name`` and
dotted overrides of the scenario's keys, as a sweep's ``[set]`` takes them) and the ``[collocation]`` table.

Every satellite is a full scenario, the file's keys with its own overrides; the cluster shares the epoch, the
integration grid, the duration and the force model's environment, so those keys are refused as overrides, and
so is every key that sets the compiled program (the controller's kind and its static settings: one program
flies every satellite).
"""

from __future__ import annotations

import re

from geojax.params import NUMBER, Field, check_table

FIELDS = {
    "alert_km": Field(NUMBER, 2.0, lower=0.0,
                      doc="the distance below which a pair's time counts as an alert (below_alert_h), km"),
    "coordinated": Field(bool, False, doc="plan the cluster's satellites in one program that keeps them "
                                          "min_separation_km apart (the MPC only: control.mpc_cluster)"),
    "min_separation_km": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True,
                               doc="the least distance a coordinated plan keeps between every pair over its "
                                   "horizon (linearised relative motion), km; 0: none"),
}
# The controllers that plan a cluster as one program (``collocation.coordinated``).
COORDINATED_KINDS = ("mpc",)

# Tables whose keys every satellite of a cluster shares: one grid, one environment, one duration.
SHARED_TABLES = ("epoch", "integration", "duration", "forces")
NAME = re.compile(r"[A-Za-z0-9_]+")


def member_overrides(satellites, collocation) -> tuple[list[tuple[str, dict]], dict]:
    """The validated ``[[satellites]]`` (``satellites``: the file's list of tables) as (name, overrides) each, and
    the validated ``[collocation]`` table; ``ValueError`` naming the key for a cluster of one, a name given twice
    or not a plain word, or an override of a shared key."""
    if not isinstance(satellites, list) or not all(isinstance(s, dict) for s in satellites):
        raise ValueError("satellites: must be an array of tables ([[satellites]]), each with a name")
    if len(satellites) < 2:
        raise ValueError(f"satellites: a cluster needs at least two [[satellites]], got {len(satellites)}; for one "
                         f"satellite leave [[satellites]] out")
    members, seen = [], set()
    for i, table in enumerate(satellites):
        name = table.get("name")
        if not isinstance(name, str) or not NAME.fullmatch(name):
            raise ValueError(f"satellites[{i}].name: must be letters, digits or _, got {name!r}")
        if name in seen:
            raise ValueError(f"satellites[{i}].name: {name!r} is given twice; every satellite needs its own name")
        seen.add(name)
        overrides = {k: v for k, v in table.items() if k != "name"}
        for key in overrides:
            table_name = str(key).split(".")[0]
            if table_name in SHARED_TABLES or key in ("description", "controller.kind", "controller.recovery"):
                raise ValueError(f"satellites[{i}].{key}: shared by every satellite of the cluster (the epoch, the "
                                 f"integration grid, the duration, the force model and the controller's kind); set "
                                 f"it once, outside [[satellites]]")
            if "." not in str(key):
                raise ValueError(f"satellites[{i}].{key}: not a scenario key; give TABLE.KEY, quoted (e.g. "
                                 f"\"station.ex\" = 2.0e-4)")
        members.append((name, overrides))
    table = check_table("collocation.", collocation or {}, FIELDS)
    if "min_separation_km" in (collocation or {}) and not table["coordinated"]:
        raise ValueError("collocation.min_separation_km: only a coordinated cluster keeps it; set "
                         "collocation.coordinated = true (the MPC)")
    return members, table


def check_coordinated(table: dict, kind: str) -> None:
    """``ValueError`` naming ``collocation.coordinated`` where it asks a controller that plans each satellite
    alone."""
    if table["coordinated"] and kind not in COORDINATED_KINDS:
        raise ValueError(f"collocation.coordinated: only {', '.join(COORDINATED_KINDS)} plans a cluster as one "
                         f"program; controller.kind is {kind!r}")


def sets_cluster(raw: dict, dotted: str, value) -> bool:
    """Set ``dotted`` in ``raw`` if it is a cluster's key: one satellite's (``satellites.NAME.TABLE.KEY``, its
    override) or the ``[collocation]`` table's (``collocation.KEY``); False for any other key."""
    head, _, rest = dotted.partition(".")
    if head == "collocation":
        raw["collocation"] = {**(raw.get("collocation") or {}), rest: value}
        return True
    if head != "satellites":
        return False
    name, _, key = rest.partition(".")
    items = raw.get("satellites")
    if not isinstance(items, list) or not any(isinstance(s, dict) and s.get("name") == name for s in items):
        known = [s.get("name") for s in items or () if isinstance(s, dict)]
        raise ValueError(f"{dotted}: the scenario has no satellite {name!r} (satellites: {', '.join(map(str, known))})"
                         if known else f"{dotted}: the scenario has no [[satellites]]")
    if "." not in key:
        raise ValueError(f"{dotted}: give satellites.NAME.TABLE.KEY (e.g. satellites.A.station.ex)")
    raw["satellites"] = [{**s, key: value} if s.get("name") == name else s for s in items]
    return True


def with_satellite_prefix(index: int, name: str, err: ValueError) -> ValueError:
    """A satellite's own validation error, named by its place in the file."""
    return ValueError(f"satellites[{index}] ({name}): {err}")
