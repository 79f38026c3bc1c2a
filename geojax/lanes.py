"""How many samples one compiled call runs per device (docs/design.md, "Scale": the device decides the batch).

On a CPU, a device is about one core and the best width is the one measured
there per controller (``Controller.lanes_cpu``): wider batches gain little and
pad small sweeps.  On an accelerator, a step is a handful of kernels whose
launch cost is the same at any width, so the batch is as wide as the device's
memory allows (up to ``ACCELERATOR_MAX_LANES``, and no wider than the sweep
needs), tens of thousands of lanes.

The memory model, per lane, is stated so it can be checked (``benchmarks/accelerator.py`` prints it beside
XLA's own ``memory_analysis`` of the compiled batch, and ``tests/test_lanes.py`` checks it covers the CPU's):

    bytes per lane = MEMORY_MARGIN x (Controller.lane_bytes + n_cycles x (Controller.lane_bytes_per_cycle
                                                                          + StateModel.bytes_per_cycle
                                                                          + kept cycle records)
                                      + reference cycles x REFERENCE_BYTES_PER_CYCLE)

``lane_bytes`` is the controller's working set (the loop's state, a step's temporaries, the plan),
``lane_bytes_per_cycle`` the per-cycle records the loop stacks (``loop.simulate.CycleRecord``) and the
controller's own records, ``StateModel.bytes_per_cycle`` those of the further states the scenario carries (the
wheels', the filter's: ``geojax.states``); the kept records (a sweep with ``cycles = true``: the orbit's series
and the states' ``columns_per_cycle``) are an output on top, and a
batch whose samples differ in what the predictor's reference depends on (a sweep over the station, the
initial state or the forces) runs one uncontrolled reference per lane, whose cycle records count too.  The width
is then the largest power of two whose lanes fit ``FREE_FRACTION`` of the device's free memory.

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
REFERENCE_BYTES_PER_CYCLE = 200  # a per-lane reference run's cycle records: the QFFC's per-cycle bytes, which hold them


class LanePlan(NamedTuple):
    """The width of one compiled call and why."""

    lanes: int  # samples per device per call
    bytes_per_lane: int  # the model above, margin included
    free_bytes: int  # the device's free memory when planned
    platform: str  # "cpu", "gpu", "tpu"
    source: str  # "measured" (the CPU's per-controller width), "memory" (fits the device), "requested"

    def describe(self) -> str:
        return (f"{self.lanes} lanes per {self.platform} device ({self.source}; "
                f"{self.bytes_per_lane / 1e3:.0f} kB per lane, {_gb(self.free_bytes)} free)")


def bytes_per_lane(controller, n_cycles: int, kept_records: int = 0, reference_cycles: int = 0,
                   state_bytes_per_cycle: int = 0) -> int:
    """The model's bytes of one lane over ``n_cycles`` cycles, margin included (``kept_records``: per-cycle
    values per sample the call returns; ``reference_cycles``: cycles of a reference run per lane;
    ``state_bytes_per_cycle``: the further states' cycle records, ``StateModel.bytes_per_cycle`` summed)."""
    per_cycle = controller.lane_bytes_per_cycle + state_bytes_per_cycle + kept_records * BYTES_PER_RECORD_VALUE
    return math.ceil(MEMORY_MARGIN * (controller.lane_bytes + n_cycles * per_cycle
                                      + reference_cycles * REFERENCE_BYTES_PER_CYCLE))


def free_bytes(device=None) -> int:
    """Free memory of ``device`` (default the first local one): an accelerator's allocator limit less what it
    holds; on a CPU the host's available memory shared by its devices."""
    device = device or jax.local_devices()[0]
    stats = device.memory_stats() if device.platform != "cpu" else None
    if stats and "bytes_limit" in stats:
        return int(stats["bytes_limit"] - stats.get("bytes_in_use", 0))
    return _host_available_bytes() // max(1, jax.local_device_count())


def plan(controller, n_cycles: int, samples_per_device: int, *, kept_records: int = 0, reference_cycles: int = 0,
         requested: int | None = None, platform: str | None = None, available: int | None = None,
         state_bytes_per_cycle: int = 0) -> LanePlan:
    """The width for ``controller`` over ``n_cycles`` cycles when each device has ``samples_per_device`` to
    run; ``requested`` fixes it (``ValueError`` naming ``lanes`` if it cannot fit or is out of range).

    ``platform`` and ``available`` (free bytes) default to the first local device's.
    """
    platform = platform or jax.local_devices()[0].platform
    available = free_bytes() if available is None else available
    per_lane = bytes_per_lane(controller, n_cycles, kept_records, reference_cycles, state_bytes_per_cycle)
    fit = int(FREE_FRACTION * available) // per_lane
    if checked(requested) is not None:
        if requested > fit:
            raise ValueError(f"lanes: {requested} lanes need about {_gb(requested * per_lane)} on each {platform} "
                             f"device ({per_lane / 1e3:.0f} kB per lane over {n_cycles} cycles), which has "
                             f"{_gb(available)} free; at most {max(fit, 0)} fit")
        return LanePlan(requested, per_lane, available, platform, "requested")
    if platform == "cpu":
        return LanePlan(max(1, min(controller.lanes_cpu, fit)), per_lane, available, platform, "measured")
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
