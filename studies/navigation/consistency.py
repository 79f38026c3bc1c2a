"""The filter's consistency and what each tracking set-up determines: a Monte Carlo of Li's QFFC satellite.

    python studies/navigation/consistency.py [--samples 64] [--days 365.25] [--out studies/navigation/results]

``li2022-qffc-ranging`` (Li 2022's QFFC satellite, the extended Kalman filter in the loop, every burn flown with
2 % and 0.1 deg execution errors; ``geojax.states.navigation``) flown ``--days`` with ``--samples`` draws under four
tracking set-ups, each 5 m ranging (or its receiver) twice a day for 2 h unless said:

1. **one station**: Xichang's ranging alone;
2. **two stations**: Xichang and New Norcia (the scenario);
3. **ranging + angles**: Xichang's ranging and its antenna's azimuth and elevation (0.01 deg);
4. **GNSS-in-GEO**: an on-board receiver's position fix, 10 m per axis, every step (continuous).

Consistency (Bar-Shalom, Li & Kirubarajan 2001, Sec. 5.4.2): the innovations of a consistent filter are white, so
the NIS summed over every update of every sample is chi^2 with the summed degrees of freedom; its average per
degree of freedom is checked against that distribution's two-sided 95 % interval.  The NEES at the decision times
is correlated from day to day; each sample's time average is checked, as the mean of ``--samples`` independent
values, against the interval of ``--samples`` chi^2(6) values (a time average varies less than one value, so the
interval is wide for it: this is the looser test), and the fraction of decision times at which the ensemble's
average NEES falls inside its own 95 % interval is reported (95 % expected).  Writes ``consistency.md`` and
``consistency.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch
from geojax.runner.setup import cycle_count
from geojax.navigation.ekf import chi2_bounds

HERE = Path(__file__).resolve().parent
XICHANG = {"lat_deg": 28.25, "lon_deg": 102.03, "alt_m": 1800.0, "cadence_s": 43200.0, "pass_s": 7200.0}
NEW_NORCIA = {"lat_deg": -31.05, "lon_deg": 116.19, "alt_m": 250.0, "cadence_s": 43200.0, "pass_s": 7200.0}
SETUPS = {
    "one station": {"navigation.stations": [{**XICHANG, "measurements": ["range"]}]},
    "two stations": {},
    "ranging + angles": {"navigation.stations": [{**XICHANG, "measurements": ["range", "angles"]}]},
    "GNSS-in-GEO": {"navigation.stations": [], "navigation.gnss": {"sigma_m": 10.0}},
}
AXES = ("radial", "along", "cross")


def run(label: str, days: float, samples: int) -> dict:
    sc = scenario.load("li2022-qffc-ranging", {"duration.days": days, **SETUPS[label]})
    begun = time.perf_counter()
    result = simulate_batch([sc] * samples, seeds=np.arange(samples))
    wall_s = time.perf_counter() - begun
    record = result.records.cycles.states["navigation"]
    n_cycles = cycle_count(days)
    nees = np.asarray(record.nees)[:, :n_cycles]  # [samples, cycles]
    nis_sum, nis_dof = float(np.asarray(record.nis_sum).sum()), float(np.asarray(record.nis_dof).sum())
    low, high = chi2_bounds(6, samples)
    per_time = nees.mean(axis=0)
    inside = float(np.mean((per_time >= low) & (per_time <= high)))
    metrics = {k: np.asarray(v, float) for k, v in result.metrics.items()}
    nis_low, nis_high = chi2_bounds(1, int(nis_dof))
    out = {
        "status": [STATUS_MEANINGS[int(s)] for s in result.status],
        "nees_mean": float(metrics["nees_mean"].mean()), "nees_bounds": [low, high],
        "nees_times_inside_fraction": inside,
        "nis_per_dof": nis_sum / nis_dof, "nis_bounds": [nis_low, nis_high], "nis_dof": nis_dof,
        "dv_per_year_mps_mean": float(metrics["dv_per_year_mps"].mean()),
        "max_abs_dlon_deg_max": float(metrics["max_abs_dlon_deg"].max()),
        "nav_position_rms_m": float(np.sqrt(np.mean(metrics["nav_position_rms_m"] ** 2))),
        "measurements_per_day": float(metrics["measurements_used"].mean() / days),
        "wall_s": wall_s,
    }
    for axis in AXES:
        out[f"nav_{axis}_rms_m"] = float(np.sqrt(np.mean(metrics[f"nav_{axis}_rms_m"] ** 2)))
        out[f"nav_{axis}_rms_mps"] = float(np.sqrt(np.mean(metrics[f"nav_{axis}_rms_mps"] ** 2)))
    out["consistent"] = bool(low <= out["nees_mean"] <= high and nis_low <= out["nis_per_dof"] <= nis_high)
    print(label, {k: v for k, v in out.items() if k != "status"}, flush=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    rows = {label: run(label, args.days, args.samples) for label in SETUPS}
    args.out.mkdir(parents=True, exist_ok=True)
    payload = {"samples": args.samples, "days": args.days, "geojax": geojax.__version__, "setups": rows}
    (args.out / "consistency.json").write_text(json.dumps(payload, indent=1))
    lines = [f"# The filter's consistency: {args.samples} samples of li2022-qffc-ranging, {args.days:g} days", "",
             f"`python studies/navigation/consistency.py --samples {args.samples} --days {args.days:g}`; geojax "
             f"{geojax.__version__}. NEES: the samples' time averages, mean, against the 95 % interval of "
             f"{args.samples} chi²(6) values; 'inside' the fraction of decision times whose ensemble average lies "
             "in its interval. NIS: per degree of freedom over every update, against the interval of its summed "
             "degrees of freedom. Errors: RMS over the decision times and samples.", "",
             "| tracking | NEES | 95 % | inside | NIS / dof | 95 % | consistent | R, S, W RMS (m) | "
             "ΔV (m/s/yr) | max abs Δλ (deg) | status |", "|---|---:|---|---:|---:|---|---|---|---:|---:|---|"]
    for label, r in rows.items():
        ok = sum(s == "ok" for s in r["status"])
        lines.append(f"| {label} | {r['nees_mean']:.2f} | {r['nees_bounds'][0]:.2f}–{r['nees_bounds'][1]:.2f} | "
                     f"{r['nees_times_inside_fraction']:.2f} | {r['nis_per_dof']:.3f} | "
                     f"{r['nis_bounds'][0]:.3f}–{r['nis_bounds'][1]:.3f} | {'yes' if r['consistent'] else 'no'} | "
                     f"{r['nav_radial_rms_m']:.1f}, {r['nav_along_rms_m']:.1f}, {r['nav_cross_rms_m']:.1f} | "
                     f"{r['dv_per_year_mps_mean']:.2f} | {r['max_abs_dlon_deg_max']:.4f} | "
                     f"{ok}/{len(r['status'])} ok |")
    (args.out / "consistency.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
