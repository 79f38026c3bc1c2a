"""The bodies of the ``geojax`` commands (``COMMANDS``): each loads its input, checks its output paths, calls the
library's run and prints its summary and the files it wrote; ``geojax.cli`` parses the arguments and maps errors
to exit codes."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from geojax import cli_files
from geojax.cli_args import check_outputs as _check_outputs, overrides as _overrides, set_values
from geojax.runner.report import flown_days
from geojax.sweep.report import summary as sweep_summary


def _say(args):
    """``print`` unless ``-q``."""
    return (lambda *a, **k: None) if getattr(args, "quiet", False) else print


def _detail(args):
    """``print`` with ``-v`` only."""
    return print if getattr(args, "verbose", False) else (lambda *a, **k: None)


def _propagate(args) -> int:
    from geojax import scenario, uncontrolled

    sc = scenario.load(args.scenario, _overrides(args))
    _check_outputs(args)
    if sc.satellites:
        return _run_cluster(sc, 0, args, uncontrolled=True)
    cli_files.check(args, sc)
    drift = uncontrolled.without_control(sc) if args.oem or args.maneuvers else None  # refused before the run
    result = uncontrolled.propagate_scenario(sc, progress=False if args.quiet else None)
    code = _finish(args, result, f"propagated {len(result.cycles.t_s)} cycles to interpolate the change over "
                                 f"exactly {sc.days:g} days", args.out, args.plots)
    if args.oem or args.maneuvers:
        cli_files.write(args, uncontrolled.free_drift(drift))
    return code


def _simulate(args) -> int:
    from geojax import scenario

    if args.seed < 0:
        raise ValueError(f"--seed: must be an integer >= 0, got {args.seed}")
    sc = scenario.load(args.scenario, _overrides(args))
    _check_outputs(args)
    if sc.satellites:
        return _run_cluster(sc, args.seed, args)
    cli_files.check(args, sc)
    return _run_simulation(sc, args.seed, args.out, args.plots, args)


def _run_simulation(sc, seed: int, out, plots, args) -> int:
    from geojax.runner import rollout

    from geojax.compilation import Compilations, waiting_note
    from geojax.control.base import keeps_steps
    from geojax.runner import report
    from geojax.runner.setup import controller_of, cycle_count, cycle_slots

    say = _say(args)
    say(f"{sc.name}: {sc.controller} for {flown_days(sc.days)}; the environment, the reference run and the closed "
        f"loop for {cycle_slots(cycle_count(sc.days))} cycles (every duration up to that many cycles runs the same "
        f"program, or a longer one's compiled already), compiled or loaded from the cache...", flush=True)
    _detail(args)(f"  {waiting_note()}", flush=True)
    figures = {}

    def meanwhile():  # the file's and figures' uncontrolled run (a planner's), on the core the loop leaves idle
        if (out or plots) and not keeps_steps(controller_of([sc])):
            figures["reference"] = report.reference_and_target(sc, cycle_count(sc.days))

    with Compilations() as log:
        result = rollout.simulate(sc, seed, on_compiled=lambda s: say(f"closed loop ready in {s:.1f} s "
                                                                      f"({log.made()}); running...", flush=True),
                                  meanwhile=meanwhile, ephemeris=cli_files.needs_ephemeris(args, sc))
    say(f"  {log.summary()}")
    code = _finish(args, result, "the run is one compiled call (no host callbacks in the loop), so it reports its "
                                 "times instead of a progress bar", out, plots, figures.get("reference"))
    cli_files.write(args, result)
    return code


def _run_cluster(sc, seed: int, args, uncontrolled: bool = False) -> int:
    """A cluster's run (``[[satellites]]``): its summary, its file (``--out``) and figures (``--plots``)."""
    from geojax.collocation import run

    cli_files.check(args, sc.satellites[0])
    _say(args)(f"{sc.name}: {len(sc.satellites)} satellites in one compiled loop, "
               f"{'free drift' if uncontrolled else sc.controller + ' each'} for {flown_days(sc.days)}; compiling "
               f"and running...", flush=True)
    result = run.simulate_cluster(sc, seed, uncontrolled=uncontrolled,
                                  ephemeris=cli_files.needs_ephemeris(args, sc.satellites[0]))
    for line in result.summary():
        _say(args)(line)
    if args.out:
        print(f"wrote {result.save(args.out)}")
    if args.plots:
        print("wrote " + " and ".join(map(str, run.plot(result, args.plots))))
    cli_files.write(args, result)  # one OEM (and burns) per satellite, STEM-NAME beside the path given
    return 0


def _finish(args, result, detail: str, out, plots, reference=None) -> int:
    """Print the run's summary (and with ``-v`` the devices and ``detail``), then write its file (``--out``) and
    figures (``--plots``), each named as it is written (``reference``: a closed loop's uncontrolled run, if computed
    already, ``runner.report.groups``)."""
    from geojax import store

    for line in result.summary():
        _say(args)(line)
    _detail(args)(f"  devices {store.device_description()}; {detail}")
    figure_reference = {} if reference is None else {"reference": reference}
    if out:
        print(f"wrote {result.save(out, **figure_reference)}")
    if plots:
        print("wrote " + " and ".join(map(str, result.plot(plots, **figure_reference))))
    return 0


def _bound(args) -> int:
    from geojax import scenario
    from geojax.bound import bound

    sc = scenario.load(args.scenario, _overrides(args))
    _check_outputs(args)
    say = _say(args)
    say(f"{sc.name}: the least Delta-V over {sc.days:g} days within +-{sc.config['station']['box_half_width_deg']:g} deg "
        f"(slots of {args.slot_steps} steps); linearising about the uncontrolled run...", flush=True)
    result = bound(sc, slot_steps=args.slot_steps, thrusters=args.thrusters, acquisition_days=args.acquisition_days,
                   free_end=args.free_end, say=say)
    return _finish(args, result, f"{result.wall_s:.1f} s in all", args.out, args.plots)


def _transfer(args) -> int:
    from geojax import transfer

    sc = transfer.load(args.scenario, set_values(args.set))  # its --days is the run's limit, not a scenario key
    _check_outputs(args)
    result = transfer.run(sc, days=args.days, progress=False if args.quiet else None)
    return _finish(args, result, f"{result.wall_s:.1f} s with compilation", args.out, args.plots)


def _tune(args) -> int:
    from geojax import tune

    spec = tune.load(args.file)
    _check_outputs(args, tune.tuned_scenario_path(args.out))
    say = _say(args)
    with warnings.catch_warnings():  # a short horizon is said at once, on one line, whatever --quiet says
        warnings.simplefilter("always", tune.ShortHorizonWarning)
        warnings.showwarning = lambda message, *rest: print(f"geojax tune: warning: {message}", file=sys.stderr)
        result = tune.tune(spec, out=args.out, verbose=not args.quiet)
    for line in result.summary():
        say(line)
    if result.best_params is None:
        print(f"wrote {args.out}")
        return 1
    fault = tune.tuned_scenario_fault(spec, result.best_params)
    if fault is not None:  # the descent kept each key in its bounds, not the scenario's joint checks
        print(f"wrote {args.out} and {tune.tuned_scenario_path(args.out)}")
        print(f"geojax tune: the tuned scenario fails its load checks (geojax simulate refuses it): {fault}",
              file=sys.stderr)
        return 1
    print(f"wrote {args.out} and {tune.tuned_scenario_path(args.out)} (run it: geojax simulate "
          f"{tune.tuned_scenario_path(args.out)})")
    return 0


def _demo(args) -> int:
    from geojax import scenario, uncontrolled

    from geojax.store import check_output_file, check_output_folder

    out = check_output_folder(args.out, "out")
    for name in ("li2022-uncontrolled.h5", "li2022-qffc.h5"):
        check_output_file(out / name, "out", args.force)
    say = _say(args)
    sc = scenario.load("li2022")
    say("geojax demo 1/2: one year of li2022 without station keeping (Li 2022 initial state, J2 + Sun + Moon + SRP)")
    result = uncontrolled.propagate_scenario(sc, progress=False if args.quiet else None)
    for line in result.summary():
        say(line)
    h5 = result.save(out / "li2022-uncontrolled.h5")
    print(f"wrote {h5} and {result.plot(out, title='li2022, no control, one year')[0]}")
    say()
    say("geojax demo 2/2: the same year with QFFC station keeping (li2022-qffc, normal arm limits)")
    return _run_simulation(scenario.load("li2022-qffc"), 0, out / "li2022-qffc.h5", out, args)


def _sweep(args) -> int:
    from geojax import store, sweep

    spec = sweep.load(args.file)
    _check_outputs(args)
    say = _say(args)
    n = spec.n_points * spec.repetitions
    say(f"{spec.name}: {len(spec.controllers)} controller(s) x {spec.n_points} grid point(s) x "
        f"{spec.repetitions} repetition(s) = {len(spec.controllers) * n} samples", flush=True)
    path = sweep.run_sweep(spec, args.out, resume=args.resume, chunk=args.chunk, progress=False if args.quiet else None,
                           ray=args.ray, workers=args.workers, lanes=args.lanes, force=args.force)
    groups, attrs = store.read_h5(path)
    lanes = f" ({attrs['lanes_per_device']} lanes per device)" if attrs.get("lanes_per_device") else ""
    _detail(args)(f"  compiled in {float(attrs.get('compile_s', float('nan'))):.1f} s, {float(attrs['wall_s']):.1f} s "
                  f"wall in all, on {attrs['device']}{lanes}")
    for line in sweep_summary(spec, groups):
        say(line)
    print(f"wrote {path}")
    return 0


def _plot(args) -> int:
    from geojax.figures import plot_file

    if not 10 <= args.dpi <= 2400:
        raise ValueError(f"--dpi: must be from 10 to 2400, got {args.dpi}")
    if args.out and Path(args.out).exists() and not Path(args.out).is_dir():
        raise ValueError(f"--out {args.out!r}: exists and is not a folder")
    print("wrote " + " and ".join(map(str, plot_file(args.file, args.out, args.format, args.dpi))))
    return 0


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


COMMANDS = {"demo": _demo, "propagate": _propagate, "simulate": _simulate, "bound": _bound, "transfer": _transfer,
            "sweep": _sweep, "tune": _tune, "plot": _plot, "scenarios": _scenarios}
