"""The filter's parameter leaves from a validated ``[navigation]`` table (``leaves_of``, ``layout_of``) and what
the filter reads of them: the stations, the measurement components in order, their noise and bias sigmas, the
initial covariance."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from geojax.navigation.measurements import MODELS
from geojax.navigation.state import Layout
from geojax.navigation.stations import Station, station_from_geodetic


def layout_of(table: dict) -> Layout:
    """The static layout of a validated ``[navigation]`` table."""
    return Layout(tuple(tuple(s["measurements"]) for s in table["stations"]), table["gnss"] is not None,
                  table["filter_forces"], table["estimate_biases"])


def leaves_of(table: dict) -> dict:
    """``Params.navigation``: the SI leaves of a validated ``[navigation]`` table, stations stacked on a leading
    axis (outages padded with empty windows)."""
    stations, gnss = table["stations"], table["gnss"]
    deg = np.pi / 180.0
    out = {
        "snc_mps2_per_rthz": table["snc_mps2_per_rthz"],
        "burn_magnitude_sigma": one_sigma(table["assumed_sigma3_dv_pct"]) / 100.0,
        "burn_pointing_sigma_rad": one_sigma(table["assumed_sigma3_att_deg"]) * deg,
        "initial_sigma_r_m": table["initial_sigma_r_m"],
        "initial_sigma_v_mps": table["initial_sigma_v_mps"],
        "burns_during_passes": float(table["burns_during_passes"]),
        "station_lat_rad": [s["lat_deg"] * deg for s in stations],
        "station_lon_rad": [s["lon_deg"] * deg for s in stations],
        "station_alt_m": [s["alt_m"] for s in stations],
        "station_mask_rad": [s["mask_deg"] * deg for s in stations],
        "range_sigma_m": [s["range_sigma_m"] for s in stations],
        "range_bias_sigma_m": [s["range_bias_sigma_m"] for s in stations],
        "range_rate_sigma_mps": [s["range_rate_sigma_mps"] for s in stations],
        "range_rate_bias_sigma_mps": [s["range_rate_bias_sigma_mps"] for s in stations],
        "angles_sigma_rad": [s["angles_sigma_deg"] * deg for s in stations],
        "angles_bias_sigma_rad": [s["angles_bias_sigma_deg"] * deg for s in stations],
        "station_cadence_s": [s["cadence_s"] for s in stations],
        "station_pass_s": [s["pass_s"] for s in stations],
        "station_phase_s": [s["phase_s"] for s in stations],
        "station_outages_s": _padded([s["outages_s"] for s in stations]),
    }
    if gnss is not None:
        out.update(gnss_sigma_m=gnss["sigma_m"], gnss_bias_sigma_m=gnss["bias_sigma_m"],
                   gnss_cadence_s=gnss["cadence_s"], gnss_pass_s=gnss["pass_s"], gnss_phase_s=gnss["phase_s"],
                   gnss_outages_s=_padded([gnss["outages_s"]])[0])
    return {k: jnp.asarray(v, jnp.float64) for k, v in out.items()}


def one_sigma(sigma3: float) -> float:
    """A 3-sigma size's 1 sigma, to 15 significant digits (0.3 deg is 0.1 deg, not the double below it)."""
    return float(f"{sigma3 / 3:.15g}")


def _padded(windows: list) -> np.ndarray:
    """[n, k, 2] outage windows, each list padded to the longest with empty windows [0, 0)."""
    k = max([len(w) for w in windows], default=0)
    out = np.zeros((len(windows), k, 2))
    for i, w in enumerate(windows):
        if w:
            out[i, : len(w)] = w
    return out


def stations_of(nav: dict) -> Station:
    return station_from_geodetic(nav["station_lat_rad"], nav["station_lon_rad"], nav["station_alt_m"])


def components(layout: Layout) -> list[tuple[int, str]]:
    """(tracker, type) of every measurement, in order (tracker -1: the GNSS receiver)."""
    out = [(i, kind) for i, kinds in enumerate(layout.stations) for kind in kinds]
    return out + ([(-1, "gnss")] if layout.gnss else [])


def sigma_bias(nav: dict, tracker: int, kind: str):
    """(noise, bias sigma) of a measurement type, scalars in its unit."""
    if kind == "gnss":
        return nav["gnss_sigma_m"], nav["gnss_bias_sigma_m"]
    name = {"range": ("range_sigma_m", "range_bias_sigma_m"),
            "range_rate": ("range_rate_sigma_mps", "range_rate_bias_sigma_mps"),
            "angles": ("angles_sigma_rad", "angles_bias_sigma_rad")}[kind]
    return nav[name[0]][tracker], nav[name[1]][tracker]


def bias_sigmas(nav: dict, layout: Layout):
    """[n_components] the 1-sigma of each measurement component's per-sample bias."""
    parts = [jnp.broadcast_to(sigma_bias(nav, t, kind)[1], (MODELS[kind].size,)) for t, kind in components(layout)]
    return jnp.concatenate(parts) if parts else jnp.zeros(0)


def n_biases(layout: Layout) -> int:
    """The biases the filter estimates: every measurement component's where ``layout.biases``, else none."""
    return sum(MODELS[kind].size for _, kind in components(layout)) if layout.biases else 0


def initial_cartesian(nav: dict):
    return jnp.diag(jnp.concatenate([jnp.full(3, nav["initial_sigma_r_m"] ** 2),
                                     jnp.full(3, nav["initial_sigma_v_mps"] ** 2)]))
