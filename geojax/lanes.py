"""How many samples one compiled call runs per device (docs/design.md, "Scale": the device decides the batch).

On a CPU, a device is about one core and the best width is the one measured
there per controller (``Sizing.lanes_cpu``): wider batches gain little and
pad small sweeps.  On an accelerator, a step is a handful of kernels whose
launch cost is the same at any width, so the batch is as wide as the device's
memory allows (up to ``ACCELERATOR_MAX_LANES``, and no wider than the sweep
needs), tens of thousands of lanes.

The memory model, per lane, is stated so it can be checked (``benchmarks/accelerator.py`` prints it beside
XLA's own ``memory_analysis`` of the compiled batch, and ``tests/test_lanes.py`` checks it covers the CPU's):

    bytes per lane = MEMORY_MARGIN x (Sizing.working_bytes + n_cycles x (record bytes per cycle
                                                                        + kept cycle records)
                                      + reference cycles x reference bytes per cycle)

``working_bytes`` is the controller's working set (the loop's state, a step's temporaries, the plan: measured with
XLA's ``memory_analysis``, stated in its module); the record bytes per cycle are what one cycle of the loop
stacks, the controller's records and every part's (``runner.rollout.record_bytes_per_cycle``: ``jax.eval_shape``
of one lane's loop, nothing counted by hand); the kept records (a sweep with ``cycles = true``: the orbit's series
and the states' ``columns_per_cycle``) are an output on top, and a batch whose samples differ in what the
predictor's reference depends on (a sweep over the station, the initial state or the forces) runs one
uncontrolled reference per lane, whose cycle records count too (``runner.setup.reference_shape``).  The width
is then the largest power of two whose lanes fit ``FREE_FRACTION`` of the device's free memory.  On a CPU the
measured width needs no memory model unless a width is requested: the record bytes are then not traced.

A sample's numbers do not depend on the width (tested at 128 and 1024 lanes on the CPU), so a platform's
width is a speed choice only; ``lanes`` (``--lanes``, a sweep file's ``lanes``) overrides it, refused in one
line if it cannot fit.
"""

from __future__ import annotations

import math
import os
from typing import NamedTuple

import jax

ACCELERATOR_MAX_LANES = 65_536  # widest batch on a GPU: 131,072 one-year QFFC samples on one H100 ran 3,724
# sample-years/s at 32,768 lanes and 4,485 at 65,536 (issue 31's measurement); wider only pads more
ACCELERATOR_MIN_LANES = 1_024  # narrowest automatic GPU batch: below it a step is all launch overhead
MEMORY_MARGIN = 2.0  # the stated per-lane bytes x this: XLA's GPU fusion can keep more temporaries than the CPU's
FREE_FRACTION = 0.8  # of the device's free memory a batch may plan to use
MAX_LANES = 1 << 22  # anything above is a typo, whatever the memory
BYTES_PER_RECORD_VALUE = 8  # a kept per-cycle record (float64) per name per cycle
# Where the CPU's measured width would fit even at this many record bytes per cycle (the shipped parts stack
# 0.45-0.6 kB), its records are not traced: the bound only decides whether to ask, never the width.
CPU_RECORD_BYTES_CEILING = 4_096


class LanePlan(NamedTuple):
    """The width of one compiled call and why."""

    lanes: int  # samples per device per call
    bytes_per_lane: int | None  # the model above, margin included (None: the CPU's measured width, not modelled)
    free_bytes: int  # the device's free memory when planned
    platform: str  # "cpu", "gpu", "tpu"
    source: str  # "measured" (the CPU's per-controller width), "memory" (fits the device), "requested"

    def describe(self) -> str:
        size = "" if self.bytes_per_lane is None else f"{self.bytes_per_lane / 1e3:.0f} kB per lane, "
        return f"{self.lanes} lanes per {self.platform} device ({self.source}; {size}{_gb(self.free_bytes)} free)"


class RecordBytes(NamedTuple):
    """What each cycle adds to a lane, bytes (``runner.rollout.record_bytes_per_cycle``, from ``jax.eval_shape``)."""

    loop: int  # the closed loop's cycle records: the orbit's, the controller's, every part's
    reference: int = 0  # a reference run's, where each lane runs its own


def bytes_per_lane(controller, n_cycles: int, records: RecordBytes, kept_records: int = 0,
                   reference_cycles: int = 0) -> int:
    """The model's bytes of one lane over ``n_cycles`` cycles, margin included (``records``: the bytes each cycle
    stacks; ``kept_records``: per-cycle values per sample the call returns; ``reference_cycles``: cycles of a
    reference run per lane)."""
    per_cycle = records.loop + kept_records * BYTES_PER_RECORD_VALUE
    return math.ceil(MEMORY_MARGIN * (controller.sizing.working_bytes + n_cycles * per_cycle
                                      + reference_cycles * records.reference))


def free_bytes(device=None) -> int:
    """Free memory of ``device`` (default the first local one): an accelerator's allocator limit less what it
    holds; on a CPU the host's available memory shared by its devices."""
    device = device or jax.local_devices()[0]
    stats = device.memory_stats() if device.platform != "cpu" else None
    if stats and "bytes_limit" in stats:
        return int(stats["bytes_limit"] - stats.get("bytes_in_use", 0))
    return _host_available_bytes() // max(1, jax.local_device_count())


def plan(controller, n_cycles: int, samples_per_device: int, records, *, kept_records: int = 0,
         reference_cycles: int = 0, requested: int | None = None, platform: str | None = None,
         available: int | None = None) -> LanePlan:
    """The width for ``controller`` over ``n_cycles`` cycles when each device has ``samples_per_device`` to
    run; ``requested`` fixes it (``ValueError`` naming ``lanes`` if it cannot fit or is out of range).

    ``records``: the ``RecordBytes`` of a cycle, or a function of no arguments that returns them (called only
    where the width depends on memory: an accelerator, or a requested width).  ``platform`` and ``available``
    (free bytes) default to the first local device's.
    """
    platform = platform or jax.local_devices()[0].platform
    available = free_bytes() if available is None else available
    lanes_cpu = controller.sizing.lanes_cpu
    if platform == "cpu" and checked(requested) is None and callable(records):
        ceiling = bytes_per_lane(controller, n_cycles, RecordBytes(CPU_RECORD_BYTES_CEILING, CPU_RECORD_BYTES_CEILING),
                                 kept_records, reference_cycles)
        if lanes_cpu * ceiling <= FREE_FRACTION * available:  # fits whatever the records: nothing to trace
            return LanePlan(lanes_cpu, None, available, platform, "measured")
    per_lane = bytes_per_lane(controller, n_cycles, records() if callable(records) else records, kept_records,
                              reference_cycles)
    fit = int(FREE_FRACTION * available) // per_lane
    if platform == "cpu" and requested is None:
        return LanePlan(max(1, min(lanes_cpu, fit)), per_lane, available, platform, "measured")
    if checked(requested) is not None:
        if requested > fit:
            raise ValueError(f"lanes: {requested} lanes need about {_gb(requested * per_lane)} on each {platform} "
                             f"device ({per_lane / 1e3:.0f} kB per lane over {n_cycles} cycles), which has "
                             f"{_gb(available)} free; at most {max(fit, 0)} fit")
        return LanePlan(requested, per_lane, available, platform, "requested")
    wanted = max(ACCELERATOR_MIN_LANES, _next_power_of_two(samples_per_device))
    lanes = min(ACCELERATOR_MAX_LANES, wanted, _power_of_two_below(fit))
    if lanes < 1:
        raise ValueError(f"lanes: not one lane fits on the {platform} device ({_gb(available)} free, "
                         f"{per_lane / 1e3:.0f} kB per lane over {n_cycles} cycles); shorten the run")
    return LanePlan(lanes, per_lane, available, platform, "memory")


def checked(requested):
    """``requested`` lanes if it is None or an integer in range, else ``ValueError`` naming ``lanes``."""
    if requested is not None and not (isinstance(requested, int) and not isinstance(requested, bool)
                                      and 1 <= requested <= MAX_LANES):
        raise ValueError(f"lanes: must be an integer from 1 to {MAX_LANES}, got {requested!r}")
    return requested


def _next_power_of_two(n: int) -> int:
    return 1 << max(0, int(n) - 1).bit_length()


def _power_of_two_below(n: int) -> int:
    return 0 if n < 1 else 1 << (int(n).bit_length() - 1)


def _host_available_bytes() -> int:
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB" if n >= 1e8 else f"{n / 1e6:.3g} MB"
