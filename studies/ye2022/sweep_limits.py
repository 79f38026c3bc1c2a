"""Ye 2022, example one beyond Table 3: Delta-V and keeping accuracy over t_max, t_min and the thrust, with
Monte Carlo over orbit-determination errors (``sweeps/ex1_limits.toml``).

    python studies/ye2022/sweep_limits.py [--reps R] [--days D] [--out studies/ye2022/results]

Runs the sweep with ``geojax.sweep`` (resumable: run it again after an interruption) into
``results/ye2022_ex1_limits.h5`` and writes ``results/sweep_limits.md``: per grid point, the mean and
standard deviation over the repetitions of the Delta-V per year and of the largest one-cycle-mean
inclination deviation after the first cycle (``max_abs_di``, MEE (h, k), doubled to the paper's vector in
degrees), the largest longitude excursion and the statuses.
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import numpy as np

from geojax import store, sweep
from geojax.parallel import use_host_cores

HERE = Path(__file__).parent


def report(spec, groups, command: str) -> str:
    grid = {k: np.asarray(v) for k, v in spec.grid.items()}  # the sweep's axis order, as the metrics are laid out
    names = list(grid)
    dv = np.asarray(groups["metrics"]["dv_per_year_mps"])[0]
    di = np.degrees(2 * np.asarray(groups["metrics"]["max_abs_di"]))[0]
    dlon = np.asarray(groups["metrics"]["max_abs_dlon_deg"])[0]
    status = np.asarray(groups["status"]["code"])[0]
    lines = ["# Ye 2022 example one: t_max, t_min, thrust and orbit-determination errors", "", f"`{command}`", "",
             "Mean ± std over the repetitions; accuracy: largest |i − i_T| of the one-cycle mean (paper's vector, "
             "°) after the first cycle, capture included; status counts (0 ok).", "",
             "| " + " | ".join(names) + " | ΔV (m/s/yr) | max |Δi| (°) | max |Δλ| (°) | statuses |",
             "|" + "---|" * (len(names) + 4)]
    for index in itertools.product(*(range(len(v)) for v in grid.values())):
        values = " | ".join(f"{grid[n][j]:g}" for n, j in zip(names, index))
        s = status[index]
        codes = ", ".join(f"{c}: {int(np.sum(s == c))}" for c in np.unique(s))
        lines.append(f"| {values} | {np.mean(dv[index]):.2f} ± {np.std(dv[index]):.2f} "
                     f"| {np.mean(di[index]):.4f} ± {np.std(di[index]):.4f} | {np.max(dlon[index]):.4f} | {codes} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, help="repetitions per grid point (default: the sweep file's)")
    parser.add_argument("--days", type=float, help="simulated days per sample (default: one year)")
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args()
    use_host_cores()
    changes = {}
    if args.reps is not None:
        changes["repetitions"] = args.reps
    if args.days is not None:
        changes["set"] = {"duration.days": args.days}
    suffix = "".join(f"-{k}{v:g}" for k, v in (("r", args.reps), ("d", args.days)) if v is not None)
    spec = sweep.load(HERE / "sweeps" / "ex1_limits.toml", changes)
    out = Path(args.out)
    path = sweep.run_sweep(spec, out / f"{spec.name}{suffix}.h5", resume=True)
    groups, _ = store.read_h5(path)
    command = "python studies/ye2022/sweep_limits.py" + "".join(
        f" --{k} {v:g}" for k, v in (("reps", args.reps), ("days", args.days)) if v is not None)
    md = out / f"sweep_limits{suffix}.md"
    md.write_text(report(spec, groups, command))
    print(md.read_text())


if __name__ == "__main__":
    main()
