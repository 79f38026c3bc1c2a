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

import os

os.environ.setdefault("XLA_FLAGS", f"--xla_force_host_platform_device_count={os.cpu_count() or 1}")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from geojax.physics import constants as c  # noqa: E402
from geojax import scenario  # noqa: E402
from geojax.loop.rollout import rollout_fn  # noqa: E402
from geojax.loop.setup import prepare  # noqa: E402
from geojax.papers import LI2022  # noqa: E402  (Sec. 5.1: s per orbit)
from geojax.parallel import replicate, shard_batch  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
PAPER_S_PER_ORBIT = {**{kind: float(row["cpu_s_per_orbit"]) for kind, row in LI2022.items()}, "mpc": None}


def speedup_cell(speedup) -> str:
    return f"{speedup:.0f}x" if speedup else "n/a"


def kept_rows(path: Path, measured) -> list:
    """The rows of an earlier results file for the controllers this run does not measure."""
    if not path.exists():
        return []
    return [r for r in json.loads(path.read_text())["rows"] if r["controller"] not in measured]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--batches", type=int, nargs="+", default=[1, 256])
    parser.add_argument("--controllers", nargs="+", choices=sorted(PAPER_S_PER_ORBIT), default=["qffc", "fompc"])
    args = parser.parse_args()
    rows = []
    for controller in args.controllers:
        sc = scenario.load(f"li2022-{controller}", {"duration.days": args.days, "errors.h_rv": 1.0, "errors.h_att": 1.0})
        setup = prepare([sc])
        setup = setup._replace(shared=replicate(setup.shared))
        for batch in args.batches:
            one = rollout_fn(setup, lanes=max(1, batch // jax.device_count()))
            batched = jax.jit(jax.vmap(lambda p, k, one=one: one(p, k)[:2]))
            states = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x[0], (batch,) + x.shape[1:]), setup.params)
            keys = jax.vmap(lambda i: jax.random.fold_in(jax.random.key(0), i))(jnp.arange(batch))
            if batch % jax.device_count() == 0:
                states, keys = shard_batch((states, keys))
            t = time.perf_counter()
            compiled = batched.lower(states, keys).compile()
            compile_s = time.perf_counter() - t
            t = time.perf_counter()
            final, rec = jax.block_until_ready(compiled(states, keys))
            run_s = time.perf_counter() - t
            dv_year = np.asarray(final.dv_mps) * 365.25 * 86400 / (setup.n_cycles * c.SIDEREAL_DAY_S)
            per_orbit = run_s / (setup.n_cycles * batch)
            paper = PAPER_S_PER_ORBIT[controller]
            rows.append({"controller": controller, "days": args.days, "batch": batch, "cycles": setup.n_cycles,
                         "compile_s": compile_s, "run_s": run_s, "s_per_orbit_per_sample": per_orbit,
                         "speedup_vs_paper": paper / per_orbit if paper else None,
                         "dv_per_year_mps_mean": float(dv_year.mean()), "dv_per_year_mps_std": float(dv_year.std())})
            print(rows[-1], flush=True)
    RESULTS.mkdir(exist_ok=True)
    rows = kept_rows(RESULTS / "simulate.json", args.controllers) + rows
    rows.sort(key=lambda r: (list(PAPER_S_PER_ORBIT).index(r["controller"]), r["batch"]))
    (RESULTS / "simulate.json").write_text(json.dumps({"devices": jax.device_count(), "rows": rows}, indent=2))
    lines = [
        "# Closed loop, li2022-qffc, li2022-fompc and li2022-mpc, H_rv = H_att = 1",
        "",
        f"`python benchmarks/simulate.py` on {os.cpu_count()} CPU cores ({jax.device_count()} XLA devices). "
        f"Li 2022: {LI2022['qffc']['cpu_s_per_orbit']} s (QFFC) and {LI2022['fompc']['cpu_s_per_orbit']} s (FOMPC) per orbit "
        "(Fortran, i7-9700K, one sample); no timing for an MPC.",
        "",
        "| controller | days | batch | cycles | compile s | run s | s per orbit per sample | vs Li 2022 | "
        "ΔV mean ± std (m/s/yr) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    lines += [f"| {r['controller']} | {r.get('days', 365.25):g} | {r['batch']} | {r['cycles']} | {r['compile_s']:.1f} | "
              f"{r['run_s']:.1f} | {r['s_per_orbit_per_sample']:.2e} | "
              f"{speedup_cell(r['speedup_vs_paper'])} | "
              f"{r['dv_per_year_mps_mean']:.2f} ± {r['dv_per_year_mps_std']:.2f} |" for r in rows]
    (RESULTS / "simulate.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
