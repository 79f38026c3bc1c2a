"""The facts a results file records about where and from what it was measured."""

from __future__ import annotations

import os
import platform
import shlex
import sys
from pathlib import Path


def command_line(argv: list[str] | None = None) -> str:
    """The command that runs this benchmark again, as the README writes it (``python benchmarks/x.py ...``)."""
    argv = list(sys.argv if argv is None else argv)
    script = Path(argv[0])
    if script.is_absolute() or script.exists():
        script = Path(os.path.relpath(script.resolve(), Path(__file__).resolve().parents[2]))
    return shlex.join(["python", str(script), *argv[1:]])


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what ``platform`` says."""
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def load_average() -> list[float]:
    """The 1-, 5- and 15-minute load averages (runnable processes, all cores together)."""
    return [round(x, 2) for x in os.getloadavg()]


def facts() -> dict:
    """The machine, the software and the source revision.  Imports JAX and geojax (call it after
    ``devices.set_up``): the device is what JAX found."""
    import jax
    import jaxlib
    import numpy

    import geojax
    from geojax.store import device_description, source_revision

    return {"cpu_model": cpu_model(), "cpu_count": os.cpu_count(), "os": platform.platform(),
            "python": platform.python_version(), "numpy": numpy.__version__,
            "jax": jax.__version__, "jaxlib": jaxlib.__version__, "platform": jax.devices()[0].platform,
            "device": device_description(), "geojax": geojax.__version__, "source_revision": source_revision()}


def peak_memory_bytes(device=None) -> float:
    """The peak memory of this process so far: an accelerator's allocator peak for ``device`` where it keeps
    one, else the process's peak resident set (Python, JAX, XLA, the compiled programs)."""
    import resource

    stats = device.memory_stats() if device is not None and device.platform != "cpu" else None
    if stats and "peak_bytes_in_use" in stats:
        return float(stats["peak_bytes_in_use"])
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0  # Linux: kB
