"""Monte Carlo sweeps: sample-years per second of ``geojax.sweep`` against the same samples one by one.

    python benchmarks/sweep.py [--batches 1 64 1024 4096] [--controller qffc] [--days 365.25] [--loop 16]

Each sample is one year of ``li2022-<controller>`` (normal limits) with its own
orbit-determination and attitude error draw (H_rv = H_att = 1, Li 2022 eq. (48)).
For every batch size B, a fresh process runs a sweep of B repetitions with
``geojax.sweep.run_sweep`` (one compilation, chunks saved to disk as they finish,
the batch sharded over one XLA CPU device per core) and reports its wall time,
compilation included, and its peak resident memory.  The baseline runs the same
samples (the same keys) one after another in a Python loop over the compiled
single rollout (``loop.rollout.rollout_fn``, compiled once and reused), as a user
without ``vmap`` would; it runs ``--loop`` samples (all of them if B is smaller)
and its rate is per sample, so it does not depend on B.  Both in one run.
Results: ``benchmarks/results/sweep.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"

SWEEP = """
name = "bench"
scenario = "li2022-{controller}"
controllers = ["{controller}"]
repetitions = {batch}
seed = 7
[set]
"duration.days" = {days}
"errors.h_rv" = 1.0
"errors.h_att" = 1.0
[grid]
"thrusters.beta_max_deg" = [70.0]
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batches", type=int, nargs="+", default=[1, 64, 1024, 4096])
    parser.add_argument("--controller", choices=["qffc", "fompc"], default="qffc")
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--loop", type=int, default=16, help="samples the Python-loop baseline runs")
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)  # internal: one measurement in this process
    parser.add_argument("--baseline", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one is not None:
        print(json.dumps(measure_sweep(args.controller, args.days, args.one)))
        return
    if args.baseline is not None:
        print(json.dumps(measure_loop(args.controller, args.days, args.baseline)))
        return
    rows = []
    loop = _child(["--baseline", str(args.loop)], args)
    for batch in args.batches:
        row = _child(["--one", str(batch)], args)
        row["loop_sample_years_per_s"] = loop["sample_years_per_s"]
        row["speedup"] = row["sample_years_per_s"] / loop["sample_years_per_s"]
        row["run_speedup"] = row["run_sample_years_per_s"] / loop["sample_years_per_s"]
        rows.append(row)
        print(f"batch {batch}: {row['sample_years_per_s']:.3g} sample-years/s ({row['speedup']:.1f}x the loop; "
              f"{row['run_speedup']:.1f}x after compilation), "
              f"peak {row['peak_rss_mb']:.0f} MB", flush=True)
    write(rows, loop, args)


def _child(flags, args) -> dict:
    """Run one measurement in a fresh Python (its own compilation, its own peak memory)."""
    cmd = [sys.executable, __file__, "--controller", args.controller, "--days", str(args.days), *flags]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def measure_sweep(controller: str, days: float, batch: int) -> dict:
    from geojax.parallel import use_host_cores

    use_host_cores()
    import jax

    from geojax import store, sweep

    with tempfile.TemporaryDirectory() as tmp:
        spec_path = Path(tmp) / "bench.toml"
        spec_path.write_text(SWEEP.format(controller=controller, batch=batch, days=days))
        start = time.perf_counter()
        out = sweep.run_sweep(sweep.load(spec_path), Path(tmp) / "bench.h5", progress=False)
        wall_s = time.perf_counter() - start
        groups, attrs = store.read_h5(out)
        dv = groups["metrics"]["dv_per_year_mps"].ravel()
    years = batch * days / 365.25
    compile_s = float(attrs["compile_s"])
    return {"batch": batch, "wall_s": wall_s, "compile_s": compile_s, "sample_years_per_s": years / wall_s,
            "run_sample_years_per_s": years / (wall_s - compile_s), "devices": jax.device_count(),
            "peak_rss_mb": _peak_rss_mb(), "dv_mean": float(dv.mean()), "dv_std": float(dv.std())}


def measure_loop(controller: str, days: float, n: int) -> dict:
    import jax

    from geojax import scenario
    from geojax.loop.rollout import rollout_fn
    from geojax.loop.setup import prepare, unstack

    sc = scenario.load(f"li2022-{controller}", {"duration.days": days, "errors.h_rv": 1.0, "errors.h_att": 1.0})
    batch = prepare([sc])
    params, one = unstack(batch.params, 0), jax.jit(rollout_fn(batch))
    key = jax.random.key(7)
    start = time.perf_counter()
    jax.block_until_ready(one(params, jax.random.fold_in(key, 0)))
    compile_s = time.perf_counter() - start
    start = time.perf_counter()
    dv = [float(one(params, jax.random.fold_in(key, j))[0].dv_mps) for j in range(n)]
    wall_s = time.perf_counter() - start
    return {"samples": n, "compile_s": compile_s, "wall_s": wall_s, "sample_years_per_s": n * days / 365.25 / wall_s,
            "peak_rss_mb": _peak_rss_mb(), "dv_first_mps": dv[0]}


def _peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: kB


def write(rows, loop, args) -> None:
    import platform

    RESULTS.mkdir(exist_ok=True)
    meta = {"controller": args.controller, "days": args.days, "cpus": os.cpu_count(), "machine": platform.processor()
            or platform.machine(), "git": _git()}
    (RESULTS / "sweep.json").write_text(json.dumps({"meta": meta, "loop": loop, "rows": rows}, indent=2) + "\n")
    lines = [
        f"# Sweeps: li2022-{args.controller}, {args.days:g} days per sample, H_rv = H_att = 1",
        "",
        f"`python benchmarks/sweep.py` on {meta['cpus']} CPU cores, git {meta['git']}. `geojax.sweep` runs B "
        "repetitions (one compilation, included in the wall time; chunks saved as they finish; sharded over "
        f"{rows[0]['devices']} XLA CPU devices) in a fresh process; the loop runs the same samples one by one "
        f"through the compiled single rollout ({loop['samples']} samples, {loop['wall_s']:.1f} s after a "
        f"{loop['compile_s']:.1f} s compilation: {loop['sample_years_per_s']:.3g} sample-years/s).",
        "",
        "| batch B | sweep wall s | of which compile s | sample-years/s | / Python loop | after compilation: "
        "sample-years/s | / Python loop | peak memory MB | ΔV mean ± std (m/s/yr) |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        lines.append(f"| {r['batch']} | {r['wall_s']:.1f} | {r['compile_s']:.1f} | {r['sample_years_per_s']:.3g} | "
                     f"{r['speedup']:.1f}x | {r['run_sample_years_per_s']:.3g} | {r['run_speedup']:.1f}x | "
                     f"{r['peak_rss_mb']:.0f} | {r['dv_mean']:.2f} ± {r['dv_std']:.2f} |")
    lines += ["", "Peak memory is the resident set of the whole process (Python, JAX, XLA, the compiled program); "
              "it is bounded by the compiled width (`geojax.lanes`: 128 QFFC lanes per CPU device), not by B."]
    (RESULTS / "sweep.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def _git() -> str:
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True, text=True).stdout
        return rev + (" + uncommitted" if dirty.strip() else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


if __name__ == "__main__":
    main()
