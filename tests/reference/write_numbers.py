"""Writes ``tests/reference/numbers.npz``: every record, metric and status of short runs of shipped scenarios,
the numbers ``tests/test_reference_numbers.py`` holds every later checkout to, bit for bit on the platform they
were written on (``platform()``: XLA compiles for the host's vector instructions, and another CPU or another
jaxlib moves the last bits: measured, 1e-16 to 7e-9 relative between two x86-64 CPUs), to 1e-6 elsewhere.

Regenerate deliberately, and only when a change is meant to move numbers (say which and why in the commit):
``python tests/reference/write_numbers.py``.  The runs cover the padded one-sample loop (``simulate``) and the
plain scan a sweep and a tuning run (``rollout_fn``), no part, the wheels and the navigation filter, and each
family of controller.
"""

from __future__ import annotations

import sys
from pathlib import Path

import jax
import numpy as np

import geojax
from geojax import arithmetic, scenario
from geojax.runner import setup
from geojax.runner.rollout import rollout_fn, simulate

HERE = Path(__file__).resolve().parent
DAYS = 4
# (label, scenario, overrides, seed): run through ``simulate`` (the padded one-sample loop)
SIMULATED = (
    ("qffc", "li2022-qffc", {"errors.h_rv": 1.0, "errors.h_att": 1.0}, 3),
    ("fompc", "li2022-fompc", {"errors.h_rv": 1.0}, 2),
    ("momentum", "li2022-momentum", {}, 1),
    ("ranging", "li2022-qffc-ranging", {}, 5),
    ("zone", "ye2022-ex1", {}, 0),
)
# run through ``rollout_fn`` (the plain scan of sweeps and tunings)
ROLLED = (("katz", "katz2025-continuous", {}, 5),)


def flat(tree, prefix: str, out: dict) -> None:
    if hasattr(tree, "_fields"):
        for k in tree._fields:
            flat(getattr(tree, k), f"{prefix}.{k}", out)
    elif isinstance(tree, dict):
        for k, v in tree.items():
            flat(v, f"{prefix}.{k}", out)
    elif tree is not None:
        out[prefix] = np.asarray(tree)


def platform() -> str:
    """What the last bits of a compiled run depend on: jax and jaxlib, and the CPU (its model and the vector
    instructions XLA may use, capped by ``--xla_cpu_max_isa``: ``geojax.arithmetic``)."""
    import hashlib
    import os
    import platform as host

    import jaxlib

    flags, model = "", host.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags") and not flags:
                flags = line.split(":", 1)[1]
            if line.startswith("model name") and not model:
                model = line.split(":", 1)[1].strip()
    except OSError:
        pass
    cap = next((f.split("=", 1)[1] for f in os.environ.get("XLA_FLAGS", "").split()
                if f.split("=", 1)[0] == arithmetic.ISA_FLAG), "")
    isa = " ".join(sorted(f for f in flags.split() if f.startswith(("avx", "sse", "fma", "amx"))))
    return (f"jax {jax.__version__}, jaxlib {jaxlib.__version__}, {host.machine()} {model}, "
            f"isa {hashlib.sha256(isa.encode()).hexdigest()[:12]}{cap and ', max ' + cap}")


def numbers() -> dict[str, np.ndarray]:
    out = {}
    for label, name, overrides, seed in SIMULATED:
        r = simulate(scenario.load(name, {"duration.days": DAYS, **overrides}), seed=seed)
        flat(r.records, f"{label}.records", out)
        flat(r.metrics, f"{label}.metrics", out)
        out[f"{label}.status"] = np.asarray(r.status)
    for label, name, overrides, seed in ROLLED:
        batch = setup.prepare([scenario.load(name, {"duration.days": DAYS, **overrides})])
        params = jax.tree_util.tree_map(lambda x: x[0], batch.params)
        _, records, metrics = jax.jit(rollout_fn(batch))(params, jax.random.key(seed))
        flat(records, f"{label}.records", out)
        flat(metrics, f"{label}.metrics", out)
    return out


if __name__ == "__main__":
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE / "numbers.npz"
    np.savez_compressed(path, **numbers(), platform=np.asarray(platform()))
    print(f"{path}: written by geojax {geojax.__version__}")
