"""What a station's ranging bias does to the filter, the orbit it determines and the Delta-V, unestimated and
estimated.

    python studies/navigation/bias_estimation.py [--samples 16] [--days 365.25] [--out studies/navigation/results]

``li2022-qffc-ranging`` (Li 2022's QFFC satellite, the extended Kalman filter on two stations' 5 m ranging twice a
day, burns flown with 2 % and 0.1 deg execution errors; ``geojax.states.navigation``) flown ``--days`` with
``--samples`` draws, both stations' ranges biased by a constant drawn per sample with sigma_b = 0, 10, 20, 50 m
(``navigation.stations[i].range_bias_sigma_m``), the filter unaware of the biases and estimating them
(``navigation.estimate_biases``), on the same draws.  Per case: the NEES averaged per sample, their mean against
the 95 % interval of ``--samples`` chi^2(6) values, the NIS per degree of freedom over every update against its
own, the position error RMS per axis, the Delta-V and the box; where estimated, the biases' error at the last
decision time in the filter's own sigmas (RMS over the samples and both stations) and that sigma.  Writes
``bias_estimation.md`` and ``.json`` into ``--out``.
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
BIAS_SIGMAS_M = (0.0, 10.0, 20.0, 50.0)
AXES = ("radial", "along", "cross")


def run(estimated: bool, days: float, samples: int) -> list[dict]:
    """One compiled batch: every bias sigma x ``samples`` draws, the biases estimated or not."""
    scenarios = [scenario.load("li2022-qffc-ranging", {
        "duration.days": days, "navigation.estimate_biases": estimated,
        **{f"navigation.stations[{i}].range_bias_sigma_m": sigma for i in range(2)}})
        for sigma in BIAS_SIGMAS_M for _ in range(samples)]
    begun = time.perf_counter()
    result = simulate_batch(scenarios, seeds=np.tile(np.arange(samples), len(BIAS_SIGMAS_M)))
    wall_s = time.perf_counter() - begun
    record = result.records.cycles.states["navigation"]
    metrics = {k: np.asarray(v, float).reshape(len(BIAS_SIGMAS_M), samples) for k, v in result.metrics.items()}
    status = np.asarray(result.status).reshape(len(BIAS_SIGMAS_M), samples)
    nis_sum = np.asarray(record.nis_sum).reshape(len(BIAS_SIGMAS_M), samples, -1).sum(axis=(1, 2))
    nis_dof = np.asarray(record.nis_dof).reshape(len(BIAS_SIGMAS_M), samples, -1).sum(axis=(1, 2))
    last = cycle_count(days) - 1
    rows = []
    for k, sigma_b in enumerate(BIAS_SIGMAS_M):
        low, high = chi2_bounds(6, samples)
        nis_low, nis_high = chi2_bounds(1, int(nis_dof[k]))
        row = {"bias_sigma_m": sigma_b, "estimated": estimated,
               "status": [STATUS_MEANINGS[int(s)] for s in status[k]],
               "nees_mean": float(metrics["nees_mean"][k].mean()), "nees_bounds": [low, high],
               "nis_per_dof": float(nis_sum[k] / nis_dof[k]), "nis_bounds": [nis_low, nis_high],
               "dv_per_year_mps_mean": float(metrics["dv_per_year_mps"][k].mean()),
               "max_abs_dlon_deg_max": float(metrics["max_abs_dlon_deg"][k].max()),
               "wall_s_of_the_batch": wall_s}
        for axis in AXES:
            row[f"nav_{axis}_rms_m"] = float(np.sqrt(np.mean(metrics[f"nav_{axis}_rms_m"][k] ** 2)))
        row["consistent"] = bool(low <= row["nees_mean"] <= high and nis_low <= row["nis_per_dof"] <= nis_high)
        if estimated:
            error = np.asarray(record.bias_error).reshape(len(BIAS_SIGMAS_M), samples, -1, 2)[k, :, last]
            sigma = np.asarray(record.bias_sigma).reshape(len(BIAS_SIGMAS_M), samples, -1, 2)[k, :, last]
            row["bias_sigma_last_m"] = float(np.sqrt(np.mean(sigma**2)))
            row["bias_error_rms_in_sigmas"] = (float(np.sqrt(np.mean((error / sigma) ** 2))) if sigma_b > 0
                                               else None)
        rows.append(row)
        print({k: v for k, v in row.items() if k != "status"}, flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    rows = run(False, args.days, args.samples) + run(True, args.days, args.samples)
    args.out.mkdir(parents=True, exist_ok=True)
    payload = {"samples": args.samples, "days": args.days, "geojax": geojax.__version__, "cases": rows}
    (args.out / "bias_estimation.json").write_text(json.dumps(payload, indent=1))
    lines = [f"# Ranging biases, unestimated and estimated: {args.samples} samples of li2022-qffc-ranging, "
             f"{args.days:g} days", "",
             f"`python studies/navigation/bias_estimation.py --samples {args.samples} --days {args.days:g}`; geojax "
             f"{geojax.__version__}. Both stations' ranges biased by a constant drawn per sample (sigma_b), the same "
             "draws in every row. NEES: the samples' time averages, mean, against the 95 % interval of "
             f"{args.samples} chi²(6) values; NIS per degree of freedom over every update against its own; errors: "
             "RMS over the decision times and samples; the biases' error at the last decision time in the "
             "filter's sigmas (RMS over samples and stations; 1 for a consistent filter).", "",
             "| sigma_b (m) | biases estimated | NEES | 95 % | NIS / dof | consistent | R, S, W RMS (m) | "
             "ΔV (m/s/yr) | max abs Δλ (deg) | status | bias sigma at the end (m) | bias error / sigma |",
             "|---:|---|---:|---|---:|---|---|---:|---:|---|---:|---:|"]
    for r in rows:
        ok = sum(s == "ok" for s in r["status"])
        ratio = r.get("bias_error_rms_in_sigmas")
        tail = (f"{r['bias_sigma_last_m']:.2f} | {'–' if ratio is None else f'{ratio:.2f}'}" if r["estimated"]
                else "– | –")
        lines.append(f"| {r['bias_sigma_m']:g} | {'yes' if r['estimated'] else 'no'} | {r['nees_mean']:.2f} | "
                     f"{r['nees_bounds'][0]:.2f}–{r['nees_bounds'][1]:.2f} | {r['nis_per_dof']:.3f} | "
                     f"{'yes' if r['consistent'] else 'no'} | {r['nav_radial_rms_m']:.1f}, {r['nav_along_rms_m']:.1f}, "
                     f"{r['nav_cross_rms_m']:.1f} | {r['dv_per_year_mps_mean']:.2f} | "
                     f"{r['max_abs_dlon_deg_max']:.4f} | {ok}/{len(r['status'])} ok | {tail} |")
    (args.out / "bias_estimation.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
