"""Small loops compiled whole (``geojax.small_loops``) against XLA's default, kernel by kernel, in one run.

    python benchmarks/small_loops.py [--rounds 2] [--name small_loops]

For each case a fresh process per setting runs the closed loop three times on its compiled programs and reports
the best ``run_s`` (the compiled closed loop and its metrics alone: no set-up, no compilation): once as
``import geojax`` sets XLA's small-loop threshold, once with ``GEOJAX_XLA_LOOPS=1`` (XLA's default, 1 KiB); the
settings alternate ``--rounds`` times and the best of each is kept.  Each child also prints a digest of every
record and metric, so the table says whether the numbers are the same bit for bit.  The cases: the QFFC with Li's
nominal errors (the Gaussian fix) and with the navigation filter, 32 samples of a year; Li's MPC, 8 samples of 30
days (its lanes on a CPU); one sample of the QFFC's year (``simulate``).
Results: ``benchmarks/results/NAME.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os

import harness

NAME = "small_loops"
LI_ERRORS = {"errors.h_rv": 1.0, "errors.h_att": 1.0}
CASES = (("li2022-qffc", LI_ERRORS, 32, 365.25), ("li2022-qffc-ranging", {}, 32, 365.25),
         ("li2022-mpc", LI_ERRORS, 8, 30.0), ("li2022-qffc", LI_ERRORS, 1, 365.25))
CHILD = """
import hashlib, json, sys, jax, numpy as np, geojax
name, overrides, batch, days = sys.argv[1], json.loads(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
sc = geojax.load_scenario(name, {"duration.days": days, **overrides})
fly = (lambda: geojax.simulate(sc, seed=0)) if batch == 1 else (
    lambda: geojax.simulate_batch([sc] * batch, seeds=np.arange(batch)))
runs = [fly() for _ in range(3)]
best = min(r.run_s for r in runs)
digest = hashlib.sha256()
for leaf in jax.tree_util.tree_leaves((runs[0].records, runs[0].metrics)):
    digest.update(np.ascontiguousarray(np.asarray(leaf)).tobytes())
print(json.dumps({"run_s": best, "sample_years_per_s": batch * days / 365.25 / best,
                  "digest": digest.hexdigest(), "compile_s": runs[0].compile_s}))
"""


def kernel_by_kernel(env) -> dict:
    """``env`` as XLA's default would run it: ``GEOJAX_XLA_LOOPS=1`` and the threshold geojax added removed."""
    from geojax.small_loops import ENV_XLA_LOOPS, with_small_loops

    flags = [f for f in env.get("XLA_FLAGS", "").split() if f != with_small_loops("")]
    return {**env, "XLA_FLAGS": " ".join(flags), ENV_XLA_LOOPS: "1"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--name", default=NAME, help="results file's name (benchmarks/results/NAME.json, .md)")
    harness.add_arguments(parser)
    args = parser.parse_args()
    devices = harness.Devices(platform=args.platform)
    run = harness.start(devices)
    settings = {"whole": dict(os.environ), "kernel by kernel": kernel_by_kernel(os.environ)}
    rows = []
    for name, overrides, batch, days in CASES:
        best = {}
        for _ in range(args.rounds):
            for label, env in settings.items():
                got = harness.run_json(["-c", CHILD, name, json.dumps(overrides), str(batch), str(days)], devices,
                                       env=env)
                print(label, name, batch, got, flush=True)
                if label not in best or got["run_s"] < best[label]["run_s"]:
                    best[label] = got
        rows.append({"scenario": name, "samples": batch, "days": days, **best,
                     "ratio": best["kernel by kernel"]["run_s"] / best["whole"]["run_s"],
                     "bit_for_bit": best["whole"]["digest"] == best["kernel by kernel"]["digest"]})
    body = [f"The best of 3 runs after compilation in a fresh process per setting, the settings alternating "
            f"{args.rounds} times; speed-up: the run time kernel by kernel over the run time whole.", "",
            *harness.table(["scenario", "samples", "days", "kernel by kernel s", "whole s", "speed-up",
                            "records and metrics"],
                           [[r["scenario"], r["samples"], f"{r['days']:g}", f"{r['kernel by kernel']['run_s']:.3f}",
                             f"{r['whole']['run_s']:.3f}", f"**{r['ratio']:.2f}×**",
                             "bit for bit" if r["bit_for_bit"] else "**differ**"] for r in rows],
                           align="lrrrrrl")]
    print(harness.write(args.out / args.name, run, "Small loops compiled whole against kernel by kernel",
                        {"rows": rows}, body))


if __name__ == "__main__":
    main()
