"""Regenerate a paper's tables and figures with one command.

    python studies/reproduce.py li2022 [katz2025 ye2022 ma2023 bounds ablation longrun lifetime compare momentum
                                         navigation contingencies collocation ...]   # or: all
    python studies/reproduce.py li2022 --only fig09 fig13         # scripts whose name contains a word
    python studies/reproduce.py all --list                         # the commands, without running them

Runs each study script of the chosen papers in a fresh Python, one after the other, with its full settings
(the ones the results in ``studies/*/results`` were made with), and prints its wall time.  The sweeps are
resumable (``geojax sweep --resume`` underneath): run the same command again after an interruption and each
finished sweep is read back, not rerun.  Stops at the first script that fails, with its exit status.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

# paper: [(script relative to studies/, arguments)], in the order a reader meets them in studies/README.md
STUDIES = {
    "li2022": [("li2022/uncontrolled_year.py", []), ("li2022/one_year.py", []),
               *((f"li2022/{name}.py", []) for name in ("fig09_beta_max", "fig10_beta_min", "fig11_alpha_max",
                                                         "fig12_alpha_min", "fig13_horizon", "fig14_di_max",
                                                         "fig15_h_att", "fig16_h_rv")),
               ("li2022/fig17_trajectories.py", [])],
    "katz2025": [("katz2025/step.py", []), ("katz2025/table.py", [])],
    "ye2022": [("ye2022/table3.py", []), ("ye2022/sweep_limits.py", [])],
    "ablation": [("ablation/fompc_annealing.py", []), ("ablation/li_predictor_error.py", []),
                 ("ablation/fig13_budget.py", []), ("ablation/katz_longitude.py", []),
                 ("ablation/li_attitude_error.py", []), ("ablation/li_fig15_unsolved.py", ["--levels", "300", "400"]),
                 ("ablation/li_fig17_width.py", ["--reps", "4"]), ("ablation/tuning_horizon.py", [])],
    "ma2023": [("ma2023/transfer.py", [])],
    "bounds": [("bounds/table.py", []), ("bounds/operational.py", ["--days", "28", "--margin", "0.2"]),
               ("bounds/periodic.py", [])],
    "longrun": [("longrun/predictor_reference.py", [])],
    "lifetime": [("lifetime/lifetime.py", [])],
    "compare": [("compare/windows.py", []), ("compare/table.py", ["--stage", "all"])],
    "momentum": [("momentum/ye_accumulation.py", []), ("momentum/li_dumping.py", []),
                 ("momentum/capacity_map.py", []), ("momentum/mpc.py", []), ("momentum/mpc_capacity.py", []), ("momentum/mpc_line_price.py", []),
                 ("momentum/mpc_line_solves.py", []), ("momentum/mpc_equinox.py", []),
                 ("momentum/tune_dump_gain.py", []),
                 ("momentum/ma_kong_transfer.py", ["--capacities", "50", "100"]), ("momentum/arm_mounts.py", [])],
    "navigation": [("navigation/consistency.py", []), ("navigation/tracking_cost.py", []),
                   ("navigation/tracking_cost.py", ["--controller", "fompc", "--samples", "8", "--days", "120"]),
                   ("navigation/tracking_cost.py", ["--controller", "mpc", "--samples", "8", "--days", "120"]),
                   ("navigation/burns_around_passes.py", []),
                   ("navigation/burns_around_passes.py", ["--controller", "fompc", "--samples", "8", "--days", "120"]),
                   ("navigation/bias_estimation.py", []),
                   ("navigation/tune_thrust_ranging.py", [])],
    "contingencies": [("contingencies/arm_lost.py", []), ("contingencies/missed_burns.py", []),
                      ("contingencies/degradation.py", []), ("contingencies/tables.py", [])],
    "collocation": [("collocation/relative_motion.py", []), ("collocation/cluster_year.py", []),
                    ("collocation/cluster_year.py", ["--navigation", "ranging"]),
                    ("collocation/cluster_year.py", ["--controller", "fompc", "--clusters", "16"]),
                    ("collocation/cluster_year.py", ["--controller", "mpc", "--clusters", "16"]),
                    ("collocation/coordinated.py", []), ("collocation/qffc_dip.py", [])],
}


def selected(papers: list[str], only: list[str] | None) -> list[tuple[str, list[str]]]:
    names = list(STUDIES) if "all" in papers else papers
    scripts = [entry for name in names for entry in STUDIES[name]]
    if only:
        scripts = [entry for entry in scripts if any(word in entry[0] for word in only)]
    return scripts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("papers", nargs="+", choices=[*STUDIES, "all"])
    parser.add_argument("--only", nargs="+", metavar="WORD", help="only the scripts whose path contains a word")
    parser.add_argument("--list", action="store_true", help="print the commands and stop")
    args = parser.parse_args(argv)
    scripts = selected(args.papers, args.only)
    if not scripts:
        print(f"--only {' '.join(args.only)}: no script of {', '.join(args.papers)} matches", file=sys.stderr)
        return 2
    start = time.perf_counter()
    for i, (script, script_args) in enumerate(scripts, 1):
        command = [sys.executable, str(HERE / script), *script_args]
        print(f"[{i}/{len(scripts)}] python studies/{script} {' '.join(script_args)}".rstrip(), flush=True)
        if args.list:
            continue
        begun = time.perf_counter()
        code = subprocess.run(command, cwd=HERE.parent).returncode
        if code != 0:
            print(f"studies/{script} failed with exit status {code}", file=sys.stderr)
            return code
        print(f"    done in {time.perf_counter() - begun:.0f} s", flush=True)
    if not args.list:
        print(f"{len(scripts)} scripts in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
