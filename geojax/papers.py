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


# Katz 2025, Table 1 and Secs. 3.1-3.3, per thrust mode: the yearly Delta-V and excursions at the gains the
# paper's fmincon tuning found ("+-" excursions as the paper states them), and those gains in its units.
KATZ2025 = {
    "continuous": {"dv_per_year_mps": "62.795", "dlon_half_range_deg": "0.0083", "dlat_half_range_deg": "0.047",
                   "k_h_per_km2_s": "9.3926e-16", "k_e_km2_per_s3": "5.48482e-6"},
    "discrete": {"dv_per_year_mps": "55.55", "dlon_half_range_deg": "0.0176", "dlat_half_range_deg": "0.0436",
                 "duty_x": "0", "duty_y": "0.115", "duty_z": "0.466",
                 "k_h_per_km2_s": "1.6407e-15", "k_e_km2_per_s3": "6.8936e-6"},
    "constant": {"dv_per_year_mps": "56.088", "dlon_half_range_deg": "0.0437", "dlat_half_range_deg": "0.0288",
                 "duty_x": "0.467", "duty_y": "0.467", "duty_z": "0.467",
                 "k_h_per_km2_s": "2.7147e-15", "k_e_km2_per_s3": "1.043e-5"},
}


# What a shipped scenario that sets a paper's numbers beside its own adds to that paper's run (the summary prints
# it under the table): the paper's numbers are for the run without it.
DIFFERS_FROM_PAPER = {
    "li2022-qffc-ranging": ("Li 2022's numbers are for its Gaussian orbit and attitude fix (eqs. (47)-(48)); this "
                            "run determines the orbit with an extended Kalman filter on two-way ranging from two "
                            "ground stations (5 m, a 2 h pass every 12 h) and flies every burn with execution "
                            "errors (2 % in magnitude, 0.1 deg in pointing), which the paper does not model"),
    "li2022-momentum": ("Li 2022's numbers are for the QFFC without attitude; this run adds reaction wheels, a 0.1 m "
                        "offset of the solar-pressure centre and dumping their momentum by tilting the arms up to "
                        "5 deg, the combined problem the paper's Sec. 6 leaves as its next step"),
}


def paper_run(scenario_name: str, config: dict) -> str | None:
    """The shipped scenario of the paper's own run whose numbers ``published`` gives (li2022-qffc for
    li2022-qffc-ranging), or None where no paper reports the run."""
    if scenario_name.startswith("li2022") and config["controller"].get("kind") in LI2022:
        return f"li2022-{config['controller']['kind']}"
    if scenario_name.startswith("katz2025") and config["controller"].get("thrust_mode") in KATZ2025:
        return f"katz2025-{config['controller']['thrust_mode']}"
    return None


def published(scenario_name: str, config: dict) -> tuple[dict, str]:
    """The published numbers of a shipped scenario's run by metric name, and their source ("Li 2022"), or
    ({}, "") for a run no paper reports."""
    if scenario_name.startswith("katz2025"):
        return KATZ2025.get(config["controller"].get("thrust_mode"), {}), "Katz 2025"
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
