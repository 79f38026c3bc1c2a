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
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
sys.path.insert(0, str(Path(__file__).resolve().parent))
from sweep import SWEEP, _peak_rss_mb  # noqa: E402  (the same samples as benchmarks/sweep.py)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=1024)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--overhead-chunks", type=int, default=16)
    parser.add_argument("--render", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--one", nargs=4, help=argparse.SUPPRESS)  # internal: batch days chunk workers (0: local)
    args = parser.parse_args()
    if args.one:
        batch, days, chunk, workers = args.one
        print(json.dumps(measure(int(batch), float(days), int(chunk) or None, int(workers))))
        return
    if args.render:  # the tables again from the last results (after a change of wording)
        saved = json.loads((RESULTS / "ray_sweep.json").read_text())
        write(saved["rows"], saved["overhead"], args)
        return
    rows = []
    for label, workers in (("local process", 0), ("Ray, 1 worker", 1), ("Ray, 2 workers", 2)):
        row = {"run": label, **_child(args.batch, args.days, 0, workers)}
        rows.append(row)
        print(f"{label}: {row['sample_years_per_s']:.3g} sample-years/s "
              f"({row['run_sample_years_per_s']:.3g} after compilation), wall {row['wall_s']:.1f} s", flush=True)
    cores = os.cpu_count() or 1
    width = 64 * cores  # one compiled QFFC batch on this machine: a chunk
    n = args.overhead_chunks * width
    local = _child(n, 1.0, width, 0)
    remote = _child(n, 1.0, width, 1)
    overhead = {"chunks": args.overhead_chunks, "samples": n, "local_run_s": local["run_s"],
                "ray_run_s": remote["run_s"], "ray_connect_s": remote["connect_s"],
                "per_chunk_s": (remote["run_s"] - local["run_s"]) / args.overhead_chunks}
    print(f"overhead per chunk: {overhead['per_chunk_s']:.3f} s", flush=True)
    write(rows, overhead, args)


def _child(batch: int, days: float, chunk: int, workers: int) -> dict:
    cmd = [sys.executable, __file__, "--one", str(batch), str(days), str(chunk), str(workers)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def measure(batch: int, days: float, chunk: int | None, workers: int) -> dict:
    from geojax.parallel import use_host_cores

    use_host_cores()
    from geojax import store, sweep

    with tempfile.TemporaryDirectory() as tmp:
        spec_path = Path(tmp) / "bench.toml"
        spec_path.write_text(SWEEP.format(controller="qffc", batch=batch, days=days))
        spec = sweep.load(spec_path)
        start = time.perf_counter()
        out = sweep.run_sweep(spec, Path(tmp) / "bench.h5", chunk=chunk, progress=False,
                              ray="local" if workers else None, workers=workers or None)
        wall_s = time.perf_counter() - start
        groups, attrs = store.read_h5(out)
    years = batch * days / 365.25
    run_s = float(attrs["wall_s"]) - float(attrs["compile_s"])  # the chunks, after the longest compilation
    return {"batch": batch, "days": days, "workers": workers, "wall_s": wall_s, "compile_s": float(attrs["compile_s"]),
            "connect_s": wall_s - float(attrs["wall_s"]), "run_s": run_s,
            "sample_years_per_s": years / wall_s, "run_sample_years_per_s": years / (wall_s - float(attrs["compile_s"])),
            "peak_rss_mb": _peak_rss_mb(), "dv_mean": float(groups["metrics"]["dv_per_year_mps"].mean())}


def write(rows: list[dict], overhead: dict, args) -> None:
    RESULTS.mkdir(exist_ok=True)
    revision = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=Path(__file__).parent).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain"], capture_output=True, text=True,
                           cwd=Path(__file__).parent).stdout.strip()
    (RESULTS / "ray_sweep.json").write_text(json.dumps({"rows": rows, "overhead": overhead}, indent=1))
    local = rows[0]["sample_years_per_s"]
    lines = [f"# Sweeps on Ray: li2022-qffc, {args.batch} samples of {args.days} days, H_rv = H_att = 1", "",
             f"`python benchmarks/ray_sweep.py` on {os.cpu_count()} CPU cores, git {revision}"
             f"{' + uncommitted' if dirty else ''}, {time.strftime('%Y-%m-%d')}. Each row is a fresh process; "
             "the Ray rows start a local Ray instance (`--ray`) whose workers compile for themselves. "
             "Wall time counts everything from the call of `run_sweep` (Ray's start, the workers' start and "
             "compilation included); 'chunks only' leaves out Ray's start and the longest compilation.", "",
             "| run | wall s | Ray start s | compile s | sample-years/s | / local | chunks only | ΔV mean |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['run']} | {r['wall_s']:.1f} | {r['connect_s']:.1f} | {r['compile_s']:.1f} | "
                     f"{r['sample_years_per_s']:.3g} | {r['sample_years_per_s'] / local:.2f}x | "
                     f"{r['batch'] * r['days'] / 365.25 / r['run_s']:.3g} | {r['dv_mean']:.4f} |")
    lines += ["", f"Overhead per chunk: {overhead['per_chunk_s'] * 1e3:.0f} ms ({overhead['chunks']} chunks of "
              f"{overhead['samples'] // overhead['chunks']} one-day samples: the Ray run's chunks took "
              f"{overhead['ray_run_s']:.2f} s after compilation, the local run's {overhead['local_run_s']:.2f} s; "
              f"Ray's own start {overhead['ray_connect_s']:.1f} s is apart). It includes the worker's process "
              "start and the transfer of each chunk's results to the driver, which writes it.", ""]
    (RESULTS / "ray_sweep.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
