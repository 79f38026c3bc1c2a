"""This tree's sweep speed against an earlier commit's, in one run: sample-years per second after compilation.

    python benchmarks/against_commit.py [--commit 3c28a1c] [--batch 32] [--days 365.25] [--rounds 2] [--name NAME]

For each scenario (li2022-qffc with Li's nominal errors, H_rv = H_att = 1: the Gaussian fix; li2022-qffc-ranging:
the navigation filter), a fresh process per tree runs ``geojax.simulate_batch`` of ``--batch`` samples (their
own seeds) three times on the compiled programs and reports the best ``run_s`` (the compiled closed loop and its
metrics alone: no set-up, no compilation); the trees alternate, ``--rounds`` times, and the best of each is kept,
so both see the same machine.  The earlier tree runs with the ``XLA_FLAGS`` it would have had (without the flags
this tree's ``import geojax`` adds: ``geojax.arithmetic``, ``geojax.small_loops``).  The earlier tree is ``git archive`` of ``--commit``'s ``geojax/`` (the public API,
``simulate_batch``, is the same in both).  Both trees' mean ΔV is printed beside, so a change of numbers shows.
Results: ``benchmarks/results/NAME.json`` and ``.md`` (default ``against_commit``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
from pathlib import Path

import harness

NAME = "against_commit"
USER_FLAGS = os.environ.get("XLA_FLAGS", "").split()  # before anything here imports geojax
ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = (("li2022-qffc", {"errors.h_rv": 1.0, "errors.h_att": 1.0}), ("li2022-qffc-ranging", {}))
CHILD = """
import json, sys, numpy as np, geojax
name, overrides, batch, days = sys.argv[1], json.loads(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
sc = geojax.load_scenario(name, {"duration.days": days, **overrides})
runs = [geojax.simulate_batch([sc] * batch, seeds=np.arange(batch)) for _ in range(3)]
best = min(r.run_s for r in runs)
print(json.dumps({"run_s": best, "sample_years_per_s": batch * days / 365.25 / best,
                  "dv_per_year_mps_mean": float(np.mean(runs[0].metrics["dv_per_year_mps"])),
                  "compile_s": runs[0].compile_s}))
"""


def baseline_tree(commit: str, folder: Path) -> Path:
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", commit, "geojax"], capture_output=True, check=True)
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive.stdout, check=True)
    return folder


def as_before_arithmetic(env) -> dict:
    """``env`` without the flags this process's ``import geojax`` added (``geojax.arithmetic``,
    ``geojax.small_loops``): an earlier tree's child runs with XLA's defaults, as it did then, unless the user's
    own ``XLA_FLAGS`` gave the flag."""
    from geojax.arithmetic import SEPARATE_ROUNDINGS
    from geojax.small_loops import with_small_loops

    added = {SEPARATE_ROUNDINGS, with_small_loops("")} - set(USER_FLAGS)
    flags = [f for f in env.get("XLA_FLAGS", "").split() if f not in added]
    return {**env, "XLA_FLAGS": " ".join(flags)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commit", default="3c28a1c")
    parser.add_argument("--batch", type=int, default=32)
    parser.add_argument("--days", type=float, default=365.25)  # 60 days run in 0.6 s: noise
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--name", default=NAME, help="results file's name (benchmarks/results/NAME.json, .md)")
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"this tree": ROOT, args.commit: baseline_tree(args.commit, Path(tmp))}
        for name, overrides in SCENARIOS:
            best = {}
            for _ in range(args.rounds):
                for label, tree in trees.items():
                    got = harness.run_json(["-c", CHILD, name, json.dumps(overrides), str(args.batch),
                                            str(args.days)], harness.Devices(platform=args.platform),
                                           pythonpath=tree, cwd=tree,  # ``-c`` puts the cwd first on the path
                                           env=None if tree == ROOT else as_before_arithmetic(os.environ))
                    print(label, name, got, flush=True)
                    if label not in best or got["run_s"] < best[label]["run_s"]:
                        best[label] = got
            rows.append({"scenario": name, **{f"{label}": best[label] for label in trees},
                         "ratio": best["this tree"]["sample_years_per_s"] / best[args.commit]["sample_years_per_s"]})
    body = [f"{args.batch} samples of {args.days:g} days each (their own seeds), the best of 3 runs after "
            f"compilation in a fresh process per tree, the trees alternating {args.rounds} times.", "",
            *harness.table(["scenario", f"{args.commit} sample-years/s", "this tree sample-years/s", "ratio",
                            f"ΔV mean {args.commit}", "ΔV mean this tree"],
                           [[r["scenario"], f"{r[args.commit]['sample_years_per_s']:.2f}",
                             f"{r['this tree']['sample_years_per_s']:.2f}", f"**{r['ratio']:.3f}×**",
                             f"{r[args.commit]['dv_per_year_mps_mean']:.6f}",
                             f"{r['this tree']['dv_per_year_mps_mean']:.6f}"] for r in rows], align="lrrrrr")]
    print(harness.write(args.out / args.name, run, f"Sweep speed against {args.commit}", {"rows": rows}, body))


if __name__ == "__main__":
    main()
