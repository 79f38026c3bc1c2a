"""The wheels' cost: a QFFC sweep with the momentum state and dumping against the same sweep without them.

    python benchmarks/momentum.py [--days 120] [--batch 64]

li2022-momentum (the wheels, the SRP offset's torque, dumping by tilting the arms; ``geojax.states.momentum``)
against li2022-qffc (the same satellite and controller, no wheels), ``--batch`` samples with their own error draws
(H_rv = H_att = 1) sharded over one XLA CPU device per core, each compiled once and timed after compilation, the
best of three runs (``benchmarks/simulate.py``'s measure). The figure is the ratio of sample-years per second, with
over without (the target: at least 0.8). Results: ``benchmarks/results/momentum.json`` and ``.md``.
"""

from __future__ import annotations

import argparse

import harness
from simulate import measure

NAME = "momentum"
TARGET_RATIO = 0.8


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=120.0)
    parser.add_argument("--batch", type=int, default=64)
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))
    rows = [measure("qffc", args.days, args.batch, name, repeats=3) for name in ("li2022-qffc", "li2022-momentum")]
    for row in rows:
        row["sample_years_per_s"] = row["batch"] * row["days"] / 365.25 / row["run_s"]
    ratio = rows[1]["sample_years_per_s"] / rows[0]["sample_years_per_s"]
    body = [f"The same {args.batch} error draws of Li's QFFC satellite for {args.days:g} days, with and without the "
            "wheels and dumping, one XLA CPU device per core, timed after compilation (the best of three runs).", "",
            *harness.table(["scenario", "compile s", "run s", "sample-years per s", "ΔV mean (m/s/yr)"],
                           [[r["scenario"], f"{r['compile_s']:.1f}", f"{r['run_s']:.2f}",
                             f"{r['sample_years_per_s']:.1f}", f"{r['dv_per_year_mps_mean']:.2f}"] for r in rows],
                           align="lrrrr"),
            "", f"With the wheels and dumping at **{ratio:.2f}×** the sample-years per second without them "
                f"(target ≥ {TARGET_RATIO}: {'met' if ratio >= TARGET_RATIO else 'not met'})."]
    print(harness.write(args.out / NAME, run, "The wheels' cost in a QFFC sweep", {"rows": rows, "ratio": ratio},
                        body))


if __name__ == "__main__":
    main()
