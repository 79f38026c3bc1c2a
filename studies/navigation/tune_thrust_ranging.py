"""A controller tuned under the orbit-determination filter: the QFFC's thrust level, with ranging in the loop.

    python studies/navigation/tune_thrust_ranging.py [--out studies/navigation/results]

Runs the tuning file ``tune-thrust-ranging.toml`` beside this script (``geojax tune`` does the same): Li's QFFC
satellite determined by the extended Kalman filter on two stations' ranging (``li2022-qffc-ranging``), its
thrusters' level tuned by the SQP with derivatives through the filter in the loop, the box as the constraint.
Writes the exact law's Delta-V and box at the scenario's thrust and at the tuned one, and what the tuning printed,
into ``tune_thrust_ranging.md`` (and the tuning's own file, ``tune_thrust_ranging.h5``) in ``--out``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import geojax
from geojax import tune
from geojax.tune.write import report_md

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=HERE / "results")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    spec = tune.load(HERE / "tune-thrust-ranging.toml")
    result = tune.tune(spec, out=args.out / "tune_thrust_ranging.h5")
    problem = result.problem
    start = float(spec.scenario.config["thrusters"]["thrust_n"])
    points = [("the scenario's", start)]
    if result.best_theta is not None:
        points.append(("tuned", float(np.exp(result.best_theta[0]))))
    rows = []
    for label, thrust_n in points:
        dv, g, ok = (np.asarray(v) for v in problem.exact(np.log([[thrust_n]])))
        rows.append(f"| {label} | {thrust_n:.4f} | {dv[0]:.3f} | {g[0, 0]:+.4f} | {g[0, 1]:+.4f} | "
                    f"{'yes' if ok[0] > 0 else 'no'} |")
    lines = [
        "# The QFFC's thrust level tuned under the orbit-determination filter",
        "",
        f"`python studies/navigation/tune_thrust_ranging.py` (geojax {geojax.__version__}; the tuning file "
        f"`studies/navigation/tune-thrust-ranging.toml`: {spec.scenario.name}, {spec.starts} starts, "
        f"{spec.iterations} SQP iterations, {problem.days} cycles). Constraints: the box, "
        f"{', '.join(problem.constraint_names)}.",
        "",
        "| thrust | F (N) | ΔV over the horizon, per year (m/s/yr) | lon constraint (excursion/box)² − 1 "
        "| lat constraint | box kept |",
        "|---|---|---|---|---|---|",
        *rows,
    ]
    print(report_md(args.out / "tune_thrust_ranging.md", lines, result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
