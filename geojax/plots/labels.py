"""Axis labels with units: a metric's from ``QUANTITIES``, a scenario or controller key's from its parameter
``Field`` (``label_for``, ``field_of``), and values shown in a power of ten named in the label (``decade``:
``e_x (10⁻⁵)``), so that no axis carries offset text."""

from __future__ import annotations

import contextlib

import numpy as np

from geojax.results import split_unit

# Axis labels (name, unit) of the metrics; a scenario or controller key is labelled by its ``Field`` (``_quantity``).
QUANTITIES = {
    "dv_per_year_mps": ("ΔV per year", "m/s/yr"), "max_abs_dlon_deg": ("max |δλ|", "deg"),
    "max_abs_dlat_deg": ("max |δφ|", "deg"), "max_abs_mean_dlon_deg": ("max |mean δλ|", "deg"),
    "mean_dlon_deg": ("mean δλ", "deg"), "dlon_half_range_deg": ("δλ half-range", "deg"),
    "dlat_half_range_deg": ("δφ half-range", "deg"), "max_abs_de": ("max |δe|", ""), "max_abs_di": ("max |δi|", ""),
    "mass_used_kg": ("propellant used", "kg"), "cycles_without_solution": ("cycles without solution", ""),
}
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def label_for(key: str, controllers=()) -> str:
    """A readable axis label with its unit for a sweep axis, metric or tuned parameter key:
    "thrusters.beta_max_deg" -> "β_max (deg)", "dv_per_year_mps" -> "ΔV per year (m/s/yr)"."""
    return _label(*_quantity(key, controllers))


def field_of(key: str, controllers=()):
    """The ``Field`` that declares a dotted scenario key ("thrusters.beta_max_deg"; a ``controller.`` key from
    the first of ``controllers``, shipped names or import paths, that declares it; of the shipped ones where
    none is named), or None."""
    from geojax.control import REGISTRY, lookup
    from geojax.scenario import SCHEMA

    table, _, name = key.rpartition(".")
    if table != "controller":
        return SCHEMA.get(table, {}).get(name)
    for controller in controllers or REGISTRY:
        with contextlib.suppress(ValueError):
            fields = lookup(controller).SPEC.fields
            if name in fields:
                return fields[name]
    return None


def _quantity(key: str, controllers=()) -> tuple[str, str]:
    """(name, unit) of a key: a metric's from ``QUANTITIES``; a scenario or controller key's from its ``Field``
    (``symbol``, ``unit``) where it declares them; else the key's last dotted part with a unit suffix read as the
    unit ("spacecraft.mass_kg" -> ("mass", "kg")); a compound unit (``_per_``) is left in the name."""
    if key in QUANTITIES:
        return QUANTITIES[key]
    field = field_of(key, controllers) if "." in key else None
    name = key.rsplit(".", 1)[-1]
    stem, unit = ("", "") if "_per_" in name else split_unit(name)  # the results files' units (geojax.results)
    stem = stem or name
    if field is not None and field.unit is not None:  # the unit declared: the name as written, or its symbol
        stem, unit = field.symbol or name, field.unit
    elif field is not None:
        stem = field.symbol or stem
    return stem, unit.replace("^2", "²")


def decade(*arrays) -> int:
    """The power of ten to show ``arrays`` in (as values / 10**power): 0 while their largest finite magnitude is
    between 0.01 and 99,999 (ΔV in m/s/yr, H_rv = 1000 read best as they are), else that magnitude's power of
    ten (1.2e-4 -> -4)."""
    finite = np.concatenate([np.ravel(np.asarray(a, float)) for a in arrays])
    finite = np.abs(finite[np.isfinite(finite)])
    largest = float(np.max(finite, initial=0.0))
    if largest == 0.0:
        return 0
    power = int(np.floor(np.log10(largest)))
    return 0 if -2 <= power <= 4 else power


def _label(name: str, unit: str = "", power: int = 0) -> str:
    """"e_x (10⁻⁵)", "drift (10⁻³ deg/day)", "β_max (deg)", "H_rv"."""
    scale = f"10{str(power).translate(SUPERSCRIPT)}" if power else ""
    inside = " ".join(filter(None, [scale, unit]))
    return f"{name} ({inside})" if inside else name


def _scaled(name: str, unit: str, *arrays):
    """The label and ``arrays`` in the power of ten that suits them (``decade``)."""
    power = decade(*arrays)
    return _label(name, unit, power), [np.asarray(a, float) / 10.0**power for a in arrays]
