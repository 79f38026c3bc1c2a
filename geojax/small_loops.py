"""Small loops compiled whole: XLA:CPU asked to emit a while loop whose iteration touches under 256 MiB as one function.

XLA's CPU runtime runs a loop's body kernel by kernel, and the closed loop's integration step is about a hundred
small kernels, so at a CPU's widths launching them was half of every step.  XLA hoists a loop into one compiled
function when the bytes one iteration accesses are under ``xla_cpu_small_while_loop_byte_threshold`` (default
1 KiB, one of ``--xla_backend_extra_options``); geojax raises it to ``SMALL_LOOP_BYTES``, which covers the step
loops at the widths geojax compiles on a CPU (the QFFC's up to 1,024 lanes).  A loop holding a custom call (a
linear solve, a host callback, a YNNPACK dot) stays as it was.  The kernels are the same, so every number is the
same bit for bit; the speed, measured in one run, is in docs/speed.md.  A user's own threshold in ``XLA_FLAGS``
wins, and ``GEOJAX_XLA_LOOPS=1`` leaves XLA's default.  Like every XLA flag it must be set before JAX starts a
backend: ``import geojax`` does it first thing.
"""

from __future__ import annotations

import os
import sys

EXTRA_OPTIONS_FLAG = "--xla_backend_extra_options"
THRESHOLD_KEY = "xla_cpu_small_while_loop_byte_threshold"
SMALL_LOOP_BYTES = 2**28
ENV_XLA_LOOPS = "GEOJAX_XLA_LOOPS"


def with_small_loops(flags: str, threshold_bytes: int = SMALL_LOOP_BYTES) -> str:
    """``XLA_FLAGS`` text ``flags`` with the small-loop threshold among XLA's backend options (added to the
    options ``flags`` already give, comma-separated); a threshold ``flags`` already sets is kept, as is every
    other flag, in its order."""
    kept = flags.split()
    option = f"{THRESHOLD_KEY}={threshold_bytes}"
    for i, flag in enumerate(kept):
        name, _, value = flag.partition("=")
        if name == EXTRA_OPTIONS_FLAG:
            options = [o for o in value.split(",") if o]
            if any(o.partition("=")[0] == THRESHOLD_KEY for o in options):
                return " ".join(kept)
            kept[i] = f"{EXTRA_OPTIONS_FLAG}={','.join([*options, option])}"
            return " ".join(kept)
    return " ".join([*kept, f"{EXTRA_OPTIONS_FLAG}={option}"])


def use_small_loops() -> bool:
    """Set ``with_small_loops`` in ``XLA_FLAGS`` unless ``$GEOJAX_XLA_LOOPS`` is set; returns whether it is in
    effect.  Once JAX has started a backend its flags are fixed: then a warning says so."""
    if os.environ.get(ENV_XLA_LOOPS, "").strip() not in ("", "0"):
        return False
    flags = os.environ.get("XLA_FLAGS", "")
    wanted = with_small_loops(flags)
    if wanted == " ".join(flags.split()):
        return True
    from jax._src import xla_bridge

    if xla_bridge.backends_are_initialized():
        print("geojax: warning: JAX started before geojax was imported, so XLA runs small loops kernel by kernel "
              f"(slower; import geojax first, or set XLA_FLAGS={with_small_loops('')})", file=sys.stderr)
        return False
    os.environ["XLA_FLAGS"] = wanted
    return True
