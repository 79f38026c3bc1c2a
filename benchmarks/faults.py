"""The faults part's cost: a QFFC sweep carrying the faults part at its defaults against the same sweep without it.

    python benchmarks/faults.py [--days 120] [--batch 32]

li2022-qffc with Li's nominal Gaussian errors (H_rv = H_att = 1), ``--batch`` samples with their own draws sharded
over one XLA CPU device per core, each compiled once and timed after compilation, the best of three runs
(``benchmarks/simulate.py``'s measure), without and with ``faults.enabled = true`` and every other key at its
default (nothing lost, nothing degraded: the part draws its missed burns, tracks four thrusters' firing and checks
the thrust every step).  The figure is the ratio of sample-years per second, with the part over without (the
target: at least 0.9).  Results: ``benchmarks/results/faults.json`` and ``.md``.
"""

from __future__ import annotations

import argparse

import harness
from simulate import measure

NAME = "faults"
TARGET_RATIO = 0.9
NOMINAL = {"errors.h_rv": 1.0, "errors.h_att": 1.0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=120.0)
    parser.add_argument("--batch", type=int, default=32)
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))
    rows = [measure("qffc", args.days, args.batch, "li2022-qffc", repeats=3, errors=NOMINAL),
            measure("qffc", args.days, args.batch, "li2022-qffc", repeats=3,
                    errors={**NOMINAL, "faults.enabled": True})]
    for row, label in zip(rows, ("without the faults part", "with it, its keys at their defaults")):
        row["sample_years_per_s"] = row["batch"] * row["days"] / 365.25 / row["run_s"]
        row["case"] = label
    ratio = rows[1]["sample_years_per_s"] / rows[0]["sample_years_per_s"]
    body = [f"The same {args.batch} samples of Li's QFFC satellite for {args.days:g} days (Li's nominal errors), "
            "without the faults part and with it at its defaults, one XLA CPU device per core, timed after "
            "compilation (the best of three runs).", "",
            *harness.table(["case", "compile s", "run s", "sample-years per s", "ΔV mean (m/s/yr)"],
                           [[r["case"], f"{r['compile_s']:.1f}", f"{r['run_s']:.2f}",
                             f"{r['sample_years_per_s']:.1f}", f"{r['dv_per_year_mps_mean']:.2f}"] for r in rows],
                           align="lrrrr"),
            "", f"With the faults part at **{ratio:.2f}×** the sample-years per second without it "
                f"(target ≥ {TARGET_RATIO}: {'met' if ratio >= TARGET_RATIO else 'not met'})."]
    print(harness.write(args.out / NAME, run, "The faults part's cost in a QFFC sweep", {"rows": rows, "ratio": ratio},
                        body))


if __name__ == "__main__":
    main()
