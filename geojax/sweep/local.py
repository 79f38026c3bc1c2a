"""The local executor: a sweep's chunks on this process's devices (its controllers compiled at once).

Like ``geojax.sweep.cluster``, it receives what it runs (``make_runner(controller)``: an object with
``compile_s``, ``plan.lanes`` and ``run(first, length, on_samples)``, the sweep's ``ChunkRunner``) and imports
nothing of the sweep.
"""

from __future__ import annotations

import functools
import time

from geojax.compilation import Compilations
from geojax.parallel import Background


def run_chunks(todo: list[tuple[str, int, int]], save, bar, *, make_runner) -> tuple[float, dict[str, int]]:
    """Run each (controller, first sample, length) of ``todo``, calling ``save(controller, first, values)`` as each
    chunk finishes and ``bar`` (``geojax.progress.Progress``) as samples do.  Returns (seconds of set-up and
    compilation, lanes per device of each controller).

    Every controller's runner (``make_runner(controller, on_phase)``: its set-up and compilation) starts at once,
    each in a thread of its own: XLA compiles a program on one core, so a 2-controller sweep on 2 cores waits
    for the longer of their compilations rather than their sum, and the first controller's chunks run while the
    next compiles.  The seconds returned are those spent waiting for runners, counted once where they overlap."""
    controllers = list(dict.fromkeys(controller for controller, _, _ in todo))
    if controllers:  # and setting up: the environment, the reference
        bar.phase(f"{', '.join(controllers)}: compiling or loading from the cache")
    with Compilations() as log:  # what the cache served, said as each controller's chunks start
        pending = {c: Background(functools.partial(make_runner, c, lambda name: None)) for c in controllers}
        waited_s, runners = 0.0, {}
        for controller, first, length in todo:
            if controller not in runners:
                begun = time.perf_counter()
                runners[controller] = pending[controller].result()
                waited_s += time.perf_counter() - begun
                bar.restart(f"{controller} {log.made()} in {runners[controller].compile_s:.1f} s "
                            f"({runners[controller].plan.lanes} lanes per device)")
            save(controller, first, runners[controller].run(first, length, bar.update))
    return waited_s, {c: r.plan.lanes for c, r in runners.items()}
