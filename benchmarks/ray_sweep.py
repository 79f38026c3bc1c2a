"""Sweeps on Ray: sample-years per second with 1 and 2 Ray worker processes against one local process,
and Ray's overhead per chunk.

    python benchmarks/ray_sweep.py [--batch 1024] [--days 365.25] [--overhead-chunks 16]

Every measurement runs in a fresh Python process on this machine: the sweep of ``benchmarks/sweep.py``
(B one-year ``li2022-qffc`` samples, H_rv = H_att = 1, the default chunk of one compiled batch) run
(a) by ``geojax.sweep`` locally, sharded over one XLA device per core, (b) with ``--ray`` on a local Ray
instance with one worker (all cores) and (c) with two workers (the cores shared out, one device each).
Sample-years per second count the whole wall time, Ray's start and the workers' compilation included;
"after compilation" leaves out the longest compilation.  The overhead per chunk comes from a separate
pair of runs of one-day samples (so a chunk computes in about 0.1 s): (Ray run time - local run time,
each after compilation) / chunks, with one worker of the same device count as the local run; it
includes the worker's start, spread over the chunks.  Results: ``benchmarks/results/ray_sweep.json``
and ``.md``.
"""

from __future__ import annotations

import argparse
import json

import harness
from sweep import run_sweep_file, sweep_spec  # the same samples as benchmarks/sweep.py

NAME = "ray_sweep"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=1024)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--overhead-chunks", type=int, default=16)
    parser.add_argument("--render", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--one", nargs=4, help=argparse.SUPPRESS)  # internal: batch days chunk workers (0: local)
    harness.add_arguments(parser)
    args = parser.parse_args()
    if args.one:  # the parent's devices, or this process's where it runs alone
        harness.set_up(harness.Devices(platform=args.platform))
        batch, days, chunk, workers = args.one
        print(json.dumps(measure(int(batch), float(days), int(chunk) or None, int(workers))))
        return
    if args.render:  # the tables again from the last results (after a change of wording), with their facts
        meta, saved = harness.read(args.out / NAME)
        if not meta:
            raise SystemExit(f"--render: {args.out / NAME}.json was not written by the harness (no meta)")
        first = saved["rows"][0]
        print(harness.save(args.out / NAME, meta, title(first["batch"], first["days"]), saved,
                           markdown(saved["rows"], saved["overhead"])))
        return
    devices = harness.Devices(platform=args.platform)
    run = harness.start(devices)
    child = lambda batch, days, chunk, workers: harness.run_json(  # noqa: E731
        [__file__, "--one", str(batch), str(days), str(chunk), str(workers)], devices)
    rows = []
    for label, workers in (("local process", 0), ("Ray, 1 worker", 1), ("Ray, 2 workers", 2)):
        row = {"run": label, **child(args.batch, args.days, 0, workers)}
        rows.append(row)
        print(f"{label}: {row['sample_years_per_s']:.3g} sample-years/s "
              f"({row['run_sample_years_per_s']:.3g} after compilation), wall {row['wall_s']:.1f} s", flush=True)
    width = 64 * len(harness.usable_cores())  # one compiled QFFC batch on this machine: a chunk
    n = args.overhead_chunks * width
    local = child(n, 1.0, width, 0)
    remote = child(n, 1.0, width, 1)
    overhead = {"chunks": args.overhead_chunks, "samples": n, "local_run_s": local["run_s"],
                "ray_run_s": remote["run_s"], "ray_connect_s": remote["connect_s"],
                "per_chunk_s": (remote["run_s"] - local["run_s"]) / args.overhead_chunks}
    print(f"overhead per chunk: {overhead['per_chunk_s']:.3f} s", flush=True)
    print(harness.write(args.out / NAME, run, title(args.batch, args.days), {"rows": rows, "overhead": overhead},
                        markdown(rows, overhead)))


def title(batch: int, days: float) -> str:
    return f"Sweeps on Ray: li2022-qffc, {batch} samples of {days} days, H_rv = H_att = 1"


def measure(batch: int, days: float, chunk: int | None, workers: int) -> dict:
    done = run_sweep_file(sweep_spec("qffc", batch, days), chunk=chunk, ray="local" if workers else None,
                          workers=workers or None)
    years = batch * days / 365.25
    wall_s, file_wall_s, compile_s = done["wall_s"], float(done["attrs"]["wall_s"]), float(done["attrs"]["compile_s"])
    return {"batch": batch, "days": days, "workers": workers, "wall_s": wall_s, "compile_s": compile_s,
            "connect_s": wall_s - file_wall_s,
            "run_s": file_wall_s - compile_s,  # the chunks, after the longest compilation
            "sample_years_per_s": years / wall_s, "run_sample_years_per_s": years / (wall_s - compile_s),
            "peak_rss_mb": harness.peak_memory_bytes() / 2**20,
            "dv_mean": float(done["metrics"]["dv_per_year_mps"].mean())}


def markdown(rows: list[dict], overhead: dict) -> list[str]:
    local = rows[0]["sample_years_per_s"]
    return ["Each row is a fresh process; the Ray rows start a local Ray instance (`--ray`) whose workers compile "
            "for themselves. Wall time counts everything from the call of `run_sweep` (Ray's start, the workers' "
            "start and compilation included); 'chunks only' leaves out Ray's start and the longest compilation.", "",
            *harness.table(["run", "wall s", "Ray start s", "compile s", "sample-years/s", "/ local", "chunks only",
                            "ΔV mean"],
                           [[r["run"], f"{r['wall_s']:.1f}", f"{r['connect_s']:.1f}", f"{r['compile_s']:.1f}",
                             f"{r['sample_years_per_s']:.3g}", f"{r['sample_years_per_s'] / local:.2f}x",
                             f"{r['batch'] * r['days'] / 365.25 / r['run_s']:.3g}", f"{r['dv_mean']:.4f}"]
                            for r in rows]),
            "", f"Overhead per chunk: {overhead['per_chunk_s'] * 1e3:.0f} ms ({overhead['chunks']} chunks of "
            f"{overhead['samples'] // overhead['chunks']} one-day samples: the Ray run's chunks took "
            f"{overhead['ray_run_s']:.2f} s after compilation, the local run's {overhead['local_run_s']:.2f} s; "
            f"Ray's own start {overhead['ray_connect_s']:.1f} s is apart). It includes the worker's process "
            "start and the transfer of each chunk's results to the driver, which writes it."]


if __name__ == "__main__":
    main()
