"""Monte Carlo sweeps: sample-years per second of ``geojax.sweep`` against the same samples one by one.

    python benchmarks/sweep.py [--batches 1 64 1024 4096] [--controller qffc] [--days 365.25] [--loop 16]

Each sample is one year of ``li2022-<controller>`` (normal limits) with its own
orbit-determination and attitude error draw (H_rv = H_att = 1, Li 2022 eq. (48)).
For every batch size B, a fresh process runs a sweep of B repetitions with
``geojax.sweep.run_sweep`` (one compilation, chunks saved to disk as they finish,
the batch sharded over one XLA CPU device per core) and reports its wall time,
compilation included, and its peak resident memory.  The baseline runs the same
samples (the same keys) one after another in a Python loop over the compiled
single rollout (``runner.rollout.rollout_fn``, compiled once and reused), as a user
without ``vmap`` would; it runs ``--loop`` samples (all of them if B is smaller)
and its rate is per sample, so it does not depend on B.  Both in one run.
Results: ``benchmarks/results/sweep.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import harness

NAME = "sweep"

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
    harness.add_arguments(parser)
    args = parser.parse_args()
    if args.one is not None or args.baseline is not None:  # the parent's devices, or this process's alone
        harness.set_up(harness.Devices(platform=args.platform))
    if args.one is not None:
        print(json.dumps(measure_sweep(args.controller, args.days, args.one)))
        return
    if args.baseline is not None:
        print(json.dumps(measure_loop(args.controller, args.days, args.baseline)))
        return
    devices = harness.Devices(platform=args.platform)
    run = harness.start(devices)
    common = [__file__, "--controller", args.controller, "--days", str(args.days)]
    child = lambda flags: harness.run_json([*common, *flags], devices)  # noqa: E731
    loop = child(["--baseline", str(args.loop)])
    rows = []
    for batch in args.batches:
        row = child(["--one", str(batch)])
        row["loop_sample_years_per_s"] = loop["sample_years_per_s"]
        row["speedup"] = row["sample_years_per_s"] / loop["sample_years_per_s"]
        row["run_speedup"] = row["run_sample_years_per_s"] / loop["sample_years_per_s"]
        rows.append(row)
        print(f"batch {batch}: {row['sample_years_per_s']:.3g} sample-years/s ({row['speedup']:.1f}x the loop; "
              f"{row['run_speedup']:.1f}x after compilation), "
              f"peak {row['peak_rss_mb']:.0f} MB", flush=True)
    print(harness.write(args.out / NAME, run, f"Sweeps: li2022-{args.controller}, {args.days:g} days per sample, "
                        "H_rv = H_att = 1", {"controller": args.controller, "days": args.days, "loop": loop,
                                             "rows": rows}, markdown(rows, loop)))


def sweep_spec(controller: str, batch: int, days: float):
    """``SWEEP`` for ``controller``, ``batch`` repetitions of ``days``, as ``geojax.sweep.load`` reads it."""
    from geojax import sweep

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.toml"
        path.write_text(SWEEP.format(controller=controller, batch=batch, days=days))
        return sweep.load(path)


def run_sweep_file(spec, **options) -> dict:
    """``geojax.sweep.run_sweep`` of ``spec`` into a temporary file: its wall time (the caller's), the file's
    attributes, metrics and status.  ``options`` go to ``run_sweep`` (``chunk``, ``ray``, ``workers``)."""
    from geojax import store, sweep

    with tempfile.TemporaryDirectory() as tmp:
        out, call = harness.timed(sweep.run_sweep, spec, Path(tmp) / "bench.h5", progress=False, **options)
        groups, attrs = store.read_h5(out)
    return {"wall_s": call.wall_s, "attrs": attrs, "metrics": groups["metrics"], "status": groups["status"]}


def measure_sweep(controller: str, days: float, batch: int) -> dict:
    import jax

    done = run_sweep_file(sweep_spec(controller, batch, days))
    dv = done["metrics"]["dv_per_year_mps"].ravel()
    years = batch * days / 365.25
    wall_s, compile_s = done["wall_s"], float(done["attrs"]["compile_s"])
    return {"batch": batch, "wall_s": wall_s, "compile_s": compile_s, "sample_years_per_s": years / wall_s,
            "run_sample_years_per_s": years / (wall_s - compile_s), "devices": jax.device_count(),
            "peak_rss_mb": harness.peak_memory_bytes() / 2**20, "dv_mean": float(dv.mean()), "dv_std": float(dv.std())}


def measure_loop(controller: str, days: float, n: int) -> dict:
    import jax

    from geojax import scenario
    from geojax.runner.rollout import rollout_fn
    from geojax.runner.setup import prepare, unstack

    sc = scenario.load(f"li2022-{controller}", {"duration.days": days, "errors.h_rv": 1.0, "errors.h_att": 1.0})
    batch = prepare([sc])
    params, one = unstack(batch.params, 0), jax.jit(rollout_fn(batch))
    key = jax.random.key(7)
    _, first = harness.timed(one, params, jax.random.fold_in(key, 0))  # compiles
    dv, timing = harness.measure(lambda: [float(one(params, jax.random.fold_in(key, j))[0].dv_mps) for j in range(n)])
    return {"samples": n, "compile_s": first.wall_s, "wall_s": timing.best_s,
            "sample_years_per_s": n * days / 365.25 / timing.best_s, "peak_rss_mb": harness.peak_memory_bytes() / 2**20,
            "dv_first_mps": dv[0]}


def markdown(rows: list[dict], loop: dict) -> list[str]:
    return [
        "`geojax.sweep` runs B repetitions (one compilation, included in the wall time; chunks saved as they "
        f"finish; sharded over {rows[0]['devices']} XLA CPU devices) in a fresh process; the loop runs the same "
        f"samples one by one through the compiled single rollout ({loop['samples']} samples, {loop['wall_s']:.1f} s "
        f"after a {loop['compile_s']:.1f} s compilation: {loop['sample_years_per_s']:.3g} sample-years/s).",
        "",
        *harness.table(["batch B", "sweep wall s", "of which compile s", "sample-years/s", "/ Python loop",
                        "after compilation: sample-years/s", "/ Python loop", "peak memory MB",
                        "ΔV mean ± std (m/s/yr)"],
                       [[r["batch"], f"{r['wall_s']:.1f}", f"{r['compile_s']:.1f}", f"{r['sample_years_per_s']:.3g}",
                         f"{r['speedup']:.1f}x", f"{r['run_sample_years_per_s']:.3g}", f"{r['run_speedup']:.1f}x",
                         f"{r['peak_rss_mb']:.0f}", f"{r['dv_mean']:.2f} ± {r['dv_std']:.2f}"] for r in rows],
                       align="rrrrrrrrl"),
        "", "Peak memory is the resident set of the whole process (Python, JAX, XLA, the compiled program); "
        "it is bounded by the compiled width (`geojax.lanes`: 128 QFFC lanes per CPU device), not by B."]


if __name__ == "__main__":
    main()
