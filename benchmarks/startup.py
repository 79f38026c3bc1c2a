"""Time to first result: every command of the README's example block, cold and warm, against an earlier revision.

    python benchmarks/startup.py [--baseline REV] [--only NAME ...]

Each command runs in a fresh process (``python benchmarks/startup.py --child ARGS``: the ``geojax`` command with
JAX's monitoring events recorded), three times: the baseline revision (a temporary ``git worktree``, default
main before this work: no cache of its own, what every run cost), then this tree with an empty cache folder
(*cold*) and again with the folder kept (*warm*, a second run of the same command), the three one after the
other for each command so that they see the same load.  Per run: the wall time and
where it went: importing geojax, tracing and lowering (Python to StableHLO), XLA compiling (or loading from the
cache), and the rest (the set-up's and the run's arithmetic, printing and writing); the programs XLA compiled
and those the cache served.  Durations are the README's where a run is short; long ones are cut (``--days``) so
the whole measurement takes about half an hour on 2 cores, and the table says so.

Then ``simulate_batch`` in one process over durations and batch sizes (10, 30 and 20 days; 1, 3 and 4 samples):
the programs compiled per call (the closed loop compiled once per slot count and lane count here; once per
call in the baseline).  Results: ``benchmarks/results/startup.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness

HERE = Path(__file__).resolve().parent
BASELINE = "66ca5fa"  # main before the time-to-first-result work

SWEEP = """name = "startup"
scenario = "li2022-qffc"
controllers = ["qffc", "fompc"]
repetitions = 1
seed = 1
[set]
"duration.days" = 10
[grid]
"thrusters.beta_max_deg" = [60.0, 70.0, 80.0, 90.0]
"""

# (name, arguments, what was cut from the README's command)
COMMANDS = [
    ("scenarios", ["scenarios"], ""),
    ("propagate", ["propagate", "li2022", "--days", "200", "--out", "drift.h5"], ""),
    ("simulate qffc 1 yr", ["simulate", "li2022-qffc", "--out", "qffc.h5"], ""),
    ("simulate qffc 1 yr, no file", ["simulate", "li2022-qffc"],
     "the issue's check: no file, so no uncontrolled run for the file's figures"),
    ("simulate qffc 30 d", ["simulate", "li2022-qffc", "--days", "30"], "not in the README: the duration check"),
    ("simulate qffc 10 d after 30 d", ["simulate", "li2022-qffc", "--days", "10"],
     "run after the 30-day run, same cache"),
    ("simulate fompc", ["simulate", "li2022-fompc", "--h-rv", "100", "--seed", "3", "--days", "30"], "30 days, not 1 yr"),
    ("simulate katz", ["simulate", "katz2025-continuous", "--days", "30"], "30 days, not 1 yr"),
    ("bound", ["bound", "li2022-qffc", "--days", "10"], "10 days, not 1 yr"),
    ("sweep qffc+fompc 4 points", ["sweep", "startup.toml", "--out", "startup.h5"],
     "2 controllers x 4 points, 10 days (the issue's check), not fig09"),
    ("transfer", ["transfer", "ma2023-boom", "--days", "5"], "5 days, not the whole transfer"),
    ("plot", ["plot", "startup-last.h5", "--out", "figs"], ""),
]
WARM_AFTER = {"simulate qffc 10 d after 30 d": "simulate qffc 30 d"}  # its cold run follows that one's


def child(argv: list[str]) -> None:
    """Run ``geojax ARGV`` in this process and print one JSON line of where its time went."""
    start = time.perf_counter()
    import jax.monitoring as monitoring

    programs, pending, hit = [], {}, [False]

    def duration(event, seconds, fun_name="", **kwargs):
        name = fun_name.removeprefix("jit(").removesuffix(")")
        if event.endswith(("jaxpr_trace_duration", "jaxpr_to_mlir_module_duration")):
            pending[name] = pending.get(name, 0.0) + seconds
        elif event.endswith("backend_compile_duration"):
            programs.append({"name": name, "trace_lower_s": pending.pop(name, 0.0), "compile_s": seconds,
                             "cached": hit[0]})
            hit[0] = False

    def event(name, **kwargs):
        if name.endswith("cache_hits"):
            hit[0] = True

    monitoring.register_event_duration_secs_listener(duration)
    monitoring.register_event_listener(event)
    from geojax.cli import main

    imported = time.perf_counter()
    code = main(argv)
    wall = time.perf_counter() - start
    fresh = [p for p in programs if not p["cached"]]
    print(json.dumps({
        "code": code, "wall_s": wall, "import_s": imported - start,
        "trace_lower_s": sum(p["trace_lower_s"] for p in programs) + sum(pending.values()),
        "compile_s": sum(p["compile_s"] for p in fresh),
        "load_s": sum(p["compile_s"] for p in programs if p["cached"]),
        "compiled": len(fresh), "loaded": len(programs) - len(fresh),
        "largest": sorted(({"name": p["name"], "s": round(p["compile_s"], 2), "cached": p["cached"]}
                           for p in programs if p["compile_s"] >= 0.5), key=lambda p: -p["s"]),
    }))


def batch_child() -> None:
    """``simulate_batch`` over durations and batch sizes in one process: per call, the programs compiled."""
    import jax.monitoring as monitoring

    compiled = []
    monitoring.register_event_duration_secs_listener(
        lambda event, s, fun_name="", **kw: compiled.append((fun_name, s)) if event.endswith(
            "backend_compile_duration") else None)
    from geojax import scenario
    from geojax.runner.rollout import simulate_batch

    rows = []
    for days, n in ((10, 1), (30, 1), (20, 1), (10, 3), (20, 4)):
        compiled.clear()
        sc = scenario.load("li2022-qffc", {"duration.days": days, "errors.h_rv": 1.0})
        begun = time.perf_counter()
        simulate_batch([sc] * n, seeds=list(range(n)))
        loops = [s for name, s in compiled if name in ("jit(_batched)", "jit(closed_loop_batch)", "jit(closed_loop)")]
        rows.append({"days": days, "samples": n, "wall_s": time.perf_counter() - begun,
                     "loop_compiles": len(loops), "loop_compile_s": sum(loops),
                     "all_compile_s": sum(s for _, s in compiled)})
    print(json.dumps(rows))


def _run(tree: Path, args: list[str], cache: Path | None, cwd: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("JAX_COMPILATION_CACHE", "GEOJAX_"))}
    env["PYTHONPATH"] = str(tree)
    if cache is None:
        env["GEOJAX_NO_CACHE"] = "1"
    else:
        env["GEOJAX_CACHE_DIR"] = str(cache)
    out = subprocess.run([sys.executable, str(HERE / "startup.py"), *args], env=env, cwd=cwd, text=True,
                         stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(trees: dict[str, Path], names: list[str], work: Path, on_command=lambda: None,
            results: dict | None = None) -> dict:
    """Every command of ``names``, the baseline's run then this tree's cold and warm ones one after the other (so
    that all three see the machine as it is then): {label: {name: {"cold": row[, "warm": row]}}}; ``on_command()``
    after each command (the results so far are in the dict returned, filled as it goes)."""
    results = {label: {} for label in trees} if results is None else results  # filled in place
    cache = work / "cache"
    for name, argv, _ in COMMANDS:
        if name not in names:
            continue
        if name not in WARM_AFTER and cache.exists():  # an empty folder: the command's first run
            subprocess.run(["rm", "-rf", str(cache)], check=True)
        for label, tree in trees.items():
            print(f"  {label}: {name}", file=sys.stderr, flush=True)
            folder = work / label.replace(" ", "-")
            if label == "baseline":
                results[label][name] = {"cold": _run(tree, ["--child", *argv], None, folder)}
            else:
                cold = _run(tree, ["--child", *argv], cache, folder)
                _remove_outputs(argv, folder)  # a sweep refuses to overwrite its file
                results[label][name] = {"cold": cold, "warm": _run(tree, ["--child", *argv], cache, folder)}
            _remove_outputs(argv, folder)
        on_command()
    return results


def _remove_outputs(argv: list[str], folder: Path) -> None:
    """The results file a command wrote (``--out``), so that its next run writes it afresh, not refuses; the
    sweep's is kept for ``plot`` after the last run."""
    if "--out" in argv and argv[0] != "plot":
        path = folder / argv[argv.index("--out") + 1]
        if path.is_file() and argv[0] != "sweep":
            path.unlink()
        elif path.is_file():
            path.rename(path.with_name("startup-last.h5"))


def markdown(base: dict, new: dict, batches: dict) -> list[str]:
    rows = []
    for name, argv, cut in COMMANDS:
        if name not in new:
            continue
        b, cold, warm = base.get(name, {}).get("cold"), new[name]["cold"], new[name]["warm"]
        ratio = (lambda row: f"{row['wall_s'] / b['wall_s']:.2f}") if b else (lambda row: "")
        split = (f"{cold['import_s']:.1f} / {cold['trace_lower_s']:.1f} / {cold['compile_s'] + cold['load_s']:.1f} / "
                 f"{cold['wall_s'] - cold['import_s'] - cold['trace_lower_s'] - cold['compile_s'] - cold['load_s']:.1f}")
        rows.append([f"`geojax {' '.join(argv)}`" + (f" ({cut})" if cut else ""),
                     f"{b['wall_s']:.1f} ({b['compiled']})" if b else "",
                     f"{cold['wall_s']:.1f} ({cold['compiled']}+{cold['loaded']})", ratio(cold),
                     f"{warm['wall_s']:.1f} ({warm['compiled']}+{warm['loaded']})", ratio(warm), split])
    lines = ["Wall seconds per command (programs XLA compiled, + those the cache served); the ratios are this tree's "
             "over the baseline's, in this run. Cold: an empty cache folder; warm: the same command again, its "
             "folder kept. The split of the cold run: import / tracing and lowering / XLA compiling (or loading) / "
             "the rest (set-up and run arithmetic, printing, writing); programs compile in threads at once (simulate's "
             "closed loop beside its set-up, a sweep's controllers and devices), so the compile seconds may exceed "
             "the wall time and the rest come out negative.", "",
             *harness.table(["command", "baseline s", "cold s", "cold / baseline", "warm s", "warm / baseline",
                             "cold: import / trace / compile / rest"], rows, "lrrrrrr"), "",
             "`simulate_batch` in one process, one call after another (the closed loop's compilations per call):", ""]
    if "this tree" not in batches:
        return lines[:-2]
    if "baseline" not in batches:
        return lines + harness.table(["days", "samples", "loop compiles", "s"],
                                     [[n["days"], n["samples"], n["loop_compiles"], f"{n['wall_s']:.1f}"]
                                      for n in batches["this tree"]], "rrrr")
    head = ["days", "samples", "baseline: loop compiles", "baseline s", "this tree: loop compiles", "this tree s"]
    lines += harness.table(head, [[n["days"], n["samples"], o["loop_compiles"], f"{o['wall_s']:.1f}",
                                   n["loop_compiles"], f"{n['wall_s']:.1f}"]
                                  for o, n in zip(batches["baseline"], batches["this tree"])], "rrrrrr")
    return lines


def main() -> None:
    if sys.argv[1:2] == ["--child"]:
        return child(sys.argv[2:])
    if sys.argv[1:2] == ["--batch-child"]:
        return batch_child()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BASELINE,
                        help=f"revision to compare with (default {BASELINE}; none: this tree alone, e.g. on a "
                             "machine without the git history)")
    parser.add_argument("--only", nargs="+", default=[name for name, _, _ in COMMANDS],
                        help="the commands to measure, by their names in the table")
    parser.add_argument("--no-batch", action="store_true", help="leave out the simulate_batch calls")
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start()
    import jax

    platform = jax.devices()[0].platform  # a GPU's results go beside the CPU's, not over them
    stem = args.out / ("startup" if platform == "cpu" else f"startup_{platform}")
    repo = HERE.parent
    data = {"baseline": args.baseline, "commands": {}, "simulate_batch": {}}

    def save() -> str:  # after every command: a run cut short keeps what it measured
        return harness.write(stem, run, "Time to first result: the README's commands, cold and warm", data,
                             markdown(data["commands"].get("baseline", {}), data["commands"]["this tree"],
                                      data["simulate_batch"]))

    with tempfile.TemporaryDirectory(prefix="geojax-startup-") as tmp:
        tmp = Path(tmp)
        old = tmp / "baseline-tree"
        trees = {"this tree": repo}
        if args.baseline != "none":
            subprocess.run(["git", "-C", str(repo), "worktree", "add", "--detach", str(old), args.baseline],
                           check=True, capture_output=True)
            trees = {"baseline": old, **trees}
        try:
            for label in trees:
                (tmp / label.replace(" ", "-")).mkdir()
                (tmp / label.replace(" ", "-") / "startup.toml").write_text(SWEEP)
            data["commands"] = {label: {} for label in trees}
            measure(trees, args.only, tmp, on_command=save, results=data["commands"])
            for label, tree in ({} if args.no_batch else trees).items():
                print(f"  {label}: simulate_batch", file=sys.stderr, flush=True)
                data["simulate_batch"][label] = _run(tree, ["--batch-child"],
                                                     None if label == "baseline" else tmp / "batch-cache",
                                                     tmp / label.replace(" ", "-"))
        finally:
            if args.baseline != "none":
                subprocess.run(["git", "-C", str(repo), "worktree", "remove", "--force", str(old)], check=False)
    print(save())


if __name__ == "__main__":
    main()
