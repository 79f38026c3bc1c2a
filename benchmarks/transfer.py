"""GTO-GEO transfers (Ma & Kong 2023): a batch of transfers with dispersed start orbits in one compilation.

    python benchmarks/transfer.py [--batch 256] [--days 250] [--single 2]

The batch (half ``ma2023-boom``, half ``ma2023-quadrilateral``; perigee +-50 km, apogee +-200 km, inclination
+-0.5 deg, uniform) is vmapped and sharded over one XLA CPU device per core (``geojax.parallel``), compiled
once.  The same transfers run one at a time (the jitted single transfer in a Python loop, ``--single`` of
them) give the batching ratio.  ``--days`` is the time limit (default 250 days: the boom reaches GEO after
about 207, the quadrilateral at 45 deg after about 280, so ``--days 300`` lets both arrive; the scan runs on,
frozen, to the limit).
Results: ``benchmarks/results/transfer.json`` and ``.md``.
"""

from __future__ import annotations

import os

os.environ.setdefault("XLA_FLAGS", f"--xla_force_host_platform_device_count={os.cpu_count() or 1}")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import numpy as np  # noqa: E402

from geojax import transfer  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"


def dispersed(batch: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    params = []
    for j in range(batch):
        overrides = {"orbit.perigee_alt_km": 964.0 + rng.uniform(-50, 50),
                     "orbit.apogee_alt_km": 35741.0 + rng.uniform(-200, 200), "orbit.i_deg": 20.8 + rng.uniform(-0.5, 0.5)}
        params.append(transfer.load(f"ma2023-{'boom' if j % 2 == 0 else 'quadrilateral'}", overrides).params)
    return params


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=256)
    parser.add_argument("--days", type=float, default=250.0)
    parser.add_argument("--single", type=int, default=2, help="transfers run one at a time for the ratio")
    args = parser.parse_args()
    sc = transfer.load("ma2023-boom")
    params = dispersed(args.batch)
    metrics, _, wall_s, compile_s = transfer.run_batch(sc, transfer.stack(params), days=args.days)
    run_s = wall_s - compile_s
    static = transfer.static_for(sc, args.days)
    grid = transfer.env_grid(sc, static)
    one = jax.jit(transfer.transfer, static_argnums=2)
    jax.block_until_ready(one(params[0], grid, static))  # compile
    start = time.perf_counter()
    for p in params[:args.single]:
        jax.block_until_ready(one(p, grid, static))
    single_s = (time.perf_counter() - start) / args.single
    per = run_s / args.batch
    row = {"batch": args.batch, "days": args.days, "devices": jax.device_count(), "cores": os.cpu_count(),
           "compile_s": compile_s, "run_s": run_s, "s_per_transfer": per, "s_per_transfer_one_at_a_time": single_s,
           "batching_ratio": single_s / per, "us_per_transfer_step": 1e6 * per / (args.days * 86400 / sc.step_s),
           "reached_geo": float(np.mean(metrics["status"] == 1)), "mean_transfer_days": float(np.mean(metrics["transfer_days"]))}
    print(row, flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "transfer.json").write_text(json.dumps(row, indent=2))
    lines = [f"# GTO-GEO transfers (Ma 2023), batch of {args.batch}, {args.days:g}-day limit", "",
             f"`python benchmarks/transfer.py --batch {args.batch} --days {args.days:g}` on {os.cpu_count()} CPU cores "
             f"({jax.device_count()} XLA devices), shared with other work. One compilation for the batch "
             "(half boom, half quadrilateral; dispersed start orbits).", "",
             "| batch | compile s | run s | s per transfer (batched) | s per transfer (one at a time) | ratio | "
             "µs per transfer step | reached GEO | mean days |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
             f"| {args.batch} | {compile_s:.1f} | {run_s:.1f} | {per:.3f} | {single_s:.3f} | {single_s / per:.1f}x | "
             f"{row['us_per_transfer_step']:.2f} | {100 * row['reached_geo']:.0f} % | {row['mean_transfer_days']:.1f} |"]
    (RESULTS / "transfer.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
