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
parses and turns errors into exit codes; the commands' bodies (``geojax.cli_commands``) call and print.

Bad input (an unknown scenario, a field of the wrong type or out of range) prints one line naming the field (the
flag, where the library's spec key has one) and what is allowed, and exits with status 2.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from geojax.cli_args import parser as _parser
from geojax.cli_commands import COMMANDS
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


if __name__ == "__main__":
    sys.exit(main())
