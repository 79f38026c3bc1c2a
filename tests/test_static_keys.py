"""Whether a key is static is declared once, on its ``Field``: the batch's static check and the compiled
programs' identity are derived from the declarations, so every static key changes the identity.

Independent check: each static field of every table (the loop's and the parts') changed in turn, by a value
built from its declaration alone (another choice, the other truth value, another number), changes what the
batch compares (``STATIC_KEYS``) and, but for the keys whose values reach the programs as arguments, the
programs' identity; the documentation's key table marks each of them.
"""

import copy
import types
from pathlib import Path

from geojax import scenario
from geojax.runner.setup import STATIC_KEYS, program_identity

ROOT = Path(__file__).resolve().parents[1]
ARGUMENTS = ("duration.days", "epoch.utc", "epoch.ut1_minus_utc_s")  # reach the programs as arrays and shapes


def _other(field, value):
    """A value of ``field`` other than ``value`` whose identity differs."""
    if field.choices:
        return next(c for c in field.choices if c != value)
    if field.kind is bool:
        return not value
    if value is None:
        return {} if field.kind is dict else 4
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return value * 2 + 1
    if isinstance(value, str):
        return value.replace("20", "21", 1)
    if isinstance(value, list):
        return [*value, {"measurements": ["range"]}] if field.identity is not tuple else [*value, "mine:PART"]
    if isinstance(value, dict):
        return None
    raise AssertionError(f"no other value for {field!r}")


def test_every_static_field_is_a_static_key_and_changes_the_programs_identity():
    sc = scenario.load("li2022-qffc-ranging")
    declared = {f"{t}.{k}" if t else k for t, fields in scenario.SCHEMA.items() if t != "controller"
                for k, f in fields.items() if f.static}
    assert declared == set(STATIC_KEYS)
    assert {"integration.step_s", "forces.gravity_degree", "forces.ephemeris", "attitude.wheels",
            "navigation.stations"} <= declared
    base = types.SimpleNamespace(config=sc.config)
    for key, value_of in STATIC_KEYS.items():
        table, _, name = key.rpartition(".")
        changed = types.SimpleNamespace(config=copy.deepcopy(sc.config))
        where = changed.config[table] if table else changed.config
        where[name] = _other(scenario.SCHEMA[table][name], where[name])
        assert value_of(changed) != value_of(base), key
        if key not in ARGUMENTS:
            assert program_identity(changed, "loop") != program_identity(base, "loop"), key


def test_the_key_tables_mark_every_static_key():
    page = (ROOT / "docs" / "scenario-keys.md").read_text()
    for key in STATIC_KEYS:
        rows = [line for line in page.splitlines() if line.startswith(f"| `{key}` |")]
        assert any("static" in row for row in rows), key
