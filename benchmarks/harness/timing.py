"""Timing a call: warm-up, repeats, the fastest and the median, compilation apart, and what else the
machine did meanwhile.

A call is timed until its result is ready (``jax.block_until_ready``, which passes over what is not a JAX
array).  Besides the wall time, each call records this process's CPU time, the whole machine's busy time and
the time the hypervisor took from this virtual machine ("steal", both from ``/proc/stat``): a call during
which other processes and steal used more than ``DISTURBED_CORES`` is disturbed, and ``measure`` calls again
(up to ``EXTRA_CALLS`` more, one for calls over ``LONG_CALL_S``) while every call so far was.  The fastest
undisturbed call is the measurement, else the fastest.
"""

from __future__ import annotations

import math
import os
import statistics
import sys
import time
from typing import Callable, NamedTuple

DISTURBED_CORES = 0.2  # other processes' load + hypervisor steal above which a timing is repeated
EXTRA_CALLS = 2  # at most this many calls more while every call was disturbed
LONG_CALL_S = 60.0  # calls longer than this get at most one extra call


class Call(NamedTuple):
    """One timed call."""

    wall_s: float
    cpu_s: float  # this process, all threads
    machine_busy_s: float  # every process on the machine, hypervisor steal excluded (NaN if unknown)
    steal_s: float  # CPU time the hypervisor took from this virtual machine (NaN if unknown)

    @property
    def cores_busy(self) -> float:
        """This process's CPU time over the wall time, in cores."""
        return self.cpu_s / self.wall_s

    @property
    def other_load_cores(self) -> float:
        """CPU used by other processes meanwhile, in cores."""
        return max(0.0, (self.machine_busy_s - self.cpu_s) / self.wall_s)

    @property
    def steal_cores(self) -> float:
        return self.steal_s / self.wall_s

    @property
    def disturbed(self) -> bool:
        return self.other_load_cores + self.steal_cores > DISTURBED_CORES


class Timing(NamedTuple):
    """The timed calls of one measurement (warm-up calls excluded) and its compilation apart."""

    calls: tuple[Call, ...]
    compile_s: float = 0.0

    @property
    def best(self) -> Call:
        """The fastest undisturbed call, else the fastest."""
        return min([c for c in self.calls if not c.disturbed] or self.calls, key=lambda c: c.wall_s)

    @property
    def best_s(self) -> float:
        return self.best.wall_s

    @property
    def median_s(self) -> float:
        return statistics.median(c.wall_s for c in self.calls)

    @property
    def attempts(self) -> int:
        return len(self.calls)

    def row(self) -> dict:
        """The columns every results table shows for a timing."""
        best = self.best
        return {"compile_s": self.compile_s, "run_s": best.wall_s, "median_s": self.median_s,
                "cores_busy": best.cores_busy, "other_load_cores": best.other_load_cores,
                "steal_cores": best.steal_cores, "attempts": self.attempts}


def timed(fn: Callable, *args, **kwargs) -> tuple[object, Call]:
    """(result, Call) of one call of ``fn``, timed until its result is ready."""
    wall, cpu, (busy, steal) = time.perf_counter(), time.process_time(), _machine_counters()
    result = _ready(fn(*args, **kwargs))
    busy_end, steal_end = _machine_counters()
    return result, Call(time.perf_counter() - wall, time.process_time() - cpu, busy_end - busy, steal_end - steal)


def measure(fn: Callable, *args, repeats: int = 1, warmup: int = 0, compile_s: float = 0.0,
            **kwargs) -> tuple[object, Timing]:
    """(result of the best call, Timing) of ``repeats`` calls of ``fn(*args, **kwargs)`` after ``warmup``
    untimed ones, called again while every call so far was disturbed (see the module's docstring);
    ``compile_s`` (measured apart, ``compile_jitted``) is kept with the timing."""
    for _ in range(warmup):
        _ready(fn(*args, **kwargs))
    runs = [timed(fn, *args, **kwargs)]
    most = repeats + (1 if runs[0][1].wall_s > LONG_CALL_S else EXTRA_CALLS)
    while len(runs) < repeats or (len(runs) < most and all(call.disturbed for _, call in runs)):
        runs.append(timed(fn, *args, **kwargs))
    timing = Timing(tuple(call for _, call in runs), compile_s)
    return next(result for result, call in runs if call is timing.best), timing


def compile_jitted(jitted, *args, **static):
    """(compiled executable, seconds to lower and compile it) of a ``jax.jit`` function for ``args``."""
    start = time.perf_counter()
    compiled = jitted.lower(*args, **static).compile()
    return compiled, time.perf_counter() - start


def total(calls) -> Call:
    """One Call for calls made one after the other (a serial loop timed piece by piece)."""
    return Call(*(math.fsum(values) for values in zip(*calls)))


def _ready(result):
    jax = sys.modules.get("jax")  # a result holds JAX arrays only where JAX was imported
    return jax.block_until_ready(result) if jax is not None else result


def _machine_counters() -> tuple[float, float]:
    """(busy, steal) CPU seconds of the machine since boot, from /proc/stat (NaN where unavailable).

    busy = user + nice + system + irq + softirq; steal is counted apart.
    """
    try:
        with open("/proc/stat") as f:
            fields = [int(x) for x in f.readline().split()[1:]]
        busy, steal = fields[0] + fields[1] + fields[2] + fields[5] + fields[6], fields[7]
    except (OSError, ValueError, IndexError):
        return float("nan"), float("nan")
    ticks = os.sysconf("SC_CLK_TCK")
    return busy / ticks, steal / ticks
