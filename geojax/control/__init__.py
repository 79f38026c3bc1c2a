"""Station-keeping controllers (docs/design.md: controllers and parts): one module per controller, on the protocol of ``control.base``.

``REGISTRY`` maps a scenario's ``controller.kind`` to its module; each module
defines ``SPEC`` (``control.base.Spec``: its ``[controller]`` keys, checks and
thrusters) and ``make(tables) -> Controller`` (``tables``: the validated
``[controller]`` tables of every scenario in a batch, so a factory can size
what is static, e.g. the FOMPC's padded horizon).

A user's own controller needs no registration: ``controller.kind =
"package.module:NAME"`` (in a scenario, or a sweep's ``controllers``) imports
``NAME`` from ``package.module`` -- a ``Controller``, or a module-like object
with ``SPEC`` and ``make`` -- and ``lookup`` serves it like a shipped one.
"""

import functools
import importlib
from typing import Callable, NamedTuple

from geojax.control import fompc, lyapunov, mpc, mpc_momentum, none, qffc, zone_nssk
from geojax.control.base import Controller, Spec

REGISTRY = {
    "none": none,
    "qffc": qffc,
    "fompc": fompc,
    "lyapunov": lyapunov,
    "zone_nssk": zone_nssk,
    "mpc": mpc,
    "mpc_momentum": mpc_momentum,
}


class Imported(NamedTuple):
    """A user's ``Controller`` as a registry entry: its spec, and a factory that returns it (the same object
    every time, so its compiled rollouts are reused)."""

    SPEC: Spec
    make: Callable


def lookup(kind: str):
    """The registry entry of ``controller.kind``: a shipped module, or the controller an import path
    ``"package.module:NAME"`` names; ``ValueError`` naming ``controller.kind`` otherwise."""
    if isinstance(kind, str) and kind in REGISTRY:
        return REGISTRY[kind]
    if isinstance(kind, str) and kind.count(":") == 1 and all(kind.split(":")):
        return _imported(kind)
    raise ValueError(f"controller.kind: must be one of {', '.join(map(repr, REGISTRY))} or a controller of one's "
                     f"own as 'package.module:NAME', got {kind!r}")


@functools.cache
def _imported(path: str):
    module_name, name = path.split(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:  # ModuleNotFoundError included
        raise ValueError(f"controller.kind: cannot import {module_name!r} for {path!r} ({err})") from None
    found = getattr(module, name, None)
    if isinstance(found, Controller):
        return Imported(found.spec, lambda tables: found)
    if callable(getattr(found, "make", None)) and isinstance(getattr(found, "SPEC", None), Spec):
        return found
    raise ValueError(f"controller.kind: {path!r} is not a geojax Controller (found {type(found).__name__}); "
                     f"define NAME = geojax.Controller(init, plan, thrust, geojax.Spec(fields=...))")


__all__ = ["Controller", "REGISTRY", "Spec", "lookup"]
