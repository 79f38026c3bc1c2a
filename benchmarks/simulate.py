"""Closed-loop station keeping, one year of li2022-qffc, li2022-fompc and li2022-mpc: seconds per simulated orbit.

    python benchmarks/simulate.py [--days 365.25] [--batches 1 256] [--controllers qffc fompc mpc]

A run replaces the rows of the controllers it measures and keeps the others' (each row names its days).
The MPC's target (issue 14): under 0.02 s per orbit per sample at batch 256 on 2 cores.

Each sample is the same scenario with its own error draw (H_rv = H_att = 1,
Li 2022 eq. (48)), so the batch is a Monte Carlo set.  geojax shards the batch
over one XLA CPU device per core (``geojax.parallel``).  Li 2022 reports
0.09 s (QFFC) and 57.4 s (FOMPC) per orbit on an i7-9700K (Fortran, one
sample at a time).
Results: ``benchmarks/results/simulate.json`` and ``.md``.
"""

from __future__ import annotations

import argparse

import harness

from geojax.papers import LI2022  # Sec. 5.1 and Table 2: s per orbit

NAME = "simulate"
PAPER_S_PER_ORBIT = {**{kind: float(row["cpu_s_per_orbit"]) for kind, row in LI2022.items()}, "mpc": None}


def speedup_cell(speedup) -> str:
    return f"{speedup:.0f}x" if speedup else "n/a"


def kept_rows(stem, measured) -> list:
    """The rows of an earlier results file for the controllers this run does not measure."""
    if not stem.with_suffix(".json").exists():
        return []
    return [r for r in harness.read(stem)[1]["rows"] if r["controller"] not in measured]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--batches", type=int, nargs="+", default=[1, 256])
    parser.add_argument("--controllers", nargs="+", choices=sorted(PAPER_S_PER_ORBIT), default=["qffc", "fompc"])
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))
    rows = [measure(controller, args.days, batch) for controller in args.controllers
            for batch in args.batches]
    rows = kept_rows(args.out / NAME, args.controllers) + rows
    rows.sort(key=lambda r: (list(PAPER_S_PER_ORBIT).index(r["controller"]), r["batch"]))
    print(harness.write(args.out / NAME, run, "Closed loop, li2022-qffc, li2022-fompc and li2022-mpc, H_rv = H_att = 1",
                        {"rows": rows}, markdown(rows)))


def measure(controller: str, days: float, batch: int, name: str | None = None, repeats: int = 1,
            errors: dict | None = None) -> dict:
    """One row: ``batch`` samples of ``li2022-<controller>`` (or of the scenario ``name``) with their own error
    draws (``errors``: the overrides that set them; Li's nominal H_rv = H_att = 1 by default), compiled once; the
    best of ``repeats`` runs."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from geojax import scenario
    from geojax.runner.rollout import rollout_fn
    from geojax.runner.setup import prepare
    from geojax.parallel import replicate, shard_batch
    from geojax.physics import constants as c

    errors = {"errors.h_rv": 1.0, "errors.h_att": 1.0} if errors is None else errors
    sc = scenario.load(name or f"li2022-{controller}", {"duration.days": days, **errors})
    setup = prepare([sc])
    setup = setup._replace(shared=replicate(setup.shared))
    one = rollout_fn(setup, lanes=max(1, batch // jax.device_count()))
    batched = jax.jit(jax.vmap(lambda p, k: one(p, k)[:2]))
    states = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x[0], (batch,) + x.shape[1:]), setup.params)
    keys = jax.vmap(lambda i: jax.random.fold_in(jax.random.key(0), i))(jnp.arange(batch))
    if batch % jax.device_count() == 0:
        states, keys = shard_batch((states, keys))
    compiled, compile_s = harness.compile_jitted(batched, states, keys)
    (final, _), timing = harness.measure(compiled, states, keys, repeats=repeats)
    dv_year = np.asarray(final.dv_mps) * 365.25 * 86400 / (setup.n_cycles * c.SIDEREAL_DAY_S)
    per_orbit = timing.best_s / (setup.n_cycles * batch)
    paper = PAPER_S_PER_ORBIT[controller]
    row = {"controller": controller, "scenario": sc.name, "days": days, "batch": batch, "cycles": setup.n_cycles,
           "devices": jax.device_count(), "compile_s": compile_s, "run_s": timing.best_s,
           "s_per_orbit_per_sample": per_orbit, "speedup_vs_paper": paper / per_orbit if paper else None,
           "dv_per_year_mps_mean": float(dv_year.mean()), "dv_per_year_mps_std": float(dv_year.std())}
    print(row, flush=True)
    return row


def markdown(rows: list[dict]) -> list[str]:
    return [f"Each batch sharded over one XLA CPU device per core. Li 2022: {LI2022['qffc']['cpu_s_per_orbit']} s "
            f"(QFFC) and {LI2022['fompc']['cpu_s_per_orbit']} s (FOMPC) per orbit (Fortran, i7-9700K, one sample); "
            "no timing for an MPC.", "",
            *harness.table(["controller", "days", "batch", "cycles", "compile s", "run s", "s per orbit per sample",
                            "vs Li 2022", "ΔV mean ± std (m/s/yr)"],
                           [[r["controller"], f"{r.get('days', 365.25):g}", r["batch"], r["cycles"],
                             f"{r['compile_s']:.1f}", f"{r['run_s']:.1f}", f"{r['s_per_orbit_per_sample']:.2e}",
                             speedup_cell(r["speedup_vs_paper"]),
                             f"{r['dv_per_year_mps_mean']:.2f} ± {r['dv_per_year_mps_std']:.2f}"] for r in rows],
                           align="lrrrrrrrl")]


if __name__ == "__main__":
    main()
