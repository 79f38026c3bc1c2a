"""Where a closed loop's XLA compilation goes: per program, the phases of XLA's CPU compiler and the code that
makes its kernels.

    python benchmarks/compile_profile.py [--cases qffc fompc mpc field20 qffc-one] [--lanes 128] [--days 20] [--flags]

For each case (li2022-qffc, -fompc, -mpc, the QFFC with the EGM2008 20x20 field, and the QFFC for one sample as
``simulate`` compiles it), the closed loop of ``simulate_batch`` for ``--lanes`` samples (one for ``qffc-one``) is
traced and lowered (timed), then compiled once under JAX's
profiler (``jax.profiler.trace``, its Perfetto trace read back): the compilation's wall time split into XLA's
HLO passes (before and after layout assignment), emitting the kernels (``ThunkEmitter``, with each fusion's
MLIR-to-LLVM compilation, ``FusionCompiler::Compile``, counted) and LLVM's code generation (``Codegen``); the
kernels compiled; the StableHLO's size; and the optimized HLO's fusions grouped by the JAX source path that
produced them (``op_name`` metadata), so that the code that makes the most kernels is named.  Then the
compiled program's run time (best of 3).

``--flags``: the QFFC case again in a child process per XLA flag set (``XLA_FLAGS``), its compile and run times
and whether its numbers are bit for bit the default's.  With the compilation cache off throughout.  Results:
``benchmarks/results/compile_profile.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import collections
import glob
import gzip
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness

CASES = {"qffc": ("li2022-qffc", {}), "fompc": ("li2022-fompc", {}), "mpc": ("li2022-mpc", {}),
         "field20": ("li2022-qffc", {"forces.gravity_degree": 20}), "qffc-one": ("li2022-qffc", {})}
ONE_SAMPLE = {"qffc-one"}  # compiled for one sample, as ``simulate`` compiles its closed loop (``--lanes`` aside)
FLAG_SETS = ["", "--xla_backend_optimization_level=1", "--xla_backend_optimization_level=0",
             "--xla_cpu_use_fusion_emitters=false", "--xla_cpu_parallel_codegen_split_count=1"]
PHASES = {"HLO passes before layout": "HLO passes through layout assignment",
          "HLO passes after layout": "HLO passes after layout assignment",
          "emitting kernels": "ThunkEmitter::EmitEntryComputation", "LLVM codegen": "Codegen"}


def loop_program(name: str, changes: dict, lanes: int, days: float):
    """(jitted closed loop, its arguments, its static arguments, XLA's options) as ``simulate_batch`` compiles it
    (one lane: for start-up, ``rollout.compiler_options``)."""
    import jax

    from geojax import scenario
    from geojax.runner import rollout

    sc = scenario.load(name, {"duration.days": days, "errors.h_rv": 1.0, **changes})
    batch = rollout.prepare([sc])
    params = rollout.prepare_params(sc, lanes)
    keys = jax.random.split(jax.random.key(0), lanes)
    dynamics = rollout.for_one_sample(batch.dynamics) if lanes == 1 else rollout.for_lanes(batch.dynamics, lanes)
    static = dict(controller=batch.controller, step_s=batch.step_s, dynamics=dynamics, keep_steps=False,
                  states=batch.states)
    return (rollout.closed_loop_batch, (params, keys, batch.shared, rollout._reference_env(batch)), static,
            rollout.compiler_options(lanes, batch.controller))


def profile(case: str, lanes: int, days: float) -> dict:
    import jax

    jitted, args, static, options = loop_program(*CASES[case], 1 if case in ONE_SAMPLE else lanes, days)
    begun = time.perf_counter()
    lowered = jitted.lower(*args, **static)
    lower_s = time.perf_counter() - begun
    with tempfile.TemporaryDirectory() as folder:
        with jax.profiler.trace(folder, create_perfetto_trace=True):
            begun = time.perf_counter()
            compiled = lowered.compile(options)
            compile_s = time.perf_counter() - begun
        (trace,) = glob.glob(f"{folder}/**/perfetto_trace.json.gz", recursive=True)
        events = [e for e in json.load(gzip.open(trace))["traceEvents"] if e.get("ph") == "X"]
    seconds = collections.Counter()
    for e in events:
        seconds[e["name"]] += e["dur"] / 1e6
    kernels = [e for e in events if e["name"] == "FusionCompiler::Compile"]
    text = compiled.as_text()
    groups = fusion_groups(text)
    best = float("inf")
    jax.block_until_ready(compiled(*args))
    for _ in range(3):
        begun = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        best = min(best, time.perf_counter() - begun)
    row = {"lower_s": lower_s, "compile_s": compile_s,
           "phases_s": {label: sum(v for k, v in seconds.items() if k.startswith(name))
                        for label, name in PHASES.items()},
           "kernels": len(kernels), "kernel_compile_s": sum(e["dur"] for e in kernels) / 1e6,
           "stablehlo_lines": lowered.as_text().count("\n"), "fusions": sum(groups.values()),
           "fusion_groups": dict(groups.most_common(8)), "run_s": best}
    print(f"{case}: lowered in {lower_s:.1f} s, compiled in {compile_s:.1f} s ({len(kernels)} kernels), "
          f"runs in {best:.3f} s", flush=True)
    return row


def fusion_groups(hlo_text: str) -> collections.Counter:
    """The optimized HLO's fusion instructions, counted by the JAX source path (``op_name``) that made them,
    cut after the step scan or the cycle scan and at the first primitive."""
    groups = collections.Counter()
    for line in hlo_text.splitlines():
        if not re.search(r"= \S+ fusion\(", line) or "kind=" not in line:
            continue
        found = re.search(r'op_name="([^"]+)"', line)
        path = found.group(1) if found else "(no source)"
        path = path.replace("jit(closed_loop_batch)/vmap()/", "").replace("jit(closed_loop_batch)/", "")
        path = path.replace("closed_call/", "")
        parts = [p for p in path.split("/") if p not in ("checkpoint", "body")]
        groups["/".join(parts[:4])] += 1
    return groups


def flag_child(flags: str, reference: str) -> dict:
    """The QFFC case compiled and run in a child process under ``XLA_FLAGS=flags``; its numbers against those
    saved in ``reference`` (the first child's)."""
    env = {**os.environ, "XLA_FLAGS": " ".join(filter(None, [os.environ.get("XLA_FLAGS", ""), flags])),
           "GEOJAX_NO_CACHE": "1"}
    out = subprocess.run([sys.executable, __file__, "--flag-child", reference], env=env, text=True,
                         stdout=subprocess.PIPE, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def flag_child_main(reference: str) -> None:
    import jax
    import numpy as np

    harness.set_up(harness.Devices(host_device_count=1, replace_count=True))
    jitted, args, static, _ = loop_program(*CASES["qffc"], 128, 20.0)
    begun = time.perf_counter()
    compiled = jitted.lower(*args, **static).compile()
    compile_s = time.perf_counter() - begun
    out = jax.block_until_ready(compiled(*args))
    best = float("inf")
    for _ in range(3):
        begun = time.perf_counter()
        out = jax.block_until_ready(compiled(*args))
        best = min(best, time.perf_counter() - begun)
    leaves = [np.asarray(x) for x in jax.tree_util.tree_leaves(out)]
    if not Path(reference).exists():
        np.savez(reference, *leaves)
        same = True
    else:
        saved = np.load(reference)
        same = all(np.array_equal(saved[f"arr_{i}"], x, equal_nan=True) for i, x in enumerate(leaves))
    print(json.dumps({"compile_s": compile_s, "run_s": best, "bit_for_bit": bool(same)}))


def markdown(rows: dict, flags: dict, lanes: int, days: float) -> list[str]:
    lines = [f"The closed loop of `simulate_batch` for {lanes} samples and {days:g} days (one CPU device), compiled "
             "once under JAX's profiler; phases from XLA's own trace events (the kernels' compilation runs on XLA's "
             "threads inside *emitting kernels*).  `qffc-one`: the QFFC's for one sample, as `simulate` compiles it "
             "(no lane axis, the RK4 stages in a loop, XLA's classic CPU emitters and LLVM unoptimized: "
             "`geojax.compilation.ONE_SAMPLE_OPTIONS`).", "",
             *harness.table(["case", "trace + lower s", "compile s", "HLO passes before / after layout s",
                             "emitting kernels s", "LLVM codegen s", "kernels", "StableHLO lines", "run s"],
                            [[case, f"{r['lower_s']:.1f}", f"{r['compile_s']:.1f}",
                              f"{r['phases_s']['HLO passes before layout']:.1f} / "
                              f"{r['phases_s']['HLO passes after layout']:.1f}",
                              f"{r['phases_s']['emitting kernels']:.1f}", f"{r['phases_s']['LLVM codegen']:.1f}",
                              r["kernels"], r["stablehlo_lines"], f"{r['run_s']:.3f}"] for case, r in rows.items()],
                            "lrrrrrrrr"), "",
             "The code that makes the most fusions (optimized HLO, by JAX source path):", ""]
    for case, r in rows.items():
        lines.append(f"- {case} ({r['fusions']} fusions): " + "; ".join(f"`{k}` {v}"
                                                                       for k, v in r["fusion_groups"].items()))
    if flags:
        lines += ["", "XLA flags, the QFFC case in a child process each (same lanes and days):", "",
                  *harness.table(["XLA_FLAGS", "compile s", "run s", "bit for bit"],
                                 [[f"`{f}`" if f else "(default)", f"{r['compile_s']:.1f}", f"{r['run_s']:.3f}",
                                   "yes" if r["bit_for_bit"] else "no"] for f, r in flags.items()], "lrrl")]
    return lines


def main() -> None:
    if sys.argv[1:2] == ["--flag-child"]:
        return flag_child_main(sys.argv[2])
    os.environ["GEOJAX_NO_CACHE"] = "1"  # every program compiled, none loaded
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--lanes", type=int, default=128)
    parser.add_argument("--days", type=float, default=20.0)
    parser.add_argument("--flags", action="store_true", help="the QFFC case under each of FLAG_SETS")
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(host_device_count=1, replace_count=True, platform=args.platform))
    rows = {case: profile(case, args.lanes, args.days) for case in args.cases}
    flags = {}
    if args.flags:
        with tempfile.TemporaryDirectory() as folder:
            reference = str(Path(folder) / "reference.npz")
            for flag_set in FLAG_SETS:
                flags[flag_set] = flag_child(flag_set, reference)
                print(f"XLA_FLAGS={flag_set!r}: {flags[flag_set]}", flush=True)
    data = {"lanes": args.lanes, "days": args.days, "cases": rows, "flags": flags}
    print(harness.write(args.out / "compile_profile", run, "Where the closed loop's compilation goes", data,
                        markdown(rows, flags, args.lanes, args.days)))


if __name__ == "__main__":
    main()
