"""The ``geojax`` command line.

    geojax demo [--out DIR]
    geojax propagate SCENARIO [--days D] [--step S] [--out FILE.h5]
    geojax simulate SCENARIO [--controller qffc|fompc] [--horizon N] [--days D] [--seed S] [--out FILE.h5] [--plots DIR]
    geojax sweep SWEEP.toml --out FILE.h5 [--resume] [--chunk N] [--ray [ADDRESS]] [--workers N]
    geojax tune TUNE.toml --out FILE.h5 [--quiet]
    geojax plot FILE.h5 [--out DIR]
    geojax scenarios

Bad input (an unknown scenario, a field of the wrong type or out of range)
prints one line naming the field and what is allowed, and exits with status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXIT_BAD_INPUT = 2


def main(argv: list[str] | None = None) -> int:
    from geojax.parallel import use_host_cores

    use_host_cores()  # batches (sweeps) are sharded over one XLA CPU device per core
    parser = _parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return EXIT_BAD_INPUT
    try:
        return args.func(args) or 0
    except ValueError as err:
        print(f"geojax {args.command}: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeError as err:
        from geojax.cluster import ClusterError

        if not isinstance(err, ClusterError):
            raise
        print(f"geojax {args.command}: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"geojax {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `geojax scenarios | head`: the reader left; say nothing more
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


def _version() -> str:
    import geojax

    return geojax.__version__


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="geojax",
        description="Closed-loop station keeping of electric-propulsion GEO satellites in JAX.",
    )
    parser.add_argument("--version", action="version", version=f"geojax {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    demo = sub.add_parser("demo", help="li2022 for one year, without control and with the QFFC: summaries, figures")
    demo.add_argument("--out", default="geojax-demo", help="folder for the figure and HDF5 file (default: geojax-demo)")
    demo.set_defaults(func=_demo)

    prop = sub.add_parser("propagate", help="uncontrolled propagation; one-cycle mean elements per sidereal day")
    prop.add_argument("scenario", help="a shipped scenario name (see 'geojax scenarios') or a .toml path")
    prop.add_argument("--days", type=float, help="duration in days (default: the scenario's)")
    prop.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    prop.add_argument("--out", help="write the per-cycle mean elements to this HDF5 file")
    prop.add_argument("--quiet", action="store_true", help="no progress bar")
    prop.set_defaults(func=_propagate)

    sim = sub.add_parser("simulate", help="closed-loop station keeping (any controller); summary, metrics, status, HDF5")
    sim.add_argument("scenario", help="a scenario with a [controller] table, e.g. li2022-qffc, li2022-fompc, or a .toml path")
    sim.add_argument("--controller", help="override controller.kind (qffc, fompc, lyapunov, ...)")
    sim.add_argument("--horizon", type=int, help="FOMPC prediction horizon N in cycles, 1-10 (default: the scenario's)")
    sim.add_argument("--days", type=float, help="duration in days (default: the scenario's)")
    sim.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    sim.add_argument("--seed", type=int, default=0, help="seed of the orbit-determination and attitude errors (default 0)")
    sim.add_argument("--h-rv", type=float, help="orbit-determination error level H_rv (Li 2022 eq. 48; default: the scenario's)")
    sim.add_argument("--h-att", type=float, help="attitude error level H_att (default: the scenario's)")
    sim.add_argument("--out", help="write /metrics and /cycles to this HDF5 file")
    sim.add_argument("--plots", help="folder for the mean-element figure")
    sim.set_defaults(func=_simulate)

    tune = sub.add_parser("tune", help="tune Milankovitch-Lyapunov gains by gradients through the rollout (Katz 2025)")
    tune.add_argument("file", help="a tuning file (TOML; see geojax.tune for the keys)")
    tune.add_argument("--out", required=True, help="results file (HDF5): /iterations per iteration, /best, /metrics")
    tune.add_argument("--quiet", action="store_true", help="no per-iteration lines")
    tune.set_defaults(func=_tune)

    swp = sub.add_parser("sweep", help="Monte Carlo sweep over scenario parameters x repetitions x controllers; HDF5")
    swp.add_argument("file", help="a sweep file (TOML; see geojax.sweep for the keys)")
    swp.add_argument("--out", required=True, help="results file (HDF5); chunks are kept in FILE.h5.parts/ until done")
    swp.add_argument("--resume", action="store_true", help="continue an interrupted sweep into the same --out")
    swp.add_argument("--chunk", type=int, help="samples per saved chunk (default: one compiled batch of the widest "
                     "controller, 64 per device; a resumed sweep keeps its cut)")
    swp.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                     help="run the chunks as Ray tasks: alone, on a Ray instance started here; 'auto', HOST:PORT or "
                     "ray://HOST:PORT, on a running cluster (pip install \"geojax[ray]\"); same results as a local run")
    swp.add_argument("--workers", type=int, help="with --ray: worker processes (default one per node, each using "
                     "its node's cores)")
    swp.add_argument("--quiet", action="store_true", help="no progress bar")
    swp.set_defaults(func=_sweep)

    plot = sub.add_parser("plot", help="draw the figures of a results file")
    plot.add_argument("file", help="an HDF5 file written by geojax")
    plot.add_argument("--out", help="folder for the figures (default: next to the file)")
    plot.set_defaults(func=_plot)

    scen = sub.add_parser("scenarios", help="list the shipped scenarios, or print one's TOML")
    scen.add_argument("--show", metavar="NAME", help="print the TOML of the shipped scenario NAME")
    scen.set_defaults(func=_scenarios)
    return parser


def _overrides(args) -> dict:
    overrides = {}
    if args.days is not None:
        overrides["duration.days"] = args.days
    if args.step is not None:
        overrides["integration.step_s"] = args.step
    return overrides


def _propagate(args) -> int:
    from geojax import scenario, store
    from geojax import uncontrolled as run

    sc = scenario.load(args.scenario, _overrides(args))
    result = run.propagate_scenario(sc, progress=None if not args.quiet else False)
    summary = run.drift_summary(result.cycles, sc.days)
    _print_summary(sc, result, summary)
    if args.out:
        path = store.write_h5(
            args.out,
            {"cycles": run.cycles_table(result.cycles)},
            scenario.to_toml(sc.config),
            result.wall_s,
            attrs={"kind": "propagate", "scenario": sc.name, "epoch_tt_s": sc.epoch_tt_s, "step_s": result.step_s},
        )
        print(f"wrote {path}")
    return 0


# Li 2022, Sec. 5.1 and Table 2.
PAPER = {
    "qffc": {"dv_per_year_mps": "60.2", "burns_total": "728", "burns_per_thruster_per_orbit": "0.997",
             "max_abs_mean_dlon_deg": "~0.013", "max_abs_de": "~1.1e-4", "cpu_s_per_orbit": "0.09"},
    "fompc": {"dv_per_year_mps": "54.2", "burns_total": "721", "burns_per_thruster_per_orbit": "0.988",
              "max_abs_mean_dlon_deg": "~0.013", "max_abs_de": "~1.1e-4", "cpu_s_per_orbit": "57.4"},
}


def _simulate(args) -> int:
    from geojax import plots, scenario, store
    from geojax.loop.metrics import STATUS_MEANINGS
    from geojax.loop.rollout import reference_and_target, simulate
    from geojax.tune import PAPER as KATZ

    overrides = _overrides(args)
    if args.controller:
        overrides["controller.kind"] = args.controller
    if args.horizon is not None:
        overrides["controller.horizon"] = args.horizon
    if args.h_rv is not None:
        overrides["errors.h_rv"] = args.h_rv
    if args.h_att is not None:
        overrides["errors.h_att"] = args.h_att
    if args.seed < 0:
        raise ValueError(f"--seed: must be an integer >= 0, got {args.seed}")
    sc = scenario.load(args.scenario, overrides)
    if sc.controller == "none":
        raise ValueError(f"controller.kind: {sc.name} has no controller; give --controller or use 'geojax propagate'")
    _check_outputs(args)
    print(f"{sc.name}: {sc.controller} for {sc.days:g} days (compiling, then running)...", flush=True)
    feedback = sc.controller == "lyapunov"
    result = simulate(sc, args.seed, keep_steps=feedback)
    cycles = result.cycles()
    print(f"{sc.name}: {sc.controller}, {len(cycles['t_s'])} cycles, {result.wall_s:.1f} s wall, "
          f"status {int(result.status)} ({STATUS_MEANINGS[int(result.status)]})")
    if feedback:
        mode = sc.config["controller"]["thrust_mode"]
        paper, source = (KATZ.get(mode, {}), "Katz 2025") if sc.name.startswith("katz2025") else ({}, "")
    else:
        paper, source = (PAPER.get(sc.controller, {}), "Li 2022") if sc.name.startswith("li2022") else ({}, "")
    metrics = {**{k: float(v) for k, v in result.metrics.items()}, "cpu_s_per_orbit": result.wall_s / len(cycles["t_s"])}
    print(f"  {'metric':32s} {'geojax':>12s}  {source}")
    for name, value in metrics.items():
        print(f"  {name:32s} {value:12.5g}  {paper.get(name, '')}")
    groups = {"metrics": {**metrics, "status": int(result.status)}, "cycles": cycles}
    steps = _steps_table(result) if feedback else None
    if steps is not None:
        groups["steps"] = steps
    else:
        groups["reference"], groups["target"] = reference_and_target(sc, len(result.records.cycles.dv_mps))
    if args.out:
        path = store.write_h5(args.out, groups, scenario.to_toml(sc.config), result.wall_s,
                              attrs={"kind": "simulate", "scenario": sc.name, "epoch_tt_s": sc.epoch_tt_s,
                                     "seed": args.seed, "status_codes": _status_text()})
        print(f"wrote {path}")
    if args.plots:
        title = f"{sc.name}, {sc.controller}"
        if steps is not None:
            figures = plots.plot_feedback(steps, sc.config["station"]["box_half_width_deg"], Path(args.plots) / sc.name,
                                          title=f"{sc.name}, {sc.config['controller']['thrust_mode']} thrust")
        else:
            figures = [plots.plot_cycles(cycles, Path(args.plots) / f"{sc.name}.png", title=title),
                       plots.plot_station_keeping(cycles, groups["reference"], groups["target"],
                                                  Path(args.plots) / f"{sc.name}-station-keeping.png", title=title)]
        print("wrote " + " and ".join(map(str, figures)))
    return 0


def _status_text() -> str:
    from geojax.loop.metrics import STATUS_TEXT

    return STATUS_TEXT


def _steps_table(result) -> dict:
    from geojax.loop.metrics import step_table

    return step_table(result.records, result.step_s, float(result.params.station["lon_rad"]))


def _check_outputs(args) -> None:
    """Output paths are checked before any computation (a run never finds out after an hour that it cannot save)."""
    from geojax.store import check_output_file

    if getattr(args, "out", None):
        check_output_file(args.out)
    if getattr(args, "plots", None):
        plots = Path(args.plots)
        if plots.exists() and not plots.is_dir():
            raise ValueError(f"--plots {str(plots)!r}: exists and is not a folder")


def _tune(args) -> int:
    from geojax import scenario, tune

    spec = tune.load(args.file)
    _check_outputs(args)
    result = tune.tune(spec, out=args.out, verbose=not args.quiet)
    print(f"{spec.scenario.name}: {result.message}; {result.wall_s:.1f} s wall")
    if result.best_params is None:
        print("  no feasible point: every iterate left the box with the exact law")
        return 1
    fields = scenario.controller_fields(spec.scenario.config["controller"], spec.controller)
    for name, value in tune.paper_units(result.best_params, fields).items():
        print(f"  {name:24s} {value:.6g}")
    print(f"  ΔV (exact law, full horizon)  {result.best_dv_per_year_mps:.3f} m/s/yr, box kept "
          f"(constraint lon {result.best_constraint[0]:+.4f}, lat {result.best_constraint[1]:+.4f})")
    print(f"wrote {args.out}")
    return 0


def _print_summary(sc, result, summary) -> None:
    print(f"{sc.name}: {len(result.cycles.t_s)} sidereal-day cycles, step {result.step_s:.2f} s, "
          f"{sc.dynamics.upper()} RK4, {result.wall_s:.1f} s wall")
    print(f"  mean inclination       {summary.i_start_deg:.4f} deg -> {summary.i_end_deg:.4f} deg")
    print(f"  inclination-vector change  {summary.di_deg:.4f} deg towards {summary.di_direction_deg:.1f} deg "
          f"over {summary.elapsed_days:.1f} days")
    print(f"  mean longitude drift   {summary.dlon_deg:+.4f} deg")
    print(f"  largest |e - e0|       {summary.de_max:.3e}")


def _demo(args) -> int:
    from geojax import plots, scenario, store
    from geojax import uncontrolled as run

    out = Path(args.out)
    sc = scenario.load("li2022")
    print("geojax demo 1/2: one year of li2022 without station keeping (Li 2022 initial state, J2 + Sun + Moon + SRP)")
    result = run.propagate_scenario(sc)
    summary = run.drift_summary(result.cycles, sc.days)
    _print_summary(sc, result, summary)
    table = run.cycles_table(result.cycles)
    h5 = store.write_h5(out / "li2022-uncontrolled.h5", {"cycles": table}, scenario.to_toml(sc.config), result.wall_s,
                        attrs={"kind": "propagate", "scenario": sc.name, "epoch_tt_s": sc.epoch_tt_s, "step_s": result.step_s})
    figure = plots.plot_cycles(table, out / "li2022-uncontrolled.png", title="li2022, no control, one year")
    print(f"wrote {h5} and {figure}")
    print()
    print("geojax demo 2/2: the same year with QFFC station keeping (li2022-qffc, normal arm limits)")
    args_sim = argparse.Namespace(scenario="li2022-qffc", controller=None, horizon=None, days=None, step=None, seed=0, h_rv=None, h_att=None,
                                  out=str(out / "li2022-qffc.h5"), plots=str(out))
    return _simulate(args_sim)


def _sweep(args) -> int:
    import numpy as np

    from geojax import store, sweep

    spec = sweep.load(args.file)
    _check_outputs(args)
    n = spec.n_points * spec.repetitions
    print(f"{spec.name}: {len(spec.controllers)} controller(s) x {spec.n_points} grid point(s) x "
          f"{spec.repetitions} repetition(s) = {len(spec.controllers) * n} samples", flush=True)
    path = sweep.run_sweep(spec, args.out, resume=args.resume, chunk=args.chunk, progress=False if args.quiet else None,
                           ray=args.ray, workers=args.workers)
    groups, _ = store.read_h5(path)
    dv = groups["metrics"]["dv_per_year_mps"]
    from geojax.loop.metrics import STATUS_MEANINGS

    for i, controller in enumerate(spec.controllers):
        codes = groups["status"]["code"][i]
        counts = ", ".join(f"{int(np.sum(codes == c))} {STATUS_MEANINGS[c]}" for c in range(1, len(STATUS_MEANINGS))
                           if np.any(codes == c))
        print(f"  {controller}: ΔV per year {np.nanmean(dv[i]):.2f} m/s/yr averaged over the sweep; "
              f"{counts or 'every sample ok'}")
    print(f"wrote {path}")
    return 0


def _plot(args) -> int:
    from geojax import plots, store

    path = Path(args.file)
    if not path.is_file():
        raise ValueError(f"file {str(path)!r}: no such file")
    try:
        groups, attrs = store.read_h5(path)
    except OSError:
        raise ValueError(f"file {str(path)!r}: not an HDF5 file") from None
    out = Path(args.out) if args.out else path.parent
    if attrs.get("kind") == "sweep":
        figure = plots.plot_sweep(groups, str(attrs["grid_axes"]).split(","), out / f"{path.stem}.png",
                                  title=str(attrs.get("name", path.stem)))
        print(f"wrote {figure}")
        return 0
    if "steps" in groups:  # a feedback run (Katz 2025)
        box = _box_half_width_deg(attrs)
        figures = plots.plot_feedback(groups["steps"], box, out / path.stem, title=str(attrs.get("scenario", path.stem)))
        print("wrote " + " and ".join(map(str, figures)))
        return 0
    if "cycles" not in groups:
        raise ValueError(f"file {str(path)!r}: no /cycles group to plot")
    title = str(attrs.get("scenario", path.stem))
    figures = [plots.plot_cycles(groups["cycles"], out / f"{path.stem}.png", title=title)]
    if {"reference", "target"} <= set(groups):
        figures.append(plots.plot_station_keeping(groups["cycles"], groups["reference"], groups["target"],
                                                  out / f"{path.stem}-station-keeping.png", title=title))
    print("wrote " + " and ".join(map(str, figures)))
    return 0


def _box_half_width_deg(attrs) -> float:
    """The box half-width (deg) of the scenario stored with a results file."""
    from geojax import scenario

    return float(scenario.from_dict(scenario.tomllib.loads(str(attrs["config_toml"]))).config["station"]["box_half_width_deg"])


def _scenarios(args) -> int:
    from geojax import scenario

    if args.show:
        print(scenario.read_text(args.show), end="")
        return 0
    names = scenario.available()
    width = max(map(len, names))
    for name in names:
        print(f"{name:{width}s}  {scenario.load(name).config['description']}")
    print(f"\n`geojax scenarios --show NAME` prints a scenario's TOML (to copy and edit: "
          f"`geojax scenarios --show li2022-qffc > mine.toml`).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
