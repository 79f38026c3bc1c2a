"""The cost of keeping burns out of the tracking passes (Gazzino 2016's orbit-determination periods).

    python studies/navigation/burns_around_passes.py [--samples 16] [--days 365.25] [--out studies/navigation/results]

Gazzino 2016 plans its manoeuvres around orbit-determination periods, during which the thrusters do not fire.
``li2022-qffc-ranging`` (QFFC, the extended Kalman filter on two stations' ranging; ``geojax.states.navigation``)
flown ``--days`` with ``--samples`` draws, burns allowed during the passes and forbidden
(``navigation.burns_during_passes = false``: no step that starts in a pass fires; the QFFC does not plan around the
windows, its next cycle makes up what was not flown), for passes of 2 h and of 4 h twice a day, on the same draws.
The cost is the Delta-V difference, draw by draw, and the box margin.  Writes ``burns_around_passes.md`` and
``.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.loop.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
PASSES_S = (7200.0, 14400.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    cases = [(pass_s, allowed) for pass_s in PASSES_S for allowed in (True, False)]
    scenarios = [scenario.load("li2022-qffc-ranging", {
        "duration.days": args.days, "navigation.burns_during_passes": allowed,
        "navigation.stations[0].pass_s": pass_s, "navigation.stations[1].pass_s": pass_s}) for pass_s, allowed in cases]
    n = args.samples
    result = simulate_batch([sc for sc in scenarios for _ in range(n)], seeds=np.tile(np.arange(n), len(cases)))
    dv = np.asarray(result.metrics["dv_per_year_mps"]).reshape(len(cases), n)
    dlon = np.asarray(result.metrics["max_abs_dlon_deg"]).reshape(len(cases), n)
    duty = np.asarray(result.metrics["duty_fraction"]).reshape(len(cases), n)
    status = np.asarray(result.status).reshape(len(cases), n)
    rows = []
    for i, (pass_s, allowed) in enumerate(cases):
        base = dv[cases.index((pass_s, True))]
        rows.append({"pass_h": pass_s / 3600.0, "burns_during_passes": allowed,
                     "dv_per_year_mps_mean": float(dv[i].mean()), "dv_per_year_mps_std": float(dv[i].std()),
                     "extra_dv_per_year_mps_mean": float((dv[i] - base).mean()),
                     "extra_dv_per_year_mps_max": float((dv[i] - base).max()),
                     "max_abs_dlon_deg": float(dlon[i].max()), "duty_fraction_mean": float(duty[i].mean()),
                     "ok": int(np.sum(status[i] == 0)), "status": [STATUS_MEANINGS[int(s)] for s in status[i]]})
        print(rows[-1], flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "burns_around_passes.json").write_text(json.dumps(
        {"samples": n, "days": args.days, "geojax": geojax.__version__, "rows": rows}, indent=1))
    lines = [f"# Burns kept out of the tracking passes: QFFC, {n} draws, {args.days:g} days", "",
             f"`python studies/navigation/burns_around_passes.py --samples {n} --days {args.days:g}`; geojax "
             f"{geojax.__version__}. li2022-qffc-ranging (two stations' passes twice a day at the same times); "
             "extra ΔV: against the same draws with burns allowed, mean and largest.", "",
             "| passes | burns in passes | ΔV (m/s/yr) | ± std | extra ΔV mean (m/s/yr) | extra ΔV max | "
             "max abs Δλ (deg) | duty | in the box |", "|---|---|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| 2 × {r['pass_h']:g} h | {'allowed' if r['burns_during_passes'] else 'forbidden'} | "
                     f"{r['dv_per_year_mps_mean']:.3f} | {r['dv_per_year_mps_std']:.3f} | "
                     f"{r['extra_dv_per_year_mps_mean']:.3f} | {r['extra_dv_per_year_mps_max']:.3f} | "
                     f"{r['max_abs_dlon_deg']:.4f} | {r['duty_fraction_mean']:.4f} | {r['ok']}/{n} |")
    (args.out / "burns_around_passes.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
