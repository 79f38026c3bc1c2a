"""The ``geojax`` command line: arguments in, the library's runs called, their summaries printed and files written.

    geojax demo [--out DIR]
    geojax propagate SCENARIO [--days D] [--step S] [--set KEY=VALUE ...] [--out FILE.h5] [--plots DIR]
                     [--oem FILE [--oem-step S]] [--maneuvers FILE.opm]
    geojax simulate SCENARIO [--controller KIND] [--horizon N] [--days D] [--step S] [--seed S] [--h-rv H] [--h-att H]
                    [--set KEY=VALUE ...] [--out FILE.h5] [--plots DIR]
                    [--oem FILE [--oem-step S] [--oem-of truth|estimate]] [--maneuvers FILE.opm]
    geojax bound SCENARIO [--days D] [--step S] [--slot-steps N] [--thrusters arms|gimbal|fixed4]
                 [--acquisition-days D] [--free-end] [--set KEY=VALUE ...] [--out FILE.h5] [--plots DIR]
    geojax transfer SCENARIO [--days D] [--set KEY=VALUE ...] [--out FILE.h5] [--plots DIR]
    geojax sweep SWEEP.toml --out FILE.h5 [--resume] [--chunk N] [--lanes N] [--ray [ADDRESS]] [--workers N]
    geojax tune TUNE.toml --out FILE.h5
    geojax plot FILE.h5 [--out DIR] [--format png|pdf|svg] [--dpi N]
    geojax scenarios [--show NAME]

Every command takes -q (print only the files written) and -v (also compilation times and devices); every one that
writes files takes --force (replace them; refused by default, before anything runs).
``--days D`` means D solar days, run as round(D / sidereal day) cycles, in every station-keeping command.
What a run writes and prints is its result's (``Result.save`` / ``summary`` / ``plot`` and the like): this module
parses, calls and prints.

Bad input (an unknown scenario, a field of the wrong type or out of range) prints one line naming the field (the
flag, where the library's spec key has one) and what is allowed, and exits with status 2.
"""

from __future__ import annotations

import re
import sys
import warnings
from pathlib import Path

from geojax import cli_files
from geojax.cli_args import check_outputs as _check_outputs, overrides as _overrides, parser as _parser, set_values
from geojax.runner.report import flown_days  # noqa: F401  (printed before a run; tests read it here)
from geojax.sweep.report import summary as sweep_summary, title as sweep_title  # noqa: F401

EXIT_BAD_INPUT = 2
# The flag of each spec key a library error may name (the library speaks in spec keys, the command line in flags).
FLAGS = {"bound.slot_steps": "--slot-steps", "bound.acquisition_days": "--acquisition-days",
         "bound.thrusters": "--thrusters", "out": "--out", "oem": "--oem", "oem_step": "--oem-step",
         "oem_of": "--oem-of", "maneuvers": "--maneuvers", "resume": "--resume", "chunk": "--chunk",
         "workers": "--workers", "ray": "--ray", "force": "--force", "plots": "--plots"}


def main(argv: list[str] | None = None) -> int:
    from geojax.parallel import use_host_cores

    use_host_cores()  # batches (sweeps) are sharded over one XLA CPU device per core
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_BAD_INPUT
    user_modules_importable(args)
    if args.no_cache:
        from geojax.compilation import use_cache

        use_cache(False)
    try:
        return COMMANDS[args.command](args) or 0
    except ValueError as err:
        print(f"geojax {args.command}: error: {in_flags(str(err))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeError as err:
        from geojax.sweep.cluster import ClusterError

        if not isinstance(err, ClusterError):
            raise
        print(f"geojax {args.command}: error: {in_flags(str(err))}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return _interrupted(args)
    except BrokenPipeError:  # `geojax scenarios | head`: the reader left; say nothing more
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command ended by Ctrl-C


def _interrupted(args) -> int:
    """Ctrl-C: say what was saved and how to go on, and end with status 130.

    Where a thread of this process is still at work (a compilation: ``parallel.per_device`` compiles each
    device's program in a daemon thread, which XLA cannot stop), the process ends at once (``os._exit``) after
    flushing its output: Python's exit would tear that thread down inside XLA, which aborts ("terminate called
    after throwing an instance of '' ... FATAL: exception not rethrown").  Every file is written atomically,
    so nothing is left half written either way."""
    import os
    import threading

    saved = ""
    if args.command == "sweep":
        from geojax.sweep import saved_samples

        parts, chunks, samples = saved_samples(args.out)
        resume = f"geojax sweep {args.file} --out {args.out} --resume"
        saved = (f"; {chunks} chunk(s) of {samples} sample(s) are saved in {parts}: `{resume}` continues from them"
                 if chunks else f"; no chunk had finished, nothing is saved: `{resume}` starts it afresh")
    elif args.command == "tune" and args.out:
        from geojax import store, tune

        if Path(args.out).is_file():
            tuned = tune.tuned_scenario_path(args.out)
            saved = (f"; {args.out} holds the iterations done, status \"{store.read_attrs(args.out)['status']}\""
                     + (f", and {tuned} the best feasible point so far" if tuned.is_file() else ""))
        else:
            saved = "; no iteration had finished, nothing is saved"
        saved += f"; a tuning cannot be resumed: `geojax tune {args.file} --out {args.out}` runs it again"
    print(f"geojax {args.command}: interrupted{saved}", file=sys.stderr)
    if threading.active_count() > 1:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(EXIT_INTERRUPTED)
    return EXIT_INTERRUPTED


def user_modules_importable(args) -> None:
    """Let a controller named by import path (``"my_laws:LAW"``) come from the current folder or the folder of
    the scenario, sweep or tuning file the command reads, as ``python my_script.py`` would find it: those
    folders are added after the installed packages (so they never hide one) to ``sys.path`` and, for the
    processes a run starts (Ray's workers), to ``PYTHONPATH``."""
    import os

    folders = [Path.cwd()]
    given = getattr(args, "file", None) or getattr(args, "scenario", None)
    if given and Path(given).is_file():
        folders.append(Path(given).resolve().parent)
    added = [str(f) for f in dict.fromkeys(folders) if str(f) not in sys.path]
    sys.path.extend(added)
    if added:
        os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [os.environ.get("PYTHONPATH"), *added]))


def in_flags(message: str) -> str:
    """A library error in spec keys written in flags: the key it starts with ("bound.slot_steps: ..." ->
    "--slot-steps: ...") and every setting it names ("resume=True" -> "--resume", "chunk=3" -> "--chunk 3",
    "out='a.h5'" -> "--out 'a.h5'")."""
    key, colon, rest = message.partition(":")
    text = f"{FLAGS[key]}{colon}{rest}" if colon and key in FLAGS else message
    return re.sub(r"\b([a-z_.]+)=(\S+?)(?=[\s;,)]|:\s|$)",
                  lambda m: m[0] if m[1] not in FLAGS else FLAGS[m[1]] + ("" if m[2] == "True" else f" {m[2]}"),
                  text)


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
        f"program), compiled or loaded from the cache...", flush=True)
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

if __name__ == "__main__":
    sys.exit(main())
