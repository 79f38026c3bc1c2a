"""The benchmarks' shared harness: devices (``XLA_FLAGS``, platform, cores), timing, machine facts and the
results files.  A benchmark script keeps only what it measures and its tables.

    import harness

    def main():
        args = parser.parse_args()
        run = harness.start(harness.Devices())           # before JAX starts its backend
        ...                                              # import and measure
        _, timing = harness.measure(fn, x, repeats=3, warmup=1)
        print(harness.write(args.out / "name", run, "Title", data, body_lines))

Scripts run as ``python benchmarks/NAME.py`` find this package beside them.  Nothing here imports JAX or
geojax at import time, so a script measuring an older geojax (``core.py --baseline``) can use it too.
"""

from harness.child import run_json
from harness.devices import Devices, environment, pin, set_up, usable_cores
from harness.machine import command_line, facts, peak_memory_bytes
from harness.results import RESULTS_DIR, Run, add_arguments, ratio_table, ratios, read, save, start, table, write
from harness.timing import Call, Timing, compile_jitted, measure, timed, total

__all__ = ["Call", "Devices", "RESULTS_DIR", "Run", "Timing", "add_arguments", "command_line", "compile_jitted",
           "environment", "facts", "measure", "peak_memory_bytes", "pin", "ratio_table", "ratios", "read",
           "run_json", "save", "set_up", "start", "table", "timed", "total", "usable_cores", "write"]
