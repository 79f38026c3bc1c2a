"""The cost of keeping burns out of the tracking passes (Gazzino 2016's orbit-determination periods).

    python studies/navigation/burns_around_passes.py [--controller qffc|fompc] [--samples 16] [--days 365.25]
                                                     [--out studies/navigation/results]

Gazzino 2016 plans its manoeuvres around orbit-determination periods, during which the thrusters do not fire.
``li2022-qffc-ranging`` (QFFC, the extended Kalman filter on two stations' ranging; ``geojax.states.navigation``)
flown ``--days`` with ``--samples`` draws, burns allowed during the passes, forbidden
(``navigation.burns_during_passes = false``: no step that starts in a pass fires), and forbidden with the QFFC
planning around them (``controller.around_passes = true``: both burn nodes moved off eq. (31)'s by the least shift
that clears the passes, ``geojax.control.around_passes``); without the planner the QFFC does not know the
windows and its next cycle makes up what was not flown.  Passes of 2 h and of 4 h twice a day, on the same draws.
The cost is the Delta-V difference, draw by draw, and the box margin.  ``--controller fompc``: the same with the
FOMPC (its flown cycle planned around the passes).  Writes ``burns_around_passes.md`` and ``.json`` into ``--out``
(the FOMPC's: ``burns_around_passes_fompc``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
PASSES_S = (7200.0, 14400.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--controller", choices=("qffc", "fompc"), default="qffc")
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    n = args.samples
    # (pass length, burns allowed in passes, the QFFC plans around them); the planner is its own compiled program
    groups = [[(pass_s, allowed, False) for pass_s in PASSES_S for allowed in (True, False)],
              [(pass_s, False, True) for pass_s in PASSES_S]]
    cases, metrics = [], {"dv_per_year_mps": [], "max_abs_dlon_deg": [], "duty_fraction": [], "status": []}
    for group in groups:
        scenarios = [scenario.load("li2022-qffc-ranging", {
            "duration.days": args.days, "navigation.burns_during_passes": allowed, "controller.around_passes": around,
            "controller.kind": args.controller,
            "navigation.stations[0].pass_s": pass_s, "navigation.stations[1].pass_s": pass_s})
            for pass_s, allowed, around in group]
        result = simulate_batch([sc for sc in scenarios for _ in range(n)], seeds=np.tile(np.arange(n), len(group)))
        for key in ("dv_per_year_mps", "max_abs_dlon_deg", "duty_fraction"):
            metrics[key].append(np.asarray(result.metrics[key]).reshape(len(group), n))
        metrics["status"].append(np.asarray(result.status).reshape(len(group), n))
        cases += group
    dv, dlon, duty, status = (np.concatenate(metrics[k]) for k in ("dv_per_year_mps", "max_abs_dlon_deg",
                                                                   "duty_fraction", "status"))
    rows = []
    for i, (pass_s, allowed, around) in enumerate(cases):
        base = dv[cases.index((pass_s, True, False))]
        rows.append({"pass_h": pass_s / 3600.0, "burns_during_passes": allowed, "around_passes": around,
                     "dv_per_year_mps_mean": float(dv[i].mean()), "dv_per_year_mps_std": float(dv[i].std()),
                     "extra_dv_per_year_mps_mean": float((dv[i] - base).mean()),
                     "extra_dv_per_year_mps_max": float((dv[i] - base).max()),
                     "max_abs_dlon_deg": float(dlon[i].max()), "duty_fraction_mean": float(duty[i].mean()),
                     "ok": int(np.sum(status[i] == 0)), "status": [STATUS_MEANINGS[int(s)] for s in status[i]]})
        print(rows[-1], flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "burns_around_passes" if args.controller == "qffc" else f"burns_around_passes_{args.controller}"
    (args.out / f"{stem}.json").write_text(json.dumps(
        {"samples": n, "days": args.days, "geojax": geojax.__version__, "rows": rows}, indent=1))
    lines = [f"# Burns kept out of the tracking passes: {args.controller.upper()}, {n} draws, {args.days:g} days", "",
             f"`python studies/navigation/burns_around_passes.py "
             f"{'' if args.controller == 'qffc' else f'--controller {args.controller} '}--samples {n} --days {args.days:g}`; geojax "
             f"{geojax.__version__}. li2022-qffc-ranging (two stations' passes twice a day at the same times); "
             "extra ΔV: against the same draws with burns allowed, mean and largest.", "",
             "| passes | burns in passes | ΔV (m/s/yr) | ± std | extra ΔV mean (m/s/yr) | extra ΔV max | "
             "max abs Δλ (deg) | duty | in the box |", "|---|---|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        how = "allowed" if r["burns_during_passes"] else ("forbidden, planned around" if r["around_passes"]
                                                         else "forbidden")
        lines.append(f"| 2 × {r['pass_h']:g} h | {how} | "
                     f"{r['dv_per_year_mps_mean']:.3f} | {r['dv_per_year_mps_std']:.3f} | "
                     f"{r['extra_dv_per_year_mps_mean']:.3f} | {r['extra_dv_per_year_mps_max']:.3f} | "
                     f"{r['max_abs_dlon_deg']:.4f} | {r['duty_fraction_mean']:.4f} | {r['ok']}/{n} |")
    (args.out / f"{stem}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
