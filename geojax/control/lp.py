"""Linear programs with exact-penalty soft rows, solved in pure JAX by a primal-dual interior-point method.

    minimise    c'x + sum_k p_k dist(a_k'x, [l_k, u_k])        (p_k = inf: a hard row, l_k <= a_k'x <= u_k)

Each finite bound of a row is an inequality with a slack s >= 0 and a multiplier z >= 0; a soft row's
side also gets a violation v >= 0 of cost p (a_k'x - v <= u_k), whose multiplier zeta = p - z keeps z <= p,
so the program is always feasible.  Mehrotra's predictor-corrector (Nocedal & Wright, "Numerical
Optimization", 2nd ed., Algorithm 14.3, on this inequality form) takes two solves per iteration with one
factorisation of the normal matrix A' diag(omega) A, omega = 1 / (s / z + v / zeta) per side (the slack,
the violation and their multipliers eliminated), step 0.99 of the way to the boundary.

The matrix A is never formed by the solver: an ``Operator`` gives A x, A'y, the solve of
diag(sigma) + A' diag(rho) A and the row and column norms of a scaling of A, so a caller with structure
(the MPC's condensed dynamics, ``control.mpc``) factors a small matrix, and ``dense_operator`` serves any
dense A.  The problem is first equilibrated (OSQP's modified Ruiz scaling).  The iterations run in a
``lax.while_loop`` that stops when ``certify`` accepts the iterate (duality gap, hard-row violation and
dual residual within ``tolerance``); under ``vmap`` a batch runs until its slowest member has converged,
or for ``Settings.iterations`` at most.  Its sums (the complementarity mean, the objectives) are added in a
fixed order (``reductions.sum_pairwise``), so that a lane's iterates, and when it stops, do not depend on the
batch's width.

Why not ADMM in the OSQP form (tried first): on the MPC's programs (``control.mpc``), whose longitude rows
are ~1e4 times more sensitive to tangential Delta-V than the inclination rows, it left half of 16 random
plans unsolved after 4000 iterations, with Ruiz scaling, adaptive rho and polishing; this method solves
them all in 15-30 iterations.  (PDHG, untried, is as sensitive to the conditioning.)
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp

from geojax.reductions import sum_pairwise


class Settings(NamedTuple):
    """The solver's shape (static: hashable Python numbers)."""

    iterations: int = 40  # interior-point iterations at most
    step_fraction: float = 0.99  # of the step to the boundary of the positive orthant
    regularization: float = 1e-12  # added to the normal matrix's diagonal (relative to the scaled problem)
    scaling_iterations: int = 10  # Ruiz equilibration passes (OSQP's default)


class Operator(NamedTuple):
    """The constraint matrix A [m, n] as functions (closures over the caller's arrays)."""

    matvec: Callable  # x [n] -> A x [m]
    rmatvec: Callable  # y [m] -> A'y [n]
    factor: Callable  # (rho [m], sigma [n]) -> solve: rhs [n] -> (diag(sigma) + A' diag(rho) A)^-1 rhs
    norms: Callable  # (d [m], e [n]) -> the infinity norms of the rows [m] and columns [n] of diag(d) A diag(e)


def scaled(operator: Operator, d, e) -> Operator:
    """The operator of diag(d) A diag(e) (``equilibrate``'s scaling)."""

    def factor(rho, sigma):
        solve = operator.factor(d * d * rho, sigma / (e * e))
        return lambda rhs: solve(rhs / e) / e

    return Operator(lambda x: d * operator.matvec(e * x), lambda y: e * operator.rmatvec(d * y), factor,
                    lambda d2, e2: operator.norms(d * d2, e * e2))


def equilibrate(operator: Operator, c, m: int, iterations: int):
    """OSQP's modified Ruiz equilibration (Stellato et al. 2020, Sec. 5.1, P = 0): row and column scalings d [m],
    e [n] that bring every row and column of diag(d) A diag(e) near unit infinity norm, and the cost scale."""
    d, e = jnp.ones(m), jnp.ones(c.shape[0])

    def guard(norm):  # OSQP: norms below 1e-4 (empty rows or columns) are left alone, the rest clipped
        return jnp.where(norm < 1e-4, 1.0, jnp.minimum(norm, 1e4))

    for _ in range(iterations):
        rows, cols = operator.norms(d, e)
        d, e = d / jnp.sqrt(guard(rows)), e / jnp.sqrt(guard(cols))
    return d, e, 1.0 / guard(_norm(e * c))


class Solution(NamedTuple):
    x: jnp.ndarray  # [n] primal solution
    ax: jnp.ndarray  # [m] the rows' values A x
    y: jnp.ndarray  # [m] multipliers of the rows (positive on an upper bound, negative on a lower one)
    objective: jnp.ndarray  # [] c'x + the soft rows' penalties at A x
    primal_residual: jnp.ndarray  # [] largest violation of a hard row
    dual_residual: jnp.ndarray  # [] |c + A'y|_inf
    iterations: jnp.ndarray  # [] int, iterations run
    converged: jnp.ndarray  # [] bool, certified optimal to the tolerance (``certify``)


def solve(c, operator: Operator, lower, upper, penalty, *, tolerance, settings: Settings = Settings()) -> Solution:
    """Minimise c'x + sum_k penalty_k dist(a_k'x, [lower_k, upper_k]) (see the module docstring).

    ``c`` [n]; ``lower``, ``upper`` [m] (may be -inf / inf; every variable must be bounded through some
    rows, e.g. x >= 0 as identity rows, so that the normal matrix is definite); ``penalty`` [m] (inf: a hard
    row); ``tolerance`` that of ``certify``.  Returns the first certified iterate, else the last.
    """
    m = lower.shape[0]
    # Solve the equilibrated problem: x = e x', rows d A x, cost s c, multipliers y = d y' / s.
    d, e, cost_scale = equilibrate(operator, c, m, settings.scaling_iterations)
    original = (c, operator, lower, upper, penalty)
    op = scaled(operator, d, e)
    c, lower, upper, penalty = cost_scale * e * c, d * lower, d * upper, cost_scale * penalty / d

    # Sides [2, m]: 0 the upper bound (a'x + s - v = u), 1 the lower (-a'x + s - v = -l).
    sign = jnp.array([1.0, -1.0])[:, None]
    present = jnp.stack([jnp.isfinite(upper), jnp.isfinite(lower)])
    h = jnp.where(present, jnp.stack([upper, -lower]), 0.0)
    soft = present & jnp.isfinite(penalty)[None]
    p = jnp.where(soft, penalty[None], 0.0)
    count = jnp.sum(present) + jnp.sum(soft)
    sigma = settings.regularization * jnp.ones_like(c)

    def multipliers(z):
        return jnp.where(present[0], z[0], 0.0) - jnp.where(present[1], z[1], 0.0)

    def residual(state):
        x, s, z, v, zeta = state
        ax = op.matvec(x)
        r_primal = jnp.where(present, sign * ax - v + s - h, 0.0)
        r_dual = c + op.rmatvec(multipliers(z))
        r_penalty = jnp.where(soft, p - z - zeta, 0.0)
        return ax, r_primal, r_dual, r_penalty

    def mu_of(s, z, v, zeta):
        return (sum_pairwise(jnp.where(present, s * z, 0.0).reshape(-1))
                + sum_pairwise(jnp.where(soft, v * zeta, 0.0).reshape(-1))) / count

    def iteration(carry):
        state, k = carry[:2]
        x, s, z, v, zeta = state
        _, r_primal, r_dual, r_penalty = residual(state)
        mu = mu_of(s, z, v, zeta)
        v_ratio = jnp.where(soft, v / zeta, 0.0)
        omega = jnp.where(present, 1.0 / (s / z + v_ratio), 0.0)
        normal_solve = op.factor(omega[0] + omega[1], sigma)

        def direction(r_slack, r_violation):  # complementarity residuals s z - target, v zeta - target
            rho = r_primal + jnp.where(soft, r_violation / zeta + v_ratio * r_penalty, 0.0) - r_slack / z
            dx = normal_solve(-r_dual - op.rmatvec(multipliers(omega * rho)))
            dz = jnp.where(present, omega * (sign * op.matvec(dx) + rho), 0.0)
            ds = jnp.where(present, (-r_slack - s * dz) / z, 0.0)
            dzeta = jnp.where(soft, r_penalty - dz, 0.0)
            dv = jnp.where(soft, (-r_violation - v * dzeta) / zeta, 0.0)
            return dx, ds, dz, dv, dzeta

        def step_to_boundary(values, deltas, mask):
            ratio = jnp.where(mask & (deltas < 0), -values / jnp.where(deltas < 0, deltas, -1.0), jnp.inf)
            return jnp.min(ratio)

        def longest(ds, dz, dv, dzeta):
            steps = [step_to_boundary(s, ds, present), step_to_boundary(z, dz, present),
                     step_to_boundary(v, dv, soft), step_to_boundary(zeta, dzeta, soft)]
            return jnp.minimum(1.0, jnp.min(jnp.stack(steps)))

        # Predictor (affine scaling), then the corrector with the centring sigma = (mu_aff / mu)^3.
        _, ds_a, dz_a, dv_a, dzeta_a = direction(s * z, v * zeta)
        a = longest(ds_a, dz_a, dv_a, dzeta_a)
        mu_affine = mu_of(s + a * ds_a, z + a * dz_a, v + a * dv_a, zeta + a * dzeta_a)
        target = (mu_affine / mu) ** 3 * mu
        dx, ds, dz, dv, dzeta = direction(s * z + ds_a * dz_a - target, v * zeta + dv_a * dzeta_a - target)
        a = settings.step_fraction * longest(ds, dz, dv, dzeta)
        new = (x + a * dx, s + a * ds, z + a * dz, v + a * dv, zeta + a * dzeta)
        # Past the accuracy the weights' spread allows, a factorisation can fail (NaN): keep the last
        # iterate and stop there.
        finite = jnp.all(jnp.stack([jnp.all(jnp.isfinite(part)) for part in new]))
        state = jax.tree_util.tree_map(lambda a_new, a_old: jnp.where(finite, a_new, a_old), new, state)
        certified = certify(c, op, lower, upper, penalty, state[0], multipliers(state[2]), tolerance)
        return state, k + 1, certified, ~finite

    def unfinished(carry):
        return (carry[1] < settings.iterations) & ~carry[2] & ~carry[3]

    # Start: x = 0, slacks at least 1 (a violated soft side takes its violation up in v), multipliers 1 or
    # half the penalty (so that z + zeta = p).
    x = jnp.zeros_like(c)
    margin = jnp.where(present, h - sign * op.matvec(x)[None], 1.0)
    v = jnp.where(soft, jnp.maximum(-margin, 0.0) + 1.0, 0.0)
    s = jnp.where(present, jnp.maximum(margin + v, 1.0), 1.0)
    z = jnp.where(soft, 0.5 * p, 1.0)
    zeta = jnp.where(soft, 0.5 * p, 1.0)
    start = ((x, s, z, v, zeta), jnp.asarray(0), jnp.asarray(False), jnp.asarray(False))
    (x, _, z, _, _), iterations, certified, _ = jax.lax.while_loop(unfinished, iteration, start)

    y = multipliers(z)
    c, operator, lower, upper, penalty = original
    x, y = e * x, d * y / cost_scale
    ax = operator.matvec(x)
    primal, dual = residuals(c, operator, lower, upper, penalty, ax, y)
    return Solution(x, ax, y, objective(c, ax, x, lower, upper, penalty), primal, dual, iterations, certified)


def residuals(c, operator: Operator, lower, upper, penalty, ax, y):
    """(largest violation of a hard row, |c + A'y|_inf) at row values ``ax`` and multipliers ``y``."""
    hard = jnp.isinf(penalty)
    primal = _norm(jnp.where(hard, jnp.maximum(lower - ax, 0.0) + jnp.maximum(ax - upper, 0.0), 0.0))
    return primal, _norm(c + operator.rmatvec(y))


def objective(c, ax, x, lower, upper, penalty):
    """c'x plus the soft rows' penalties at the row values ``ax``."""
    soft = jnp.isfinite(penalty)
    violation = jnp.maximum(lower - ax, 0.0) + jnp.maximum(ax - upper, 0.0)
    return sum_pairwise(c * x) + sum_pairwise(jnp.where(soft, jnp.where(soft, penalty, 0.0) * violation, 0.0))


def dual_objective(lower, upper, penalty, y):
    """The Lagrange dual's value at multipliers ``y`` with c + A'y = 0: -sum_k (u_k y_k+ - l_k y_k-), the
    support function of each row's interval; -inf where y_k leaves what row k allows (|y_k| <= p_k, and no
    multiplier on an infinite bound)."""
    pos, neg = jnp.maximum(y, 0.0), jnp.minimum(y, 0.0)
    support = jnp.where(pos > 0, upper, 0.0) * pos + jnp.where(neg < 0, lower, 0.0) * neg
    allowed = jnp.abs(y) <= penalty * (1 + 1e-9)
    return jnp.where(jnp.all(allowed), -sum_pairwise(support), -jnp.inf)


def certify(c, operator: Operator, lower, upper, penalty, x, y, tolerance):
    """Whether (x, y) is optimal to ``tolerance``: the hard rows hold and c + A'y = 0 (each relative to the
    problem's scale), and the duality gap is at most ``tolerance`` (1 + |objective|)."""
    ax = operator.matvec(x)
    primal, dual = residuals(c, operator, lower, upper, penalty, ax, y)
    value = objective(c, ax, x, lower, upper, penalty)
    gap = value - dual_objective(lower, upper, penalty, y)
    return (primal <= tolerance * (1 + _norm(ax))) & (dual <= tolerance * (1 + _norm(c))) \
        & (jnp.abs(gap) <= tolerance * (1 + jnp.abs(value)))


def _norm(v):
    return jnp.max(jnp.abs(v))


# Factorisations in plain XLA operations.  jaxlib's LAPACK kernels (lapack_dpotrf_ffi, lapack_dtrsm_ffi) split
# a large batch over XLA's intra-op thread pool from inside a running program; with one device per core
# (``geojax.parallel.per_device``, as sweeps run) both pool threads wait in such a kernel for work that no
# thread is left to run: the MPC at 64 lanes per device on 2 devices hung in ParallelBatchMap (gdb).  The
# matrices here are small (2G x 2G per cycle), so a column loop costs little under vmap.


def cholesky(a):
    """The lower Cholesky factor of a symmetric positive definite a [n, n] (NaN where it is not)."""
    n = a.shape[-1]
    index = jnp.arange(n)

    def column(k, factor_rest):
        factor, rest = factor_rest
        col = jnp.where(index >= k, rest[:, k] / jnp.sqrt(rest[k, k]), 0.0)
        return factor.at[:, k].set(col), rest - jnp.outer(col, col)

    return jax.lax.fori_loop(0, n, column, (jnp.zeros_like(a), a))[0]


def cho_solve(factor, b):
    """x with (L L') x = b for the lower factor L [n, n] of ``cholesky``; b [n] or [n, k]."""
    n = factor.shape[-1]

    def forward(i, y):
        return y.at[i].set((b[i] - factor[i] @ y) / factor[i, i])

    def backward(j, x):
        i = n - 1 - j
        return x.at[i].set((y[i] - factor[:, i] @ x) / factor[i, i])

    y = jax.lax.fori_loop(0, n, forward, jnp.zeros_like(b))
    return jax.lax.fori_loop(0, n, backward, jnp.zeros_like(b))


def dense_operator(a) -> Operator:
    """The ``Operator`` of a dense matrix ``a`` [m, n] (Cholesky of the n x n KKT matrix per stage)."""

    def factor(rho, sigma):
        lower = cholesky(jnp.diag(sigma) + a.T @ (rho[:, None] * a))
        return lambda rhs: cho_solve(lower, rhs)

    def norms(d, e):
        scaled_abs = jnp.abs(a) * d[:, None] * e[None, :]
        return jnp.max(scaled_abs, 1), jnp.max(scaled_abs, 0)

    return Operator(lambda x: a @ x, lambda y: a.T @ y, factor, norms)
