"""Which devices a benchmark runs on: the platform, the number of XLA CPU devices and the cores.

XLA reads ``XLA_FLAGS`` (and JAX its platforms) when JAX starts its first backend, not when ``jax`` is
imported, so ``set_up`` may run after ``import jax`` but must run before the first array or
``jax.devices()``; it refuses to run later, where the flags would silently change nothing.  Nothing here
imports JAX at import time.
"""

from __future__ import annotations

import os
import sys
from typing import NamedTuple


class Devices(NamedTuple):
    """What a benchmark process runs on."""

    host_device_count: int | None = None  # XLA CPU devices; None: one per core this process may use
    replace_count: bool = False  # True: replace a device count the user's XLA_FLAGS gives (else it wins)
    platform: str | None = None  # JAX_PLATFORMS ("cpu", "cuda", ...); None: the user's or JAX's choice
    cores: tuple[int, ...] | None = None  # pin the process to these cores; None: the cores it was started on


def usable_cores() -> tuple[int, ...]:
    """The cores this process may run on (its affinity; every core where the OS does not say)."""
    try:
        return tuple(sorted(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return tuple(range(os.cpu_count() or 1))


def pin(cores: tuple[int, ...]) -> None:
    """Run this process (and the threads and children it starts later) on ``cores`` only."""
    os.sched_setaffinity(0, set(cores))


def environment(devices: Devices, base: dict[str, str] | None = None) -> dict[str, str]:
    """``base`` (default: this process's environment) with ``XLA_FLAGS`` and ``JAX_PLATFORMS`` for ``devices``:
    what ``set_up`` sets here, or what a child process is given."""
    from geojax.parallel import with_host_device_count  # the geojax command's composition (imports JAX)

    env = dict(os.environ if base is None else base)
    count = devices.host_device_count or len(devices.cores or usable_cores())
    env["XLA_FLAGS"] = with_host_device_count(env.get("XLA_FLAGS", ""), count, devices.replace_count)
    if devices.platform:
        env["JAX_PLATFORMS"] = devices.platform
    return env


def set_up(devices: Devices) -> dict:
    """Pin this process and set its ``XLA_FLAGS`` and platform for ``devices``; what was set, for the record.

    Raises RuntimeError once JAX has started a backend (the flags would no longer apply).
    """
    if _jax_started():
        raise RuntimeError("benchmark devices set up after JAX started its backend: call harness.start first")
    if devices.cores is not None:
        pin(devices.cores)
    env = environment(devices)
    os.environ["XLA_FLAGS"] = env["XLA_FLAGS"]
    if devices.platform:
        os.environ["JAX_PLATFORMS"] = devices.platform
        if "jax" in sys.modules:  # JAX read JAX_PLATFORMS at import; its config takes the choice from here
            sys.modules["jax"].config.update("jax_platforms", devices.platform)
    return {"xla_flags": env["XLA_FLAGS"], "jax_platforms": env.get("JAX_PLATFORMS"), "cores": list(usable_cores())}


def _jax_started() -> bool:
    if "jax" not in sys.modules:
        return False
    from jax._src import xla_bridge  # no public API says whether a backend exists yet

    return xla_bridge.backends_are_initialized()
