"""The published numbers geojax is compared with, each table with its source: one place for the command line's
summaries, the studies and the benchmarks.

Values are strings as the paper prints them ("~0.013" where it gives an order, read off a figure); a
study that computes with one takes ``float`` of it.  Keys are geojax's metric names where the number is one of
them (units in the names), so a summary can set a paper's value beside its own by name.
"""

from __future__ import annotations

# Li 2022, Sec. 5.1 and Table 2: one year of li2022 (normal arm limits, no errors) per controller.  The "~"
# values are read off Figs. 2-8; cpu_s_per_orbit is the paper's Fortran on an i7-9700K, one sample.
LI2022 = {
    "qffc": {"dv_per_year_mps": "60.2", "burns_total": "728", "burns_per_thruster_per_orbit": "0.997",
             "max_abs_mean_dlon_deg": "~0.013", "max_abs_de": "~1.1e-4", "cpu_s_per_orbit": "0.09"},
    "fompc": {"dv_per_year_mps": "54.2", "burns_total": "721", "burns_per_thruster_per_orbit": "0.988",
              "max_abs_mean_dlon_deg": "~0.013", "max_abs_de": "~1.1e-4", "cpu_s_per_orbit": "57.4"},
}

# Ma & Kong 2023, Sec. 4.2 and the conclusions: the gimbaled boom against the quadrilateral layout (savings in
# %, the quadrilateral's time and fuel the base), the boom's thrust efficiency and its joints' largest
# tracking errors.
MA2023 = {"time_saving_percent": "29.7", "fuel_saving_percent": "22.9", "thrust_efficiency": "0.95",
          "j1_track_max_deg": "0.017", "j2_track_max_deg": "0.006", "j3_track_max_deg": "0.011"}

# Ye 2022, Tables 2-3, per example: (Delta-V m/s/yr, keeping accuracy deg, the zones' path, capture as the text
# states it).
YE2022_TABLE3 = {
    1: ("44.04", "0.03", "five → two → normal", "≈ 6 months"),
    2: ("41.48", "0.03", "five → three → normal", "–"),
    3: ("46.89", "0.03", "four → one → normal", "–"),
    4: ("47.82", "0.005", "four → one → normal", "–"),
    5: ("54.93", "0.008", "four → one → normal", "–"),
}

# Gazzino 2016, Sec. 5: the fuel-based plan's propellant over the effect-based one's.
GAZZINO2016 = {"fuel_over_effect_percent": "+81.6"}

# The equilibrium longitudes of a geostationary satellite in the Earth's field (deg E), as issue 33 quotes them
# (Soop, Handbook of Geostationary Orbits, 1994, Sec. 3.4).
SOOP1994_EQUILIBRIA_DEG = {"stable": (75.1, -105.3), "unstable": (-11.5, 161.9)}


def __getattr__(name: str):
    # Katz 2025, Table 1 and Secs. 3.1-3.3 (per thrust mode) lives with the tuning (geojax.tune.PAPER) until
    # the tuning's split moves it here; read through this module meanwhile.
    if name == "KATZ2025":
        from geojax.tune import PAPER

        return PAPER
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def published(scenario_name: str, config: dict) -> tuple[dict, str]:
    """The published numbers of a shipped scenario's run by metric name, and their source ("Li 2022"), or
    ({}, "") for a run no paper reports."""
    if scenario_name.startswith("katz2025"):
        return __getattr__("KATZ2025").get(config["controller"].get("thrust_mode"), {}), "Katz 2025"
    if scenario_name.startswith("li2022"):
        return LI2022.get(config["controller"].get("kind"), {}), "Li 2022"
    return {}, ""


def departures(config: dict, seed: int, shipped: dict | None) -> list[str]:
    """The settings of a run that differ from the paper's run of its shipped scenario (``shipped``: that
    scenario's table, None for a file of one's own), as "duration.days = 20"."""
    if shipped is None:
        return ["the scenario (a file of one's own)"]
    out = [f"{table}.{key} = {value}" for table, values in config.items() if isinstance(values, dict)
           for key, value in values.items() if shipped.get(table, {}).get(key) != value]
    return out + ([f"seed = {seed}"] if seed != 0 else [])
