"""A validated scenario table written back as TOML text (``to_toml``: the ``config_toml`` a results file keeps)."""

from __future__ import annotations


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
    if isinstance(value, dict):  # a sub-table inside a table (``[[navigation.stations]]``): an inline table
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items() if v is not None) + "}"
    return repr(value)
