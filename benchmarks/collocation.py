"""A cluster's cost: ``collocation-4`` (four satellites in one compiled loop, their separations computed every
step) against the same four satellites flown as four lone samples of one batch.

    python benchmarks/collocation.py [--days 10] [--clusters 2]

``--clusters`` copies of the cluster (each with its own draws; Li's nominal errors H_rv = H_att = 1) against
4 x ``--clusters`` lone samples of its satellites, each compiled once and timed after compilation, the best of
three runs, sharded over one XLA CPU device per core where the count divides.  The figure is the ratio of
satellite-years per second, cluster over lone (the target: the cluster at most 1.2x the lone cost, a ratio of
at least 1 / 1.2 = 0.83).  Results: ``benchmarks/results/collocation.json`` and ``.md``.
"""

from __future__ import annotations

import argparse

import harness

NAME = "collocation"
TARGET_RATIO = 1 / 1.2


def measure(days: float, clusters: int) -> list[dict]:
    import jax
    import jax.numpy as jnp

    from geojax import scenario
    from geojax.collocation.run import cluster_rollout, satellite_keys
    from geojax.parallel import shard_batch
    from geojax.physics.propagate import for_lanes
    from geojax.runner.rollout import rollout_fn
    from geojax.runner.setup import prepare

    sc = scenario.load("collocation-4", {"duration.days": days, "errors.h_rv": 1.0, "errors.h_att": 1.0})
    batch = prepare(list(sc.satellites))
    names = tuple(m.name for m in sc.satellites)
    n = len(names)
    steps_per_cycle = batch.shared.env.earth_angle_rad.shape[1]
    reference_env = batch.reference_env if batch.reference_per_sample else None
    repeat = lambda tree, k: jax.tree_util.tree_map(lambda x: jnp.stack([x] * k), tree)  # noqa: E731
    keys = jnp.stack([jax.random.key_data(satellite_keys(seed, names)) for seed in range(clusters)])
    keys = jax.random.wrap_key_data(keys)

    def cluster_fn(params, keys):
        out = cluster_rollout(params, keys, batch.shared, reference_env, jnp.asarray(2e3), controller=batch.controller,
                              step_s=batch.step_s, dynamics=for_lanes(batch.dynamics, n * clusters),
                              keep_steps=False, states=batch.states, steps_per_cycle=steps_per_cycle)
        return out[0], out[4]["min_separation_km"]

    one = rollout_fn(batch, lanes=n * clusters)
    lone_fn = jax.jit(jax.vmap(lambda p, k: one(p, k)[0]))
    rows = []
    cluster_args = (repeat(batch.params, clusters), keys)
    lone_args = (jax.tree_util.tree_map(lambda x: x.reshape((n * clusters,) + x.shape[2:]), cluster_args[0]),
                 keys.reshape((n * clusters,)))
    for label, fn, args, count in (("cluster", jax.jit(jax.vmap(cluster_fn)), cluster_args, clusters),
                                   ("lone", lone_fn, lone_args, n * clusters)):
        if count % jax.device_count() == 0:
            args = shard_batch(args)
        compiled, compile_s = harness.compile_jitted(fn, *args)
        _, timing = harness.measure(compiled, *args, repeats=3)
        rows.append({"run": label, "satellites": n * clusters, "days": days, "compile_s": compile_s,
                     "run_s": timing.best_s, "satellite_years_per_s": n * clusters * days / 365.25 / timing.best_s})
        print(rows[-1], flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=10.0)
    parser.add_argument("--clusters", type=int, default=2)
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))
    rows = measure(args.days, args.clusters)
    ratio = rows[0]["satellite_years_per_s"] / rows[1]["satellite_years_per_s"]
    body = [f"{args.clusters} clusters of collocation-4 (four QFFC satellites, Li's nominal errors) for {args.days:g} "
            f"days against their {4 * args.clusters} satellites flown alone in one batch, one XLA CPU device per "
            "core, timed after compilation (the best of three runs).", "",
            *harness.table(["run", "satellites", "compile s", "run s", "satellite-years per s"],
                           [[r["run"], r["satellites"], f"{r['compile_s']:.1f}", f"{r['run_s']:.2f}",
                             f"{r['satellite_years_per_s']:.2f}"] for r in rows], align="lrrrr"),
            "", f"The cluster at **{ratio:.2f}×** the satellite-years per second of the lone satellites "
                f"(target ≥ {TARGET_RATIO:.2f}, a cluster costing at most 1.2× its satellites alone: "
                f"{'met' if ratio >= TARGET_RATIO else 'not met'})."]
    print(harness.write(args.out / NAME, run, "A cluster's cost against its satellites alone",
                        {"rows": rows, "ratio": ratio}, body))


if __name__ == "__main__":
    main()
