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

import argparse

import numpy as np

import harness

NAME = "transfer"


def dispersed(batch: int, seed: int = 0):
    from geojax import transfer

    rng = np.random.default_rng(seed)
    params = []
    for j in range(batch):
        overrides = {"orbit.perigee_alt_km": 964.0 + rng.uniform(-50, 50),
                     "orbit.apogee_alt_km": 35741.0 + rng.uniform(-200, 200),
                     "orbit.i_deg": 20.8 + rng.uniform(-0.5, 0.5)}
        params.append(transfer.load(f"ma2023-{'boom' if j % 2 == 0 else 'quadrilateral'}", overrides).params)
    return params


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=256)
    parser.add_argument("--days", type=float, default=250.0)
    parser.add_argument("--single", type=int, default=2, help="transfers run one at a time for the ratio")
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))
    row = measure(args.batch, args.days, args.single)
    print(row, flush=True)
    print(harness.write(args.out / NAME, run, f"GTO-GEO transfers (Ma 2023), batch of {args.batch}, "
                        f"{args.days:g}-day limit", row, markdown(row)))


def measure(batch: int, days: float, single: int) -> dict:
    """The batch in one compiled call (``transfer.run_batch``) and ``single`` of its transfers one at a time."""
    import jax

    from geojax import transfer

    sc = transfer.load("ma2023-boom")
    params = dispersed(batch)
    metrics, _, wall_s, compile_s = transfer.run_batch(sc, transfer.stack(params), days=days)
    run_s = wall_s - compile_s
    static = transfer.static_for(sc, days)
    grid = transfer.env_grid(sc, static)
    one = jax.jit(transfer.transfer, static_argnums=2)
    harness.timed(one, params[0], grid, static)  # compiles
    _, timing = harness.measure(lambda: [one(p, grid, static) for p in params[:single]])
    single_s = timing.best_s / single
    per = run_s / batch
    return {"batch": batch, "days": days, "devices": jax.device_count(), "compile_s": compile_s, "run_s": run_s,
            "s_per_transfer": per, "s_per_transfer_one_at_a_time": single_s, "batching_ratio": single_s / per,
            "us_per_transfer_step": 1e6 * per / (days * 86400 / sc.step_s),
            "reached_geo": float(np.mean(metrics["status"] == 1)),
            "mean_transfer_days": float(np.mean(metrics["transfer_days"]))}


def markdown(row: dict) -> list[str]:
    return ["One compilation for the batch (half boom, half quadrilateral; dispersed start orbits), sharded over "
            f"{row['devices']} XLA devices; the one-at-a-time rate is the best of the jitted single transfer "
            "in a Python loop.", "",
            *harness.table(["batch", "compile s", "run s", "s per transfer (batched)", "s per transfer (one at a time)",
                            "ratio", "µs per transfer step", "reached GEO", "mean days"],
                           [[row["batch"], f"{row['compile_s']:.1f}", f"{row['run_s']:.1f}",
                             f"{row['s_per_transfer']:.3f}", f"{row['s_per_transfer_one_at_a_time']:.3f}",
                             f"{row['batching_ratio']:.1f}x", f"{row['us_per_transfer_step']:.2f}",
                             f"{100 * row['reached_geo']:.0f} %", f"{row['mean_transfer_days']:.1f}"]], align="r" * 9)]


if __name__ == "__main__":
    main()
