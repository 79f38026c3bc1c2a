"""Where a small batch's time goes on a CPU: the closed loop's time per integration step against its width.

    python benchmarks/dispatch.py [--scenario li2022-qffc] [--lanes 4 16 32 64 256] [--seconds 6]

The closed loop of ``simulate_batch`` (``benchmarks/compile_profile.py``'s ``loop_program``: a year, Li's nominal
errors for li2022-qffc) compiled for each width on one XLA CPU device and run on its compiled program alone (the
best of the runs in ``--seconds``).  The time per step is fitted as ``fixed_us + per_lane_us * lanes`` (least
squares over the widths): the fixed part is what a step costs whatever its width (launching its kernels, XLA's
thunk executor, its thread pool), the per-lane part its arithmetic.  Beside it, the kernels (fusions) of the loop
bodies in the optimized HLO, the largest first: the step's body runs once per step, the cycle's once per cycle.
Results: ``benchmarks/results/dispatch.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import collections
import re
import time

import harness
from compile_profile import loop_program

NAME = "dispatch"
STEPS_PER_DAY = 96  # li2022's 900 s step


def loop_kernels(hlo_text: str) -> list[int]:
    """The fusions of each ``while`` body of an optimized HLO module, the largest first."""
    bodies = set(re.findall(r"while\(.*?body=%?([\w.\-]+)", hlo_text))
    counts, current = collections.Counter(), None
    for line in hlo_text.splitlines():
        head = re.match(r"^%?([\w.\-]+) .*\{$", line)
        if head and not line.startswith(" "):
            current = head.group(1) if head.group(1) in bodies else None
        elif current and " fusion(" in line:
            counts[current] += 1
    return sorted(counts.values(), reverse=True)


def measure(scenario: str, lanes: int, seconds: float, days: float = 365.25) -> dict:
    import jax

    overrides = {"errors.h_att": 1.0} if scenario == "li2022-qffc" else {}
    jitted, args, static, _ = loop_program(scenario, overrides, lanes, days)
    begun = time.perf_counter()
    compiled = jitted.lower(*args, **static).compile()
    compile_s = time.perf_counter() - begun
    jax.block_until_ready(compiled(*args))
    best, runs, start = float("inf"), 0, time.perf_counter()
    while time.perf_counter() - start < seconds or runs < 3:
        t = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        best, runs = min(best, time.perf_counter() - t), runs + 1
    steps = round(days * STEPS_PER_DAY)
    return {"lanes": lanes, "compile_s": compile_s, "run_s": best, "runs": runs, "us_per_step": best / steps * 1e6,
            "us_per_lane_step": best / (steps * lanes) * 1e6, "loop_kernels": loop_kernels(compiled.as_text())[:3]}


def fit(rows: list[dict]) -> tuple[float, float]:
    """(fixed_us, per_lane_us): least squares of the time per step over the widths."""
    import numpy as np

    lanes = np.array([r["lanes"] for r in rows], float)
    per_step = np.array([r["us_per_step"] for r in rows])
    per_lane, fixed = np.polyfit(lanes, per_step, 1)
    return float(fixed), float(per_lane)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="li2022-qffc")
    parser.add_argument("--lanes", type=int, nargs="+", default=[4, 16, 32, 64, 256])
    parser.add_argument("--seconds", type=float, default=6.0)
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(host_device_count=1, replace_count=True, platform=args.platform))
    rows = []
    for lanes in args.lanes:
        rows.append(measure(args.scenario, lanes, args.seconds))
        print(rows[-1], flush=True)
    fixed, per_lane = fit(rows)
    body = [f"`{args.scenario}`, a year, compiled for each width on one XLA CPU device, the best of the runs in "
            f"{args.seconds:g} s on the compiled program alone.", "",
            *harness.table(["lanes", "µs per step", "µs per lane-step", "runs", "compile s", "kernels of the loops' bodies"],
                           [[r["lanes"], f"{r['us_per_step']:.1f}", f"{r['us_per_lane_step']:.3f}", r["runs"],
                             f"{r['compile_s']:.1f}", ", ".join(map(str, r["loop_kernels"]))] for r in rows],
                           align="rrrrrl"), "",
            f"Fitted: **{fixed:.1f} µs per step whatever the width, plus {per_lane:.3f} µs per lane**; at 32 lanes "
            f"the fixed part is {fixed / (fixed + 32 * per_lane):.0%} of a step."]
    print(harness.write(args.out / NAME, run, "A small batch's time per step against its width",
                        {"rows": rows, "fixed_us_per_step": fixed, "per_lane_us": per_lane}, body))


if __name__ == "__main__":
    main()
