"""GTO-GEO low-thrust transfers with a triple orthogonal gimbaled thruster boom or the quadrilateral layout (Ma & Kong
2023).

``scenario`` loads and validates a transfer TOML; ``rollout.transfer`` is the pure per-transfer function
(vmap it for a batch); ``run.run`` compiles and runs one.  ``steering`` holds eq. (1), ``boom`` eqs. (7)-(9)
and the joint MPC of Sec. 3, ``quadrilateral`` the paper's baseline layout, ``pointing`` the body slew, the
body/boom split of Remark 2 and the attitude propellant, ``wheels`` the reaction wheels' momentum and its
unloading (by attitude thrusters or by the boom's own line).
"""

from geojax.transfer.rollout import STATUS_MEANINGS, STATUS_REACHED_GEO, Static, TransferParams, transfer
from geojax.transfer.run import TransferResult, env_grid, metrics, run, run_batch, stack, static_for
from geojax.transfer.scenario import TransferScenario, available, load

__all__ = ["STATUS_MEANINGS", "STATUS_REACHED_GEO", "Static", "TransferParams", "TransferResult", "TransferScenario",
           "available", "env_grid", "load", "metrics", "run", "run_batch", "stack", "static_for", "transfer"]
