"""The filter's cost: a QFFC sweep determined by the extended Kalman filter against the same sweep with Li's
Gaussian fix.

    python benchmarks/navigation.py [--days 60] [--batch 32]

li2022-qffc-ranging (the filter on two stations' ranging, every burn flown with execution errors;
``geojax.states.navigation``) against li2022-qffc with Li's nominal Gaussian errors (H_rv = H_att = 1), ``--batch``
samples with their own draws sharded over one XLA CPU device per core, each compiled once and timed after
compilation, the best of three runs (``benchmarks/simulate.py``'s measure).  The figure is the ratio of
sample-years per second, filter over fix (the target: at least 0.5); the memory per sample is the filter's carried
state and its per-cycle record, counted from their shapes.  Results: ``benchmarks/results/navigation.json`` and
``.md``.
"""

from __future__ import annotations

import argparse

import harness
from simulate import measure

NAME = "navigation"
TARGET_RATIO = 0.5


def state_bytes() -> dict:
    """Bytes per sample of the filter's carried state and of one cycle's record (float64, from the shapes the
    loop traces for li2022-qffc-ranging)."""
    import jax
    import numpy as np

    from geojax import scenario
    from geojax.runner.setup import prepare
    from geojax.loop.simulate import position_velocity
    from geojax.states import navigation

    setup = prepare([scenario.load("li2022-qffc-ranging", {"duration.days": 1})])
    params = jax.tree_util.tree_map(lambda x: x[0], setup.params)
    model = setup.states[-1]
    fm = params.forces
    env0 = jax.tree_util.tree_map(lambda x: x[0, 0, 0], setup.shared.env)
    r0, v0 = position_velocity(setup.dynamics, params.initial.orbit, fm.mu_m3_s2)
    state = jax.eval_shape(lambda: model.init(params, r0, v0, env0, fm))
    record = jax.eval_shape(lambda s: navigation.summary(params, s, s, ()), state)
    size = lambda tree: int(sum(np.prod(x.shape) * 8 for x in jax.tree_util.tree_leaves(tree)))  # noqa: E731
    return {"state_bytes": size(state), "cycle_record_bytes": size(record)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=60.0)
    parser.add_argument("--batch", type=int, default=32)
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))
    rows = [measure("qffc", args.days, args.batch, "li2022-qffc", repeats=3),
            measure("qffc", args.days, args.batch, "li2022-qffc-ranging", repeats=3, errors={})]
    for row in rows:
        row["sample_years_per_s"] = row["batch"] * row["days"] / 365.25 / row["run_s"]
    ratio = rows[1]["sample_years_per_s"] / rows[0]["sample_years_per_s"]
    memory = state_bytes()
    per_year = memory["cycle_record_bytes"] * 366
    body = [f"The same {args.batch} samples of Li's QFFC satellite for {args.days:g} days, determined by the "
            "extended Kalman filter (two stations' ranging, execution errors 2 % and 0.1°) and by Li's Gaussian fix "
            "(H_rv = H_att = 1), one XLA CPU device per core, timed after compilation (the best of three runs).", "",
            *harness.table(["scenario", "compile s", "run s", "sample-years per s", "ΔV mean (m/s/yr)"],
                           [[r["scenario"], f"{r['compile_s']:.1f}", f"{r['run_s']:.2f}",
                             f"{r['sample_years_per_s']:.1f}", f"{r['dv_per_year_mps_mean']:.2f}"] for r in rows],
                           align="lrrrr"),
            "", f"With the filter at **{ratio:.2f}×** the sample-years per second of the Gaussian fix "
                f"(target ≥ {TARGET_RATIO}: {'met' if ratio >= TARGET_RATIO else 'not met'}).",
            "", f"Memory per sample: the filter's carried state {memory['state_bytes']} bytes, its record "
                f"{memory['cycle_record_bytes']} bytes per cycle ({per_year / 1024:.1f} KiB per sample-year)."]
    print(harness.write(args.out / NAME, run, "The filter's cost in a QFFC sweep",
                        {"rows": rows, "ratio": ratio, **memory}, body))


if __name__ == "__main__":
    main()
