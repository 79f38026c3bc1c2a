"""Adam (optax) on the surrogate Delta-V plus a penalty on the box, on every start at once.

The first-order method, kept for comparison and for many-parameter problems: the loss is the surrogate's
yearly Delta-V plus ``penalty_mps`` times the violation of the box tightened by the margin
(``objective.Problem.evaluate``); every iterate is also flown with the exact law, which decides the best point.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import optax


def run(run_) -> str:
    """optax Adam on the penalised surrogate (the module docstring); ``run_``: the driver's ``Run``.  Returns the
    run's status message."""
    spec, problem = run_.spec, run_.problem
    theta = run_.theta0.copy()
    # Few parameters, few iterations: a learning rate decaying geometrically (large steps to find the box,
    # small ones to settle on its edge), a short momentum (b1), so a start that has crossed into the box
    # does not coast on through it, and a short second-moment memory (b2 = 0.5), so the penalty's large
    # gradients outside the box do not shrink the steps along the Delta-V gradient inside it.
    schedule = optax.exponential_decay(spec.learning_rate, max(spec.iterations, 1),
                                       spec.learning_rate_end / spec.learning_rate)
    optimiser = optax.adam(schedule, b1=spec.momentum, b2=0.5)
    opt_state = optimiser.init(jnp.asarray(theta))
    active = np.ones(spec.starts, bool)
    no_radius = np.full(spec.starts, np.nan)
    for it in range(spec.iterations + 1):
        temperature = run_.temperature(it)
        last = it == spec.iterations
        if last or not problem.exact_is_smooth:
            dv, g, ok = map(np.asarray, problem.exact(theta))
        if not last:
            loss, aux, grad = problem.surrogate_grad(theta, temperature)
            loss, grad = np.asarray(loss), np.asarray(grad)
            if problem.exact_is_smooth:
                dv, g, ok = map(np.asarray, aux)
        run_.keep_best(theta, dv, g, ok)
        if last:
            run_.record(it, dv, g, ok, np.full(spec.starts, np.nan), np.zeros(spec.starts), theta, temperature, active,
                        no_radius)
            return f"finished {spec.iterations} iterations"
        bad = ~(np.isfinite(loss) & np.all(np.isfinite(grad), axis=1))
        active = run_.diverged(it, bad, active)
        grad = np.where(active[:, None], grad, 0.0)
        updates, opt_state = optimiser.update(jnp.asarray(grad), opt_state)
        new = np.clip(theta + np.where(active[:, None], np.asarray(updates), 0.0), run_.low, run_.high)
        run_.record(it, dv, g, ok, loss, np.linalg.norm(new - theta, axis=1), theta, temperature, active, no_radius)
        theta = new
        if not active.any():
            return run_.all_diverged(it)
