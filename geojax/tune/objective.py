"""The objective of a tuning: the rollout of a parameter vector, its loss and box constraints, and their derivatives.

``Problem`` compiles, once per scenario, the batched exact evaluation of many parameter vectors (the
controller's own law) and the derivatives of its smooth surrogate (``Controller.surrogate``; a controller
without one is smooth and its own).  The figure minimised is the yearly Delta-V of the horizon
(``dv_per_year_mps``); the box is Katz 2025's eq. (10), normalised: one constraint per axis,
g = max(excursion^2) / Delta_s^2 - 1 <= 0; then each carried part's constraints in the same form
(``states.base.Constraint``: the wheels' g = (max |h_w| / capacity)^2 - 1 <= 0, so a dumping gain is tuned with
the box and the wheels as constraints).

Derivatives are forward-mode by default (``jacfwd``: no tape, so memory does not grow with the horizon; for 2-7
parameters about twice as fast as reverse mode on a CPU); ``gradient = "reverse"`` takes them through the
rollout's ``jax.checkpoint`` on each day, so memory grows with days, not steps.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from geojax import scenario as scenario_mod
from geojax.control.base import SURROGATE_TEMPERATURE, Controller
from geojax import states as parts
from geojax.loop.metrics import STATUS_LEFT_LAT_BOX, STATUS_LEFT_LON_BOX, STATUS_NONFINITE
from geojax.runner.rollout import rollout_fn
from geojax.runner.setup import prepare, unstack
from geojax.parallel import shard_batch
from geojax.params import Params
from geojax.tune.space import from_theta, tuned

# The box's constraints, the first of ``Problem.evaluate``'s constraint vector (the carried parts' follow).
BOX_CONSTRAINTS = ("lon", "lat")


class Problem:
    """The tuning problem of one scenario: batched exact evaluation and surrogate gradients, compiled once."""

    def __init__(self, sc: scenario_mod.Scenario, names, penalty_mps: float = 200.0, margin: float = 0.02,
                 gradient: str = "forward", controller: Controller | None = None, lanes: int = 1):
        """``lanes``: starts evaluated per device (the rollout is compiled for it)."""
        self.batch = prepare([sc], controller)
        self.base = unstack(self.batch.params, 0)
        self.entries = tuned(sc, controller, names)
        self.names = tuple(e.name for e in self.entries)
        self.sizes = [int(np.size(e.leaves_in(self.base)[e.field.si])) for e in self.entries]
        self.box_half_width_rad = float(self.base.station["box_half_width_rad"])
        self.part_constraints = tuple(c for p in parts.parts_of(self.batch.states) for c in p.constraints)
        self.constraint_names = BOX_CONSTRAINTS + tuple(c.name for c in self.part_constraints)
        self.statuses = parts.status_meanings(self.batch.states)
        self._rollouts = {False: rollout_fn(self.batch, lanes=lanes),
                          True: rollout_fn(self.batch, controller=self.batch.controller.surrogate or self.batch.controller,
                                           lanes=lanes)}
        self.penalty_mps, self.margin = penalty_mps, margin
        self._exact = jax.jit(jax.vmap(lambda th: self.evaluate(th, smooth=False)[1]))
        self._single = jax.jit(lambda th: self.evaluate(th, smooth=False)[1])
        self._grad = jax.jit(jax.vmap(_value_and_grad(self.evaluate, gradient), in_axes=(0, None)))
        self._jacobian = jax.jit(jax.vmap(_jacobian(self.evaluate, gradient), in_axes=(0, None)))

    @property
    def exact_is_smooth(self) -> bool:
        """A controller without a surrogate is smooth (a sampled-and-held law has one): its gradient run already
        is the exact evaluation."""
        return self.batch.controller.surrogate is None

    @property
    def days(self) -> int:
        return self.batch.n_cycles

    def params(self, theta) -> Params:
        return from_theta(theta, self.base, self.entries)

    def evaluate(self, theta, smooth: bool, temperature=0.05):
        """(loss, (dv_per_year_mps, constraint [2 or 3] lon/lat(/wheels), box_ok)) of one parameter vector."""
        params = self.params(theta)
        if SURROGATE_TEMPERATURE in params.controller:
            params = params._replace(controller={**params.controller, SURROGATE_TEMPERATURE: jnp.asarray(temperature)})
        _, _, m = self._rollouts[smooth](params, jax.random.key(0))
        excursion = jnp.radians(jnp.stack([m["max_abs_dlon_deg"], m["max_abs_dlat_deg"]]))
        # Katz eq. (10): delta^2 - Delta_s^2 <= 0, (lambda - lambda_d)^2 - Delta_s^2 <= 0, normalised.
        constraint = (excursion / self.box_half_width_rad) ** 2 - 1.0
        failed = [STATUS_LEFT_LON_BOX, STATUS_LEFT_LAT_BOX, STATUS_NONFINITE]
        for c in self.part_constraints:  # the parts' (the wheels within their capacity), the same form
            constraint = jnp.append(constraint, c.value(params, m))
            failed.append(self.statuses.index(c.status))
        loss = m["dv_per_year_mps"] + self.penalty_mps * jnp.sum(jax.nn.relu(constraint + self.margin))
        box_ok = ~jnp.isin(m["status"], jnp.array(failed))
        return loss, (m["dv_per_year_mps"], constraint, box_ok.astype(float))

    def exact(self, thetas):
        """Exact-law (dv_per_year_mps [n], constraint [n, C], box_ok [n]) of a batch of parameter vectors."""
        return self._exact(_spread(thetas))

    def exact_one(self, theta):
        return self._single(jnp.asarray(theta))

    def surrogate_grad(self, thetas, temperature):
        (loss, aux), grad = self._grad(_spread(thetas), jnp.asarray(temperature))
        return loss, aux, grad

    def linearise(self, thetas, temperature):
        """Exact (dv [n], constraint [n, C], box_ok [n]) and the surrogate's Jacobian [n, 1 + C, P] of
        (dv, the constraints); one pass when the exact law is itself smooth."""
        jac, aux = self._jacobian(_spread(thetas), jnp.asarray(temperature))
        exact = aux if self.exact_is_smooth else self.exact(thetas)
        return (*(np.array(v) for v in exact), np.array(jac))


def _value_and_grad(evaluate, gradient: str):
    """(loss, aux), d loss / d theta of the surrogate rollout.

    "forward": forward-mode (``jacfwd``), P tangents carried through one pass: no tape at all, so memory does
    not grow with the horizon, and for the few parameters tuned here (2 to 7) it is about twice as fast as
    reverse mode on a CPU.  "reverse": ``value_and_grad`` through the day-checkpointed rollout (memory grows
    with the number of days only), the choice when many parameters are tuned.
    """
    def surrogate(theta, temperature):
        loss, aux = evaluate(theta, smooth=True, temperature=temperature)
        return loss, (loss, aux)

    if gradient == "forward":
        def forward(theta, temperature):
            grad, (loss, aux) = jax.jacfwd(surrogate, has_aux=True)(theta, temperature)
            return (loss, aux), grad
        return forward
    if gradient == "reverse":
        return jax.value_and_grad(lambda th, t: evaluate(th, smooth=True, temperature=t), has_aux=True)
    raise ValueError(f"gradient: must be 'forward' or 'reverse', got {gradient!r}")


def _jacobian(evaluate, gradient: str):
    """theta -> (d(dv, g_lon, g_lat)/d theta [3, P], (dv, g, box_ok)) of the surrogate rollout, in one pass
    (forward mode: P tangents; reverse: three cotangents through the checkpointed rollout)."""
    def outputs(theta, temperature):
        _, (dv, g, ok) = evaluate(theta, smooth=True, temperature=temperature)
        return jnp.concatenate([dv[None], g]), (dv, g, ok)

    if gradient == "forward":
        return jax.jacfwd(outputs, has_aux=True)
    if gradient == "reverse":
        return jax.jacrev(outputs, has_aux=True)
    raise ValueError(f"gradient: must be 'forward' or 'reverse', got {gradient!r}")


def _spread(thetas):
    """The batch of starts, sharded over the local devices when it divides evenly (``geojax.parallel``)."""
    thetas = jnp.asarray(thetas)
    if jax.device_count() > 1 and thetas.shape[0] % jax.device_count() == 0:
        return shard_batch(thetas)
    return thetas
