"""The ``geojax`` command line.

    geojax demo [--out DIR]
    geojax propagate SCENARIO [--days D] [--step S] [--out FILE.h5]
    geojax simulate SCENARIO [--controller qffc|fompc|lyapunov] [--horizon N] [--days D] [--seed S] [--out FILE.h5] [--plots DIR]
    geojax sweep SWEEP.toml --out FILE.h5 [--resume] [--chunk N] [--lanes N] [--ray [ADDRESS]] [--workers N]
    geojax tune TUNE.toml --out FILE.h5
    geojax plot FILE.h5 [--out DIR] [--format png|pdf|svg] [--dpi N]
    geojax scenarios [--show NAME]
    geojax transfer SCENARIO [--days D] [--out FILE.h5]

Every command takes -q (print only the files written) and -v (also compilation times and devices).
``--days D`` means D solar days, run as round(D / sidereal day) cycles, in every command.

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
        hint = ""
        if args.command == "sweep":  # its finished chunks are on disk
            hint = f"; the chunks done are saved: geojax sweep {args.file} --out {args.out} --resume continues"
        print(f"geojax {args.command}: interrupted{hint}", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `geojax scenarios | head`: the reader left; say nothing more
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


def sweep_title(attrs, axes: list[str]) -> str:
    """What a sweep figure shows: its swept key, the sweep's name and the run's length
    ("thrusters.beta_max_deg: fig09, 365.25 days")."""
    from geojax import scenario

    days = ""
    try:
        base = scenario.tomllib.loads(str(attrs.get("base_scenario_toml", "")))
        days = f", {base['duration']['days']:g} days"
    except (ValueError, KeyError, TypeError):
        pass
    return f"{axes[1]}: {attrs.get('name', 'sweep')}{days}"


def flown_days(days: float) -> str:
    """``days`` as a run flies them: whole sidereal-day cycles, named when the rounding is more than 2 %."""
    from geojax.loop.setup import cycle_count
    from geojax.physics.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S

    n = cycle_count(days)
    flown = n * SIDEREAL_DAY_S / SECONDS_PER_DAY
    if abs(flown - days) <= 0.02 * days:
        return f"{days:g} days"
    return f"{days:g} days, flown as {n} sidereal-day cycle{'s' * (n != 1)} ({flown:.3f} days)"


def _version() -> str:
    import geojax

    return geojax.__version__


DAYS_HELP = ("duration in solar days (default: the scenario's); the run is that many sidereal-day cycles, "
             "rounded (20 days: 20 cycles), the same in propagate, simulate, sweep and tune")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="geojax",
        description="Closed-loop station keeping of electric-propulsion GEO satellites in JAX.",
    )
    parser.add_argument("--version", action="version", version=f"geojax {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    common = argparse.ArgumentParser(add_help=False)  # every command: -q / -v
    talk = common.add_mutually_exclusive_group()
    talk.add_argument("-q", "--quiet", action="store_true", help="print only the files written (and errors)")
    talk.add_argument("-v", "--verbose", action="store_true",
                      help="also print compilation times, devices and where each number comes from")

    def command(name, **kw):
        return sub.add_parser(name, parents=[common], **kw)

    demo = command("demo", help="li2022 for one year, without control and with the QFFC: summaries, figures")
    demo.add_argument("--out", default="geojax-demo", help="folder for the figures and HDF5 files (default: geojax-demo)")
    demo.set_defaults(func=_demo)

    prop = command("propagate", help="uncontrolled propagation; one-cycle mean elements per sidereal day")
    prop.add_argument("scenario", help="a shipped scenario name (see 'geojax scenarios') or a .toml path")
    prop.add_argument("--days", type=float, help=DAYS_HELP)
    prop.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    prop.add_argument("--out", help="write the per-cycle mean elements to this HDF5 file")
    prop.set_defaults(func=_propagate)

    bnd = command("bound", help="the least Delta-V that holds the scenario's box with its thrusters (a linear program), "
                                "re-simulated in the closed loop")
    bnd.add_argument("scenario", help="a shipped scenario name or a .toml path (its thrusters, box, forces, epoch)")
    bnd.add_argument("--days", type=float, help=DAYS_HELP)
    bnd.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    bnd.add_argument("--slot-steps", type=int, default=4,
                     help="integration steps per thrust slot (thrust constant in RSW over a slot; default 4: 1 h)")
    bnd.add_argument("--thrusters", choices=("arms", "gimbal", "fixed4", "axes"),
                     help="thruster geometry: Li's two arms, Katz's gimbal, Gazzino's four fixed NE/NW/SE/SW thrusters, "
                          "Katz's per-axis pairs (default: axes for a discrete lyapunov law, gimbal for another "
                          "lyapunov or a zone_nssk scenario, else arms)")
    bnd.add_argument("--acquisition-days", type=float, default=0.0,
                     help="hold the box from this day on (a start the thrusters cannot hold at once; default 0)")
    bnd.add_argument("--free-end", action="store_true",
                     help="no end condition (the free end: the plan may end anywhere in the box); default: periodic, "
                          "the plan ends where it started, x(T) = x(0) (Gazzino 2016), a steady state's Delta-V")
    bnd.add_argument("--out", help="write /metrics, /rounds and the per-slot /slots to this HDF5 file")
    bnd.set_defaults(func=_bound)

    sim = command("simulate", help="closed-loop station keeping (any controller); summary, metrics, status, HDF5")
    sim.add_argument("scenario", help="a scenario with a [controller] table, e.g. li2022-qffc, li2022-fompc, or a .toml path")
    sim.add_argument("--controller", help="override controller.kind (qffc, fompc, lyapunov, ...)")
    sim.add_argument("--horizon", type=int, help="FOMPC prediction horizon N in cycles, 1-10 (default: the scenario's)")
    sim.add_argument("--days", type=float, help=DAYS_HELP)
    sim.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    sim.add_argument("--seed", type=int, default=0, help="seed of the orbit-determination and attitude errors (default 0)")
    sim.add_argument("--h-rv", type=float, help="orbit-determination error level H_rv (Li 2022 eq. 48; default: the scenario's)")
    sim.add_argument("--h-att", type=float, help="attitude error level H_att (default: the scenario's)")
    sim.add_argument("--out", help="write /metrics and /cycles to this HDF5 file")
    sim.add_argument("--plots", help="folder for the figures")
    sim.set_defaults(func=_simulate)

    tune = command("tune", help="tune controller gains by gradients through the rollout (Katz 2025)")
    tune.add_argument("file", help="a tuning file (TOML; see geojax.tune for the keys)")
    tune.add_argument("--out", required=True, help="results file (HDF5): /iterations per iteration, /best, /metrics; "
                      "the tuned scenario is written beside it as FILE-tuned.toml")
    tune.set_defaults(func=_tune)

    swp = command("sweep", help="Monte Carlo sweep over scenario parameters x repetitions x controllers; HDF5")
    swp.add_argument("file", help="a sweep file (TOML; see geojax.sweep for the keys)")
    swp.add_argument("--out", required=True, help="results file (HDF5); chunks are kept in FILE.h5.parts/ until done")
    swp.add_argument("--resume", action="store_true", help="continue an interrupted sweep into the same --out")
    swp.add_argument("--chunk", type=int, help="samples per saved chunk (default: one compiled batch of the widest "
                     "controller on every device; a resumed sweep keeps its cut)")
    swp.add_argument("--lanes", type=int, help="samples per device in one compiled call (default: the platform's, "
                     "128 QFFC / 32 FOMPC / 8 MPC per CPU core, on a GPU the widest batch its memory holds, up to "
                     "65536); the results do not depend on it; one that cannot fit is refused")
    swp.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                     help="run the chunks as Ray tasks: alone, on a Ray instance started here; 'auto', HOST:PORT or "
                     "ray://HOST:PORT, on a running cluster (pip install \"geojax[ray]\"); same results as a local run")
    swp.add_argument("--workers", type=int, help="with --ray: worker processes (default one per GPU of a GPU node "
                     "and one per CPU node, each using its share of the node's cores)")
    swp.set_defaults(func=_sweep)

    plot = command("plot", help="draw the figures of a results file (simulate, propagate, sweep, tune)")
    plot.add_argument("file", help="an HDF5 file written by geojax")
    plot.add_argument("--out", help="folder for the figures (default: next to the file)")
    plot.add_argument("--format", choices=("png", "pdf", "svg"), default="png", help="figure format (default png)")
    plot.add_argument("--dpi", type=int, default=150, help="resolution of PNG figures (default 150)")
    plot.set_defaults(func=_plot)

    xfer = command("transfer", help="GTO-GEO low-thrust transfer, gimbaled boom or quadrilateral layout (Ma & Kong 2023)")
    xfer.add_argument("scenario", help="a shipped transfer (ma2023-boom, ma2023-quadrilateral) or a .toml path")
    xfer.add_argument("--days", type=float, help="time limit in solar days (default: the scenario's); the transfer "
                      "stops earlier when it reaches GEO (not sidereal-day cycles: a transfer has no control cycle)")
    xfer.add_argument("--out", help="write /metrics and the daily /records to this HDF5 file")
    xfer.set_defaults(func=_transfer)

    scen = command("scenarios", help="list the shipped scenarios, or print one's TOML")
    scen.add_argument("--show", metavar="NAME", help="print the TOML of the shipped scenario NAME")
    scen.set_defaults(func=_scenarios)
    return parser


def _say(args):
    """``print`` unless ``-q``."""
    return (lambda *a, **k: None) if getattr(args, "quiet", False) else print


def _detail(args):
    """``print`` with ``-v`` only."""
    return print if getattr(args, "verbose", False) else (lambda *a, **k: None)


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

    from geojax.loop.setup import cycle_count

    sc = scenario.load(args.scenario, _overrides(args))
    _check_outputs(args)
    result = run.propagate_scenario(sc, progress=False if args.quiet else None)
    summary = run.drift_summary(result.cycles, sc.days)
    _print_summary(sc, result, summary, _say(args))
    _detail(args)(f"  devices {store.device_description()}; propagated {len(result.cycles.t_s)} cycles to interpolate "
                  f"the change over exactly {sc.days:g} days")
    if args.out:
        path = store.write_h5(
            args.out,
            {"cycles": run.cycles_table(result.cycles, cycle_count(sc.days))},
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
    say, detail = _say(args), _detail(args)
    say(f"{sc.name}: {sc.controller} for {flown_days(sc.days)}; compiling...", flush=True)
    from geojax.loop.setup import controller_of

    # A feedback law (no plan, no predictor reference: Katz's laws, a user's) keeps its per-step records for
    # the ground-track figures; a planner gets the reference and targets beside its cycles instead.
    feedback = controller_of([sc]).reference_cycles == 0
    result = simulate(sc, args.seed, keep_steps=feedback,
                      on_compiled=lambda s: say(f"compiled in {s:.1f} s; running...", flush=True))
    cycles = result.cycles()
    run_s = result.wall_s - result.compile_s
    say(f"{sc.name}: {sc.controller}, {len(cycles['t_s'])} cycles in {run_s:.1f} s after compilation, "
        f"status {int(result.status)} ({STATUS_MEANINGS[int(result.status)]})")
    detail(f"  devices {_devices()}; the run is one compiled call (no host callbacks in the loop), so it reports "
           f"its times instead of a progress bar")
    if sc.name.startswith("katz2025"):
        paper, source = KATZ.get(sc.config["controller"]["thrust_mode"], {}), "Katz 2025"
    else:
        paper, source = (PAPER.get(sc.controller, {}), "Li 2022") if sc.name.startswith("li2022") else ({}, "")
    metrics = {**{k: float(v) for k, v in result.metrics.items()}, "cpu_s_per_orbit": run_s / len(cycles["t_s"])}
    changed = _departures_from_paper(args, sc) if paper else []
    if changed:
        source = f"{source} (its own run)"
    say(f"  {'metric':32s} {'geojax':>12s}  {source}")
    for name, value in metrics.items():
        say(f"  {name:32s} {value:12.5g}  {paper.get(name, '')}")
    if changed:
        say(f"  note: {source.split(' (')[0]}'s numbers are for its own run; this one differs in "
            f"{', '.join(changed)}, so they are shown for orientation only")
    groups = {"metrics": {**metrics, "status": int(result.status)}, "cycles": cycles}
    steps = _steps_table(result) if feedback else None
    if steps is not None:
        groups["steps"] = steps
    else:
        groups["reference"], groups["target"] = reference_and_target(sc, len(result.records.cycles.dv_mps))
    if args.out:
        path = store.write_h5(args.out, groups, scenario.to_toml(sc.config), result.wall_s,
                              attrs={"kind": "simulate", "scenario": sc.name, "epoch_tt_s": sc.epoch_tt_s,
                                     "seed": args.seed, "compile_s": result.compile_s,
                                     "status_codes": _status_text()})
        print(f"wrote {path}")
    if args.plots:
        title = f"{sc.name}, {sc.controller}"
        box = sc.config["station"]["box_half_width_deg"]
        if steps is not None:
            figures = plots.plot_feedback(steps, box, Path(args.plots) / sc.name,
                                          title=f"{sc.name}, {sc.config['controller']['thrust_mode']} thrust")
        else:
            figures = [plots.plot_cycles(cycles, Path(args.plots) / f"{sc.name}.png", title=title),
                       plots.plot_station_keeping(cycles, groups["reference"], groups["target"],
                                                  Path(args.plots) / f"{sc.name}-station-keeping.png", title=title,
                                                  box_half_width_deg=box)]
        print("wrote " + " and ".join(map(str, figures)))
    return 0


def _departures_from_paper(args, sc) -> list[str]:
    """The settings of this run that differ from the paper's run of its scenario ("duration.days = 20")."""
    from geojax import scenario

    shipped = scenario.load(sc.name).config if sc.name in scenario.available() else None
    if shipped is None:
        return ["the scenario (a file of one's own)"]
    out = []
    for table, values in sc.config.items():
        if isinstance(values, dict):
            for key, value in values.items():
                if shipped.get(table, {}).get(key) != value:
                    out.append(f"{table}.{key} = {value}")
    if args.seed != 0:
        out.append(f"seed = {args.seed}")
    return out


def _devices() -> str:
    from geojax.store import device_description

    return device_description()


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


# Ma & Kong 2023, Sec. 4.2 and the conclusions.
MA2023 = {"thrust_efficiency": "0.95", "j1_track_max_deg": "0.017", "j2_track_max_deg": "0.006",
          "j3_track_max_deg": "0.011"}


def _bound(args) -> int:
    import numpy as np

    from geojax import scenario, store
    from geojax.bound import bound
    from geojax.loop.metrics import STATUS_MEANINGS

    sc = scenario.load(args.scenario, _overrides(args))
    _check_outputs(args)
    say = _say(args)
    say(f"{sc.name}: the least Delta-V over {sc.days:g} days within +-{sc.config['station']['box_half_width_deg']:g} deg "
        f"(slots of {args.slot_steps} steps); linearising about the uncontrolled run...", flush=True)
    r = bound(sc, slot_steps=args.slot_steps, thrusters=args.thrusters, acquisition_days=args.acquisition_days,
              free_end=args.free_end, say=say)
    gap = 100 * (r.resim["dv_per_year_mps"] - r.bound_per_year_mps) / r.bound_per_year_mps if r.lower_mps > 0 else 0.0
    say(f"{sc.name} ({r.geometry} thrusters, {r.days:.2f} days, {r.slot_s:.0f} s slots):")
    say(f"  bound                 {r.bound_per_year_mps:10.3f} m/s/yr  (lower bound over every direction the thrusters allow)")
    say(f"  optimal plan          {r.plan_per_year_mps:10.3f} m/s/yr  (the linear program's, {len(r.rounds)} linearisations)")
    say(f"  re-simulated plan     {r.resim['dv_per_year_mps']:10.3f} m/s/yr  ({gap:+.3f} % over the bound), "
        f"status {r.resim_status} ({STATUS_MEANINGS[r.resim_status]})")
    after = f"; after day {args.acquisition_days:g}: {r.max_abs_box_deg:.5f} deg" if args.acquisition_days else ""
    say(f"  box                   max |dlon| {r.resim['max_abs_dlon_deg']:.5f} deg, max |lat| "
        f"{r.resim['max_abs_dlat_deg']:.5f} deg{after}; linear model within {r.linear_error_deg:.2e} deg of the flight")
    _detail(args)(f"  devices {store.device_description()}; {r.wall_s:.1f} s in all")
    if args.out:
        metrics = {"bound_per_year_mps": r.bound_per_year_mps, "plan_per_year_mps": r.plan_per_year_mps,
                   "resim_dv_per_year_mps": r.resim["dv_per_year_mps"], "gap_percent": gap,
                   "resim_max_abs_dlon_deg": r.resim["max_abs_dlon_deg"],
                   "resim_max_abs_dlat_deg": r.resim["max_abs_dlat_deg"], "status": r.resim_status,
                   "linear_error_deg": r.linear_error_deg, "max_abs_box_after_acquisition_deg": r.max_abs_box_deg,
                   "acquisition_days": args.acquisition_days, "free_end": int(args.free_end)}
        rounds = {k: np.array([row[k] for row in r.rounds]) for k in r.rounds[0]}
        slots = {"t_s": r.t_s, "dv_r_mps": r.u_rsw_mps[:, 0], "dv_s_mps": r.u_rsw_mps[:, 1],
                 "dv_w_mps": r.u_rsw_mps[:, 2], "dv_thruster_mps": r.thruster_mps,
                 "dlon_deg": r.lon_deg, "lat_deg": r.lat_deg}
        path = store.write_h5(args.out, {"metrics": {k: np.asarray(v) for k, v in metrics.items()}, "rounds": rounds,
                                         "slots": slots}, scenario.to_toml(sc.config), r.wall_s,
                              attrs={"kind": "bound", "scenario": sc.name, "geometry": r.geometry,
                                     "epoch_tt_s": sc.epoch_tt_s, "slot_s": r.slot_s},
                              dims={"rounds": ("round",), "slots": ("slot",), "slots/dv_thruster_mps": ("slot", "thruster"),
                                    "slots/dlon_deg": ("slot", "step"), "slots/lat_deg": ("slot", "step")})
        print(f"wrote {path}")
    return 0


def _transfer(args) -> int:
    import numpy as np

    from geojax import store
    from geojax import transfer
    from geojax.scenario import to_toml

    sc = transfer.load(args.scenario)
    _check_outputs(args)
    result = transfer.run(sc, days=args.days)
    say = _say(args)
    m = result.metrics
    say(f"{sc.name}: {sc.config['description']}")
    say(f"  status {int(m['status'])}: {transfer.STATUS_MEANINGS[int(m['status'])]}")
    for name, value in m.items():
        if name != "status":
            paper = f"   (Ma 2023: {MA2023[name]})" if name in MA2023 else ""
            say(f"  {name:24s} {float(value):12.4f}{paper}")
    _detail(args)(f"  devices {store.device_description()}; {result.wall_s:.1f} s with compilation")
    if args.out:
        path = store.write_h5(args.out, {"metrics": {k: np.asarray(v) for k, v in m.items()}, "records": result.records},
                              to_toml(sc.config), result.wall_s,
                              attrs={"kind": "transfer", "scenario": sc.name, "layout": sc.layout,
                                     "epoch_tt_s": sc.epoch_tt_s, "step_s": sc.step_s})
        print(f"wrote {path}")
    return 0


def _tune(args) -> int:
    from geojax import scenario, tune

    spec = tune.load(args.file)
    _check_outputs(args)
    say = _say(args)
    result = tune.tune(spec, out=args.out, verbose=not args.quiet)
    say(f"{spec.scenario.name}: {result.message}; {result.wall_s:.1f} s wall")
    if result.best_params is None:
        say("  no feasible point: every iterate left the box with the exact law")
        print(f"wrote {args.out}")
        return 1
    fields = scenario.controller_fields(spec.scenario.config["controller"], spec.controller)
    for name, value in tune.paper_units(result.best_params, fields).items():
        say(f"  {name:24s} {value:.6g}")
    say(f"  ΔV (exact law, full horizon)  {result.best_dv_per_year_mps:.3f} m/s/yr, box kept "
        f"(constraint lon {result.best_constraint[0]:+.4f}, lat {result.best_constraint[1]:+.4f})")
    fault = tune.tuned_scenario_fault(spec, result.best_params)
    if fault is not None:  # the descent kept each key in its bounds, not the scenario's joint checks
        print(f"wrote {args.out} and {tune.tuned_scenario_path(args.out)}")
        print(f"geojax tune: the tuned scenario fails its load checks (geojax simulate refuses it): {fault}",
              file=sys.stderr)
        return 1
    print(f"wrote {args.out} and {tune.tuned_scenario_path(args.out)} (run it: geojax simulate "
          f"{tune.tuned_scenario_path(args.out)})")
    return 0


def _print_summary(sc, result, summary, say=print) -> None:
    from geojax.loop.setup import cycle_count

    say(f"{sc.name}: {sc.days:g} days, {cycle_count(sc.days)} sidereal-day cycles, step {result.step_s:.2f} s, "
        f"{sc.dynamics.upper()} RK4, {result.wall_s:.1f} s wall")
    say(f"  mean inclination       {summary.i_start_deg:.4f} deg -> {summary.i_end_deg:.4f} deg")
    say(f"  inclination-vector change  {summary.di_deg:.4f} deg towards {summary.di_direction_deg:.1f} deg "
        f"over {summary.elapsed_days:.1f} days")
    say(f"  mean longitude drift   {summary.dlon_deg:+.4f} deg")
    say(f"  largest |e - e0|       {summary.de_max:.3e}")


def _demo(args) -> int:
    from geojax import plots, scenario, store
    from geojax import uncontrolled as run

    from geojax.loop.setup import cycle_count

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {str(out)!r}: exists and is not a folder")
    say = _say(args)
    sc = scenario.load("li2022")
    say("geojax demo 1/2: one year of li2022 without station keeping (Li 2022 initial state, J2 + Sun + Moon + SRP)")
    result = run.propagate_scenario(sc, progress=False if args.quiet else None)
    summary = run.drift_summary(result.cycles, sc.days)
    _print_summary(sc, result, summary, say)
    table = run.cycles_table(result.cycles, cycle_count(sc.days))
    h5 = store.write_h5(out / "li2022-uncontrolled.h5", {"cycles": table}, scenario.to_toml(sc.config), result.wall_s,
                        attrs={"kind": "propagate", "scenario": sc.name, "epoch_tt_s": sc.epoch_tt_s, "step_s": result.step_s})
    figure = plots.plot_cycles(table, out / "li2022-uncontrolled.png", title="li2022, no control, one year")
    print(f"wrote {h5} and {figure}")
    say()
    say("geojax demo 2/2: the same year with QFFC station keeping (li2022-qffc, normal arm limits)")
    args_sim = argparse.Namespace(scenario="li2022-qffc", controller=None, horizon=None, days=None, step=None, seed=0,
                                  h_rv=None, h_att=None, out=str(out / "li2022-qffc.h5"), plots=str(out),
                                  quiet=args.quiet, verbose=args.verbose)
    return _simulate(args_sim)


def _sweep(args) -> int:
    from geojax import store, sweep

    spec = sweep.load(args.file)
    _check_outputs(args)
    say = _say(args)
    n = spec.n_points * spec.repetitions
    say(f"{spec.name}: {len(spec.controllers)} controller(s) x {spec.n_points} grid point(s) x "
        f"{spec.repetitions} repetition(s) = {len(spec.controllers) * n} samples", flush=True)
    path = sweep.run_sweep(spec, args.out, resume=args.resume, chunk=args.chunk, progress=False if args.quiet else None,
                           ray=args.ray, workers=args.workers, lanes=args.lanes)
    groups, attrs = store.read_h5(path)
    lanes = f" ({attrs['lanes_per_device']} lanes per device)" if attrs.get("lanes_per_device") else ""
    _detail(args)(f"  compiled in {float(attrs.get('compile_s', float('nan'))):.1f} s, {float(attrs['wall_s']):.1f} s "
                  f"wall in all, on {attrs['device']}{lanes}")
    for line in sweep_summary(spec, groups):
        say(line)
    print(f"wrote {path}")
    return 0


SUMMARY_ROWS = 40  # grid points listed per controller; the rest: geojax plot or geojax.open_results


def sweep_summary(spec, groups) -> list[str]:
    """One line per controller and grid point: ΔV per year (mean ± std over the repetitions), box half-ranges
    and the statuses; a warning where the repetitions of a point are identical (nothing random in them)."""
    import itertools

    import numpy as np

    from geojax.loop.metrics import STATUS_MEANINGS

    metrics, codes = groups["metrics"], groups["status"]["code"]
    keys = list(spec.grid)
    points = list(itertools.product(*spec.grid.values()))
    lines, identical = [], []
    for i, controller in enumerate(spec.controllers):
        lines.append(f"  {controller}:")
        flat = {k: np.asarray(v[i]).reshape(len(points), spec.repetitions) for k, v in metrics.items()}
        status = np.asarray(codes[i]).reshape(len(points), spec.repetitions)
        for j, point in enumerate(points[:SUMMARY_ROWS]):
            dv = flat["dv_per_year_mps"][j]
            counts = ", ".join(f"{int(np.sum(status[j] == c))} {STATUS_MEANINGS[c]}"
                               for c in range(1, len(STATUS_MEANINGS)) if np.any(status[j] == c))
            where = ", ".join(f"{k.rpartition('.')[2]} {v:g}" for k, v in zip(keys, point, strict=True))
            spread = f" ± {np.std(dv):.2f}" if spec.repetitions > 1 else ""
            lines.append(f"    {where}: ΔV {np.mean(dv):.2f}{spread} m/s/yr, max |δλ| "
                         f"{np.max(flat['max_abs_dlon_deg'][j]):.4f}°, max |δφ| {np.max(flat['max_abs_dlat_deg'][j]):.4f}°; "
                         f"{counts or 'all ok'}")
        if len(points) > SUMMARY_ROWS:
            lines.append(f"    ... {len(points) - SUMMARY_ROWS} more grid points (geojax plot, geojax.open_results)")
        if spec.repetitions > 1:
            same = all(np.array_equal(v, v[:, :1].repeat(spec.repetitions, 1), equal_nan=True) for v in flat.values())
            if same:
                identical.append(controller)
    if identical:
        lines.append(f"  warning: the {spec.repetitions} repetitions of every grid point are identical for "
                     f"{', '.join(identical)}: nothing random in them (no orbit-determination or attitude errors, no "
                     f"[dispersion], a deterministic controller); use repetitions = 1, or add errors or a dispersion")
    return lines


def _plot(args) -> int:
    from geojax import plots, store

    path = Path(args.file)
    if not path.is_file():
        raise ValueError(f"file {str(path)!r}: no such file")
    if not 10 <= args.dpi <= 2400:
        raise ValueError(f"--dpi: must be from 10 to 2400, got {args.dpi}")
    try:
        groups, attrs = store.read_h5(path)
    except OSError:
        raise ValueError(f"file {str(path)!r}: not an HDF5 file") from None
    out = Path(args.out) if args.out else path.parent
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {str(out)!r}: exists and is not a folder")
    ext, dpi = args.format, args.dpi
    title = str(attrs.get("scenario", attrs.get("name", path.stem)))
    kind = attrs.get("kind")
    if kind == "sweep":
        axes = str(attrs["grid_axes"]).split(",")
        figures = [plots.plot_sweep(groups, axes, out / f"{path.stem}.{ext}", title=sweep_title(attrs, axes), dpi=dpi)]
    elif kind == "tune":
        if "iterations" not in groups:
            raise ValueError(f"file {str(path)!r}: a tuning file without /iterations (stopped before its first)")
        figures = [plots.plot_tuning(groups, out / f"{path.stem}-convergence.{ext}",
                                     title=f"{title}: tuning {attrs.get('parameters', '')}", dpi=dpi)]
    elif "steps" in groups:  # a feedback run (Katz 2025)
        figures = plots.plot_feedback(groups["steps"], _box_half_width_deg(attrs), out / path.stem, title=title,
                                      dpi=dpi, fmt=ext)
    elif "cycles" in groups:
        figures = [plots.plot_cycles(groups["cycles"], out / f"{path.stem}.{ext}", title=title, dpi=dpi)]
        if {"reference", "target"} <= set(groups):
            figures.append(plots.plot_station_keeping(groups["cycles"], groups["reference"], groups["target"],
                                                      out / f"{path.stem}-station-keeping.{ext}", title=title,
                                                      box_half_width_deg=_box_half_width_deg(attrs), dpi=dpi))
    else:
        raise ValueError(f"file {str(path)!r}: nothing geojax can plot (no /cycles, /steps, sweep or tuning data)")
    print("wrote " + " and ".join(map(str, figures)))
    return 0


def _box_half_width_deg(attrs) -> float:
    """The box half-width (deg) of the scenario stored with a results file."""
    from geojax import scenario

    return float(scenario.from_dict(scenario.tomllib.loads(str(attrs["config_toml"]))).config["station"]["box_half_width_deg"])


def _scenarios(args) -> int:
    from geojax import scenario, transfer

    if args.show:
        if args.show in transfer.available():
            print((transfer.scenario._shipped() / f"{args.show}.toml").read_text(), end="")
        else:
            print(scenario.read_text(args.show), end="")
        return 0
    names = scenario.available()
    width = max(map(len, names))
    for name in names:
        print(f"{name:{width}s}  {scenario.load(name).config['description']}")
    print("\n`geojax scenarios --show NAME` prints a scenario's TOML (to copy and edit: "
          f"`geojax scenarios --show li2022-qffc > mine.toml`); transfers (`geojax transfer NAME`): "
          f"{', '.join(transfer.available())}.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
