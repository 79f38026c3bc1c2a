"""The dumping law's gain tuned by gradients with the box and the wheels' capacity as constraints.

    python studies/momentum/tune_dump_gain.py [--out studies/momentum/results]

Runs the tuning file ``tune-dump-gain.toml`` beside this script (``geojax tune`` does the same) and writes what it
found, with the exact law's wheels and Delta-V at the scenario's gain and at the tuned one, into
``tune_dump_gain.md`` (and the tuning's own file, ``tune_dump_gain.h5``) in ``--out``.
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
    spec = tune.load(HERE / "tune-dump-gain.toml")
    result = tune.tune(spec, out=args.out / "tune_dump_gain.h5")
    problem = result.problem
    start_gain = float(spec.scenario.config["attitude"]["dump_gain_per_s"])
    rows = []
    for label, gain in (("the scenario's", start_gain),) + ((("tuned", float(np.exp(result.best_theta[0]))),)
                                                              if result.best_theta is not None else ()):
        dv, g, ok = (np.asarray(v) for v in problem.exact(np.log([[gain]])))
        capacity = spec.scenario.config["attitude"]["wheel_capacity_nms"]
        rows.append(f"| {label} | {gain:.4g} | {dv[0]:.3f} | {capacity * np.sqrt(max(g[0, 2] + 1, 0)):.2f} | "
                    f"{g[0, 2]:+.4f} | {'yes' if ok[0] > 0 else 'no'} |")
    lines = [
        "# The dumping gain tuned with the wheels' capacity as a constraint",
        "",
        f"`python studies/momentum/tune_dump_gain.py` (geojax {geojax.__version__}; the tuning file "
        f"`studies/momentum/tune-dump-gain.toml`: {spec.scenario.name}, {spec.starts} starts, {spec.iterations} SQP "
        f"iterations, {problem.days} cycles). Constraints: the box (lon, lat) and the wheels, "
        f"{', '.join(problem.constraint_names)}.",
        "",
        "| gain | k_dump (1/s) | ΔV over the horizon, per year (m/s/yr) | largest wheel momentum (N m s) "
        "| wheels' constraint (|h|/capacity)² − 1 | box and wheels kept |",
        "|---|---|---|---|---|---|",
        *rows,
    ]
    print(report_md(args.out / "tune_dump_gain.md", lines, result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
