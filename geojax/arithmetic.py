"""One rounding for every width: XLA:CPU kept from contracting ``a*b + c`` into fused multiply-adds.

On an x86-64 CPU with FMA instructions, XLA's CPU backend lets LLVM fuse a multiply and an add into one FMA (one
rounding instead of two). Whether a given product is fused depends on how XLA fused the program around it, and that
changes with the batch's width: ``physics.propagate.for_lanes`` materializes the RK4 stages at widths of 8 and 64
lanes, and one sample compiles its stages inside the loop. Measured with XLA's default: one RK4 step of 64 states
differed in 122-273 of them between the width tiers and between one sample and a batch, and a 4-day QFFC batch at 2
and 12 lanes in the predicted mean e vector from the second cycle. Neither value is the more accurate one (both are
correctly rounded arithmetic of different expressions), but docs/design.md promises that no number depends on the
width, so geojax asks XLA for AVX code, which has no FMA: every product rounded, at every width.

XLA reads its flags when JAX starts its first backend, so this must run before any JAX computation; ``import
geojax`` calls ``use_separate_roundings()`` first thing. A user's own ``--xla_cpu_max_isa`` in ``XLA_FLAGS`` wins,
and ``GEOJAX_FMA=1`` leaves XLA's default (fused, width-dependent in the last bit). Only x86-64 has the flag.
Measured with it (4 days, 2 against 12 and 70 lanes): the QFFC and the navigation filter bit for bit.  The rounding
is not the only width dependence: XLA's float64 ``tan`` and ``atan`` differ between a vector loop and its remainder
(``physics.trig`` has its own), and a long reduction's partial sums and a small batched dot's loop order follow the
batch's shape (``reductions.sum_pairwise``, ``per_lane.lane_by_lane``); with those the MPC and the momentum MPC are
bit for bit at 2, 12 and 70 lanes too. On an aarch64 CPU (where FMA is part of the
base instruction set) and on a GPU the numbers may still move in the last bit with the width. The cost, this tree
against the one before it with XLA's defaults in one run: ``benchmarks/results/arithmetic_{1,16,128}.md``.
"""

from __future__ import annotations

import os
import platform
import sys

ISA_FLAG = "--xla_cpu_max_isa"
SEPARATE_ROUNDINGS = f"{ISA_FLAG}=AVX"  # AVX: 256-bit vectors, no FMA (AVX2 and later fuse)
ENV_FMA = "GEOJAX_FMA"


def with_separate_roundings(flags: str, machine: str | None = None) -> str:
    """``XLA_FLAGS`` text ``flags`` with ``--xla_cpu_max_isa=AVX`` appended on x86-64; a ``--xla_cpu_max_isa``
    the flags already give is kept, as is every other flag, in its order."""
    kept = flags.split()
    machine = (machine or platform.machine()).lower()
    if machine not in ("x86_64", "amd64") or any(f.split("=", 1)[0] == ISA_FLAG for f in kept):
        return " ".join(kept)
    return " ".join([*kept, SEPARATE_ROUNDINGS])


def use_separate_roundings() -> bool:
    """Ask XLA:CPU for code without FMA (``with_separate_roundings``) unless ``$GEOJAX_FMA`` is set.

    Returns whether the flag is in effect.  Once JAX has started a backend its flags are fixed: then a warning
    says so (the numbers may depend on the batch's width in the last bit) unless the flag was given already.
    """
    if os.environ.get(ENV_FMA, "").strip() not in ("", "0"):
        return False
    flags = os.environ.get("XLA_FLAGS", "")
    wanted = with_separate_roundings(flags)
    if wanted == " ".join(flags.split()):
        return SEPARATE_ROUNDINGS in flags.split()
    from jax._src import xla_bridge

    if xla_bridge.backends_are_initialized():
        print("geojax: warning: JAX started before geojax was imported, so XLA may fuse multiply-adds and the "
              "last bit of a result may depend on the batch's width (import geojax first, or set "
              f"XLA_FLAGS={SEPARATE_ROUNDINGS})", file=sys.stderr)
        return False
    os.environ["XLA_FLAGS"] = wanted
    return True
