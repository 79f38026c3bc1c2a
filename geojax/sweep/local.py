"""The local executor: a sweep's chunks on this process's devices, one after another.

Like ``geojax.sweep.cluster``, it receives what it runs (``make_runner(controller)``: an object with
``compile_s``, ``plan.lanes`` and ``run(first, length, on_samples)``, the sweep's ``ChunkRunner``) and imports
nothing of the sweep.
"""

from __future__ import annotations


def run_chunks(todo: list[tuple[str, int, int]], save, bar, *, make_runner) -> tuple[float, dict[str, int]]:
    """Run each (controller, first sample, length) of ``todo``, calling ``save(controller, first, values)`` as each
    chunk finishes and ``bar`` (``geojax.progress.Progress``) as samples do; ``make_runner(controller, on_phase)``
    names its phases (set-up, compiling) through ``on_phase``.  Returns (seconds compiling, lanes
    per device of each controller)."""
    compile_s, runners = 0.0, {}
    for controller, first, length in todo:
        if controller not in runners:
            bar.phase(f"{controller}: set-up")
            runners[controller] = make_runner(controller, bar.phase)
            compile_s += runners[controller].compile_s
            bar.restart(f"{controller} compiled in {runners[controller].compile_s:.1f} s "
                        f"({runners[controller].plan.lanes} lanes per device)")
        save(controller, first, runners[controller].run(first, length, bar.update))
    return compile_s, {c: r.plan.lanes for c, r in runners.items()}
