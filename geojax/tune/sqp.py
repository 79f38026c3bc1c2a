"""The trust-region SQP of a tuning (the default method), on every start at once.

One forward-mode pass gives the whole Jacobian of (Delta-V, g_lon, g_lat) with respect to the parameters; each
start then solves a small QP (``qp_step``: the linearised box tightened by the margin, elastic when it cannot be
met, a damped-BFGS model of the Lagrangian's curvature that starts from one curvature fitted to all the starts'
gradients, an infinity-norm trust region) and the step is accepted on the *exact* law (``_better``): while
outside the box, when the violation shrinks; inside it, when the box is kept and Delta-V falls.  A rejected step
halves the trust region (down to ``trust_radius_min``: 0.02 for the sampled-and-held laws, about the scale below
which they are noise, and where a refused start probes a random neighbour instead of proposing the same step
again; 1e-6 for a smooth law); the run stops early when every step is shorter than ``step_tolerance``.
Constraint Jacobians are what a penalty cannot give: a start walks along the edge of the box instead of bouncing
off it.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize


def run(run_) -> str:
    """Trust-region SQP on every start at once (the module docstring); ``run_``: the driver's ``Run``.  Returns
    the run's status message."""
    spec, problem = run_.spec, run_.problem
    theta = run_.theta0.copy()
    n, n_par = theta.shape
    dv, g, ok, jac = problem.linearise(theta, run_.temperature(0))
    run_.keep_best(theta, dv, g, ok)
    radius = np.full(n, run_.trust_radius)
    # The first model's curvature: fitted over the starts; with too few, an unconstrained step as long as
    # the trust region.
    norms = np.linalg.norm(jac[:, 0], axis=1)
    norms = norms[np.isfinite(norms) & (norms > 0)]
    scale = (float(np.median(norms)) if norms.size else 1.0) / run_.trust_radius
    hessian = np.tile(population_hessian(theta, jac[:, 0], np.eye(n_par) * scale), (n, 1, 1))
    margin = np.full(g.shape, run_.margin)  # per start and constraint; see the end of the loop
    refused = np.zeros(n, bool)
    rng = np.random.default_rng(spec.seed + 1)
    active = np.ones(n, bool)
    step = np.zeros(n)
    for it in range(spec.iterations + 1):
        temperature = run_.temperature(it)
        active = run_.diverged(it, ~_finite(dv, g, jac), active)
        run_.record(it, dv, g, ok, np.where(ok > 0, dv, np.nan), step, theta, temperature, active, radius)
        if it == spec.iterations:
            return f"finished {spec.iterations} iterations"
        if not active.any():
            return run_.all_diverged(it)
        steps = np.zeros_like(theta)
        multipliers = np.zeros(g.shape)
        for i in np.flatnonzero(active):
            steps[i], multipliers[i] = qp_step(jac[i, 0], hessian[i], g[i] + margin[i], jac[i, 1:], radius[i],
                                               run_.low - theta[i], run_.high - theta[i])
        if np.all(np.max(np.abs(steps[active]), axis=1) < spec.step_tolerance):
            return f"converged at iteration {it}: every step below {spec.step_tolerance:g} (natural-log units)"
        # A start refused at the smallest trust region would propose the same step again: below that scale the
        # sampled-and-held laws are noise the model cannot see, so it probes a random neighbour instead.
        stuck = active & refused & (radius <= run_.trust_radius_min) & (run_.noise_mps > 0)
        steps += np.where(stuck[:, None], rng.uniform(-1.0, 1.0, steps.shape) * run_.trust_radius_min, 0.0)
        trial = np.clip(theta + steps, run_.low, run_.high)
        steps = trial - theta
        dv_t, g_t, ok_t, jac_t = problem.linearise(trial, run_.temperature(it + 1))
        finite = _finite(dv_t, g_t, jac_t)
        run_.keep_best(trial, np.where(finite, dv_t, np.nan), g_t, np.where(finite, ok_t, 0.0))
        accept = active & finite & _better(dv, g, dv_t, g_t, run_.noise_mps)
        step_len = np.max(np.abs(steps), axis=1)
        for i in np.flatnonzero(accept):
            lagrangian_change = (jac_t[i, 0] - jac[i, 0]) + multipliers[i] @ (jac_t[i, 1:] - jac[i, 1:])
            hessian[i] = damped_bfgs(hessian[i], steps[i], lagrangian_change)
        grow = accept & (step_len >= 0.9 * radius)
        radius = np.where(grow, np.minimum(2.0 * radius, 2.0 * run_.trust_radius), radius)
        radius = np.where(active & ~accept, np.maximum(0.5 * step_len, run_.trust_radius_min), radius)
        take = lambda new, old: np.where(accept.reshape((-1,) + (1,) * (np.ndim(old) - 1)), new, old)  # noqa: E731
        theta, dv, g, ok, jac = take(trial, theta), take(dv_t, dv), take(g_t, g), take(ok_t, ok), take(jac_t, jac)
        step = np.where(accept, step_len, 0.0)
        refused = active & ~accept
        # A step refused for leaving the box aims that much further inside next time (the linearised constraint
        # under-predicted the exact one by ``miss``); an accepted step relaxes the start's margin halfway back.
        miss = np.maximum(g_t - (g + np.einsum("ncp,np->nc", jac[:, 1:], steps)), 0.0)
        refused_outside = (active & ~accept & (np.max(g_t, axis=1) > 0))[:, None]
        margin = np.where(refused_outside, np.minimum(margin + miss * (g_t > 0), 0.5), margin)
        margin = np.where(accept[:, None], 0.5 * (margin + run_.margin), margin)


def _finite(dv, g, jac) -> np.ndarray:
    return np.isfinite(dv) & np.all(np.isfinite(g), axis=1) & np.all(np.isfinite(jac), axis=(1, 2))


def _better(dv, g, dv_new, g_new, tolerance_mps: float) -> np.ndarray:
    """The SQP's acceptance on the exact law: outside the box, a smaller violation; inside, the box kept and
    a Delta-V no more than ``tolerance_mps`` higher (a filter with two entries: no penalty weight, so noise in
    the constraint cannot outweigh a Delta-V gain).  The tolerance is the noise of the sampled-and-held laws,
    whose yearly Delta-V jumps by a few 0.01 m/s/yr between neighbouring gains: without it a step along the
    smooth trend is refused by a jump, and then proposed again and again."""
    violation, violation_new = np.sum(np.maximum(g, 0.0), axis=1), np.sum(np.maximum(g_new, 0.0), axis=1)
    return np.where(violation > 0, violation_new < violation, (violation_new == 0) & (dv_new < dv + tolerance_mps))


def qp_step(grad, hessian, g, jac_g, radius, low, high, elastic_weight: float = 1e3):
    """min grad.d + d'Hd/2 + w sum(t)  s.t.  g + jac_g d <= t, t >= 0, |d|_inf <= radius, low <= d <= high.

    The elastic t keeps the subproblem solvable when the linearised box cannot be reached inside the trust
    region (it then moves as far toward it as it can).  Returns (d, multipliers of the constraints),
    the multipliers estimated from the stationarity of the step (zero for inactive constraints).
    """
    n_par, n_con = grad.size, g.size
    lower, upper = np.maximum(-radius, low), np.minimum(radius, high)

    def objective(x):
        d, t = x[:n_par], x[n_par:]
        return grad @ d + 0.5 * d @ hessian @ d + elastic_weight * t.sum(), \
            np.concatenate([grad + hessian @ d, np.full(n_con, elastic_weight)])

    constraint = {"type": "ineq", "fun": lambda x: x[n_par:] - g - jac_g @ x[:n_par],
                  "jac": lambda x: np.hstack([-jac_g, np.eye(n_con)])}
    x0 = np.concatenate([np.zeros(n_par), np.maximum(g, 0.0)])
    bounds = [(lo, hi) for lo, hi in zip(lower, upper)] + [(0.0, None)] * n_con
    res = minimize(objective, x0, jac=True, method="SLSQP", constraints=[constraint], bounds=bounds,
                   options={"maxiter": 200, "ftol": 1e-14})
    d = np.clip(res.x[:n_par], lower, upper)
    binding = g + jac_g @ d >= -1e-9 * (1.0 + np.abs(g))
    free = (d > lower + 1e-12) & (d < upper - 1e-12)
    multipliers = np.zeros(n_con)
    if binding.any() and free.any():
        residual = -(grad + hessian @ d)
        solution = np.linalg.lstsq(jac_g[binding][:, free].T, residual[free], rcond=None)[0]
        multipliers[binding] = np.maximum(solution, 0.0)
    return d, multipliers


def population_hessian(theta, grad, fallback):
    """One curvature for every start's first model: the symmetric H of grad_i - mean = H (theta_i - mean),
    fitted by least squares over the starts, its eigenvalues floored at 1e-3 of the largest so that it is
    positive definite.  The starts sample the landscape around the scenario's gains, so their gradients
    together see a curvature no single start has yet (on the smooth law it saves about two iterations).
    ``fallback`` when there are too few finite starts to fit it."""
    keep = np.all(np.isfinite(grad), axis=1)
    theta, grad = theta[keep], grad[keep]
    if len(theta) <= theta.shape[1]:
        return fallback
    d_theta, d_grad = theta - theta.mean(axis=0), grad - grad.mean(axis=0)
    h = np.linalg.lstsq(d_theta, d_grad, rcond=None)[0]
    w, v = np.linalg.eigh(0.5 * (h + h.T))
    if not np.all(np.isfinite(w)) or np.max(w) <= 0.0:
        return fallback
    return (v * np.maximum(w, 1e-3 * np.max(w))) @ v.T


def damped_bfgs(hessian, s, y):
    """Powell's damped BFGS update: stays positive definite when the curvature along s is negative."""
    hs = hessian @ s
    shs, sy = float(s @ hs), float(s @ y)
    if shs <= 0.0:
        return hessian
    if sy < 0.2 * shs:
        weight = 0.8 * shs / (shs - sy)
        y = weight * y + (1.0 - weight) * hs
        sy = float(s @ y)
    return hessian - np.outer(hs, hs) / shs + np.outer(y, y) / sy
