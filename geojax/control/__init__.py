"""Station-keeping controllers (DESIGN.md layer 4): one module per controller, on the protocol of ``control.base``.

``REGISTRY`` maps a scenario's ``controller.kind`` to its module; each module
defines ``FIELDS`` (its ``[controller]`` keys), ``make(tables) -> Controller``
(``tables``: the validated ``[controller]`` tables of every scenario in a
batch, so a factory can size what is static, e.g. the FOMPC's padded horizon)
and optionally ``validate(config)`` (checks across tables at load).
"""

from geojax.control import fompc, lyapunov, mpc, none, qffc, zone_nssk
from geojax.control.base import Controller

REGISTRY = {
    "none": none,
    "qffc": qffc,
    "fompc": fompc,
    "lyapunov": lyapunov,
    "zone_nssk": zone_nssk,
    "mpc": mpc,
}

__all__ = ["Controller", "REGISTRY"]
