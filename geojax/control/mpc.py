"""Minimum-fuel receding-horizon controller: one linear program per cycle, first cycle flown.

Each cycle the controller solves Gazzino 2016's minimum-fuel problem (Problem 3: L1 fuel, linear dynamics,
a box) over the next N cycles on Li 2022's predictor model, and flies the first cycle's burns:

* State: the mean elements x_j = (lambda, lambda_dot, e_x, e_y, i_x, i_y) (MEE f, g, h, k) at the cycle
  boundaries j = 0..N from the estimate x_0; x_{j+1} = Phi x_j + (the reference's natural drift of cycle j,
  Li 2022 eqs. (25)-(27), as the QFFC and the FOMPC predict) + B(l_1) v_1j + B(l_2) v_2j, with B of
  ``control.effects`` (eq. (22) re-derived; its longitude row carries the drift until the cycle's end) and
  Phi advancing the longitude by the drift over each later cycle.  The state is condensed away.
* Burns: two per cycle as the QFFC's, thruster 1 (south) at l_1 and thruster 2 (north) at l_2 = l_1 + pi,
  l_2 by eq. (31) from the inclination deviation the natural drift leaves at the end of the horizon (the
  same for every cycle of the horizon).  A burn's Delta-V is sum_g w_g d_g, w >= 0, over a ``yaw_points``
  x ``pitch_points`` grid d_g of the arm's rectangle (eq. (1), built from the thrusters' traced leaves, so a
  sweep over beta_max compiles once); the fuel is sum w; each burn's sum w <= F / m x ``max_burn_h``.
* Rows at every boundary 1..N: the mean longitude within the box less the daily libration
  2 (|e_T| + e_max) and ``lon_margin_deg``; e and i within e_max and Delta i_max of their targets (inscribed
  polygons of ``facets`` sides); at N, the longitude ``terminal_cycles`` cycles on at the last drift.  Each
  row is soft, with an exact L1 penalty (``penalty_mps`` per half-width violated), so the program is always
  feasible inside ``jit``; a plan violating a row by more than 1 % of its half-width is not ``solved``.
* Later Delta-V is discounted by ``defer`` per cycle.  The timing of a correction is otherwise degenerate and
  the interior point returns the centre of the optimal face, a share of it in every cycle, so the loop
  never lets i reach the edge of its window: li2022, one year, 50.1 m/s/yr without the discount, 48.7
  with it (N = 20; the same from 1e-4 to 1e-2).
* Solver: ``control.lp``, a Mehrotra interior point certified by its duality gap (``tolerance``,
  ``iterations`` at most; 15-30 are used), with the normal matrix factored by a Riccati recursion over the
  horizon (``operator``); ``control.lp`` says why not ADMM.  N is padded to a static N_max (the largest of
  a batch): cycles beyond N have no effect and no rows, so a sweep over N compiles once.

Defaults, measured on li2022 (2020, normal limits, one year, the bound 47.65 m/s/yr): N = 20 and Delta
i_max = 3.3e-4 give 48.7 m/s/yr (N = 10: 49.3; Delta i_max = 3.5e-4: 48.6 with latitudes to 0.045 deg);
e_max = 2e-4 keeps the longitude within 0.039 deg at the same fuel as 2.5e-4; the 3 x 2 grid of
directions (yaw limits and middle, pitch 0 and beta_max) flies the same fuel as 4 x 3 or 5 x 4 at a sixth of
the cost.  The first cycle's burns are flown by ``control.burns`` as the QFFC's (thrust windows, shadow,
attitude errors, burn records); a resultant outside the arm's rectangle (two directions at the pitch limit
combine to a steeper one) is flown at its nearest (yaw, pitch) inside, with the planned magnitude.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control import burn_metrics
from geojax.control import burns as burns_mod
from geojax.control import lp
from geojax.control.base import Controller, Sizing, Spec
from geojax.control.effects import V_SYNC_MPS, cycle_coast_s, effect_matrix
from geojax.control.predictor import predict_next
from geojax.control.qffc import BurnPair
from geojax.params import LOG, NUMBER, Field, degrees, station_target
from geojax.physics.elements import wrap_angle
from geojax.physics.propulsion import alpha_beta_bounds, arm_limits, delta_v_direction_rsw
from geojax.per_lane import lane_by_lane

HORIZON_LIMIT = 30  # cycles: the largest N_max accepted
SOLVED_VIOLATION = 0.01  # a plan violating a row by more than this fraction of its half-width is "not solved"

THRUSTERS = (2, "Li 2022's two robotic arms, one burn of each per cycle")  # control.base
REDUNDANT_THRUSTERS = 4  # or two per arm (``control.burns`` allocating, ``qffc.REDUNDANT_THRUSTERS``)

FIELDS = {
    # Horizon N (cycles) and the limits of the mean elements about their targets.
    "horizon": Field(int, 20, lower=1, upper=HORIZON_LIMIT + 1, lower_inclusive=True, si="horizon"),
    "di_max": Field(NUMBER, 3.3e-4, lower=0.0, si="di_max", transform=LOG),  # MEE (h, k), as the FOMPC's
    "e_max": Field(NUMBER, 2e-4, lower=0.0, si="e_max", transform=LOG),  # MEE (f, g)
    "lon_margin_deg": Field(NUMBER, 0.005, lower=0.0, lower_inclusive=True, si="lon_margin_rad", to_si=degrees),
    "terminal_cycles": Field(NUMBER, 3.0, lower=0.0, lower_inclusive=True, upper=1e3, si="terminal_cycles"),
    # Capacity of one burn (hours at full thrust) and the soft rows' penalty (m/s per half-width violated).
    "max_burn_h": Field(NUMBER, 2.0, lower=0.0, upper=6.0 + 1e-9, si="max_burn_s", to_si=3600.0),
    "penalty_mps": Field(NUMBER, 100.0, lower=0.0, si="penalty_mps", transform=LOG),
    # The relative discount per cycle on later Delta-V (breaks the program's tie in the timing of corrections).
    "defer": Field(NUMBER, 1e-3, lower=0.0, lower_inclusive=True, upper=0.02, si="defer"),
    # The solver (``control.lp``): the certificate's tolerance, and interior-point iterations at most (static).
    "tolerance": Field(NUMBER, 1e-7, lower=0.0, upper=1.0, si="tolerance"),
    "iterations": Field(int, 40, lower=1, upper=10001, lower_inclusive=True, static=True),
    # The burn directions (yaw x pitch grid per thruster) and the polygons' sides (static: shapes).
    "yaw_points": Field(int, 3, lower=1, upper=33, lower_inclusive=True, static=True),
    "pitch_points": Field(int, 2, lower=1, upper=33, lower_inclusive=True, static=True),
    "facets": Field(int, 12, lower=4, upper=129, lower_inclusive=True, static=True),
}


class Shape(NamedTuple):
    """What sets the compiled plan's shapes (static: hashable Python numbers)."""

    n_max: int = 20  # horizon padding (cycles)
    yaw_points: int = 3
    pitch_points: int = 2
    facets: int = 12  # sides of the e and i polygons (even)
    iterations: int = 40  # interior-point iterations at most

    @property
    def generators(self) -> int:
        return self.yaw_points * self.pitch_points

    @property
    def rows_per_boundary(self) -> int:
        return 2 + self.facets  # longitude, terminal longitude, facets / 2 two-sided rows each for e and i


def generators(limits, shape: Shape):
    """[2, G, 3] unit Delta-V directions (RSW): the yaw x pitch grid of each thruster's rectangle (eq. (1))."""
    (a_lo, a_hi), (b_lo, b_hi) = alpha_beta_bounds(limits)
    grid = lambda lo, hi, k: lo[:, None] + (hi - lo)[:, None] * jnp.linspace(0.0, 1.0, k)  # noqa: E731
    alpha = grid(a_lo, a_hi, shape.yaw_points)[:, :, None]
    beta = grid(b_lo, b_hi, shape.pitch_points)[:, None, :]
    alpha, beta = jnp.broadcast_arrays(alpha, beta)
    return delta_v_direction_rsw(alpha.reshape(2, -1), beta.reshape(2, -1))


def natural_deviations(x0, target, ref_mean, cycle_s):
    """[n + 1, 6] the mean elements' deviation from ``target`` at boundaries 0..n without burns (longitude
    wrapped), from the estimate ``x0`` [6] and the reference's means ``ref_mean`` [n + 1, 7]."""

    def one(x, refs):
        x_next = predict_next(x, refs[0], refs[1], cycle_s)
        return x_next, x_next

    _, path = jax.lax.scan(one, x0, (ref_mean[:-1], ref_mean[1:]))
    path = jnp.concatenate([x0[None], path]) - target
    return path.at[:, 0].set(wrap_angle(path[:, 0]))


class Model(NamedTuple):
    """One plan's linear program (leaves of one sample; ``Shape`` gives the sizes)."""

    effect: jnp.ndarray  # [6, 2G] change of the mean elements per m/s along each direction of burn 1, then 2
    directions: jnp.ndarray  # [2, G, 3] the directions (RSW)
    l_rad: jnp.ndarray  # [2] right ascensions of the burns
    rows: jnp.ndarray  # [n_max, R, 6] state rows of boundaries 1..n_max, scaled to half-width 1
    lower: jnp.ndarray  # [n_max, R] bounds of rows @ (state change by the burns)
    upper: jnp.ndarray  # [n_max, R]
    cap_scale: jnp.ndarray  # [] m/s, the capacity of each burn (its row is sum w / cap_scale <= 1)
    mask: jnp.ndarray  # [n_max] 1 for the cycles of the horizon, 0 beyond
    cycle_s: jnp.ndarray  # []


def build(x0, target, ref_mean, l_start_rad, limits, accel_mps2, cycle_s, leaves: dict, station: dict,
          shape: Shape) -> Model:
    """The program of the cycle starting at the estimate ``x0`` [6] (``ref_mean`` [n_max + 1, 7], the
    reference's means from this boundary on; ``accel_mps2`` thrust over mass; ``leaves`` the controller's
    SI leaves; ``station`` the station's)."""
    n_max, k = shape.n_max, shape.facets // 2
    horizon = jnp.clip(leaves["horizon"], 1, n_max)
    free = natural_deviations(x0, target, ref_mean, cycle_s)
    # Eq. (31) on the deviation left at the end of the horizon: thruster 2 at l_2, thruster 1 opposite.
    di_end = -free[horizon, 4:]
    l2 = jnp.arctan2(di_end[1], di_end[0])
    l_rad = jnp.stack([l2 - jnp.pi, l2])
    directions = generators(limits, shape)
    b = effect_matrix(l_rad, cycle_coast_s(l_rad, l_start_rad))  # [2, 6, 3]
    effect = jnp.einsum("bsv,bgv->sbg", b, directions).reshape(6, -1)

    # Rows per boundary: longitude; terminal longitude (lon + m T drift, at j = N only); e and i facets.
    angles = 2 * jnp.pi * jnp.arange(k) / shape.facets
    facet = jnp.stack([jnp.cos(angles), jnp.sin(angles)], -1)  # [k, 2] normals of one side of each pair
    e_half = leaves["e_max"] * math.cos(math.pi / shape.facets)  # inscribed polygon
    i_half = leaves["di_max"] * math.cos(math.pi / shape.facets)
    e_target = jnp.hypot(target[2], target[3])
    lon_half = station["box_half_width_rad"] - 2 * (e_target + leaves["e_max"]) - leaves["lon_margin_rad"]
    zero = jnp.zeros((k, 2))
    rows = jnp.concatenate([
        jnp.array([[1.0, 0, 0, 0, 0, 0]]) / lon_half,
        jnp.stack([1.0, leaves["terminal_cycles"] * cycle_s, 0, 0, 0, 0])[None] / lon_half,
        jnp.concatenate([jnp.zeros((k, 2)), facet, zero], 1) / e_half,
        jnp.concatenate([jnp.zeros((k, 2)), zero, facet], 1) / i_half,
    ])  # [R, 6]
    rows = jnp.broadcast_to(rows, (n_max, *rows.shape))
    boundary = jnp.arange(1, n_max + 1)[:, None]
    row_index = jnp.arange(rows.shape[1])[None, :]
    active = (boundary <= horizon) & ((row_index != 1) | (boundary == horizon))
    value = jnp.einsum("jrs,js->jr", rows, free[1:])
    lower = jnp.where(active, -1.0 - value, -jnp.inf)
    upper = jnp.where(active, 1.0 - value, jnp.inf)
    cap_scale = accel_mps2 * leaves["max_burn_s"]
    mask = (jnp.arange(n_max) < horizon).astype(float)
    return Model(effect, directions, l_rad, rows, lower, upper, cap_scale, mask, jnp.asarray(cycle_s))


def operator(model: Model, shape: Shape) -> lp.Operator:
    """The program's rows as an ``lp.Operator`` on w [n_max * 2G] (m/s, ordered cycle, burn, direction).

    Rows: w >= 0 (n); each burn's sum w / cap_scale (2 n_max); the state rows (n_max R).  A w is never
    multiplied by a formed matrix: w -> per-cycle effects (E w_i) -> boundaries (the dynamics) -> rows.
    The normal matrix diag(sigma) + A' diag(rho) A = Theta + G'QG, with Theta block-diagonal per cycle
    (the bounds' and the capacities' rows) and Q per boundary (rows' diag(rho) rows, 6 x 6), is the Hessian
    of a linear-quadratic problem over the horizon (x_{j+1} = Phi x_j + E w_j, x_0 = 0): ``riccati`` solves it
    with one 2G x 2G Cholesky per cycle, stably whatever the spread of the interior-point weights (a
    Woodbury solve through an 8N x 8N matrix was measured to lose all accuracy once they span 1e8).  A
    cluster's program (``mpc_cluster``) is the same on its satellites' states and burns side by side.
    """
    n_max, g = shape.n_max, shape.generators
    size, width = model.effect.shape[-2:]  # the state and one cycle's decisions: 6 and 2G, or a cluster's stacked
    burns, r = width // g, model.rows.shape[-2]
    n = n_max * width
    phi = transition(model.cycle_s)
    if size > 6:  # a cluster's satellites side by side (``mpc_cluster``)
        phi = jnp.kron(jnp.eye(size // 6), phi)
    effect = model.mask[:, None, None] * model.effect  # [n_max, 6, 2G]: no burns beyond the horizon
    # each burn's capacity: one for every burn (a satellite's), or [burns] of each cycle (a cluster's)
    cap = model.cap_scale if model.cap_scale.ndim == 0 else jnp.tile(model.cap_scale, n_max)
    cap_column = cap if cap.ndim == 0 else jnp.repeat(cap.reshape(n_max, burns), g, -1)[:, :, None]
    cap_row = cap if cap.ndim == 0 else cap[:, None]

    def state_change(w):  # [n] -> [n_max, 6] at boundaries 1..n_max
        def one(x, e_w):
            x = phi @ x + e_w
            return x, x

        return jax.lax.scan(one, jnp.zeros(size), jnp.einsum("jsv,jv->js", effect, w.reshape(n_max, width)))[1]

    # |state rows of A| [n_max R, n], for the equilibration's norms: the rows of every unit Delta-V.
    condensed = jax.vmap(state_change, out_axes=-1)(jnp.eye(n))  # [n_max, 6, n]
    abs_rows = jnp.abs(jnp.einsum("jrs,jsn->jrn", model.rows, condensed)).reshape(-1, n)

    def state_change_t(v):  # [n_max, 6] -> [n]: the adjoint, a backward pass
        def one(lam, v_j):
            lam = phi.T @ lam + v_j
            return lam, lam

        lam = jax.lax.scan(one, jnp.zeros(size), v, reverse=True)[1]
        return jnp.einsum("jsv,js->jv", effect, lam).reshape(-1)

    def caps(w):  # [n] -> [2 n_max]
        return jnp.sum(w.reshape(burns * n_max, g), -1) / cap

    def caps_t(v):  # [2 n_max] -> [n]
        return jnp.repeat(v / cap, g)

    def split(v):
        return v[:n], v[n:n + burns * n_max], v[n + burns * n_max:].reshape(n_max, r)

    def matvec(w):
        rows = jnp.einsum("jrs,js->jr", model.rows, state_change(w))
        return jnp.concatenate([w, caps(w), rows.reshape(-1)])

    def rmatvec(y):
        y_bound, y_cap, y_rows = split(y)
        return y_bound + caps_t(y_cap) + state_change_t(jnp.einsum("jrs,jr->js", model.rows, y_rows))

    def factor(rho, sigma):
        rho_bound, rho_cap, rho_rows = split(rho)
        q = jnp.einsum("jrs,jr,jrt->jst", model.rows, rho_rows, model.rows)
        ones = jnp.kron(jnp.eye(burns), jnp.ones((g, g)))  # [2G, 2G] the capacity rows' Gram, per unit weight
        theta = jax.vmap(jnp.diag)((sigma + rho_bound).reshape(n_max, width)) \
            + ones * jnp.repeat(rho_cap.reshape(n_max, burns), g, -1)[:, :, None] / cap_column**2
        return riccati(phi, effect, theta, q, n_max)

    def norms(d, e):
        d_bound, d_cap, d_rows = split(d)
        caps_abs = (d_cap[:, None] * e.reshape(burns * n_max, g)) / cap_row
        rows_abs = d_rows.reshape(-1, 1) * abs_rows * e
        row_norms = jnp.concatenate([d_bound * e, jnp.max(caps_abs, 1), jnp.max(rows_abs, 1)])
        col_norms = jnp.maximum(jnp.maximum(d_bound * e, caps_abs.reshape(-1)), jnp.max(rows_abs, 0))
        return row_norms, col_norms

    return lp.Operator(matvec, rmatvec, factor, norms)


def transition(cycle_s):
    """Phi [6, 6]: the mean elements over one cycle without burns (the longitude advances by drift x T)."""
    return jnp.eye(6).at[0, 1].set(cycle_s)


def riccati(phi, effect, theta, q, n_max: int, stage=None):
    """The solve of (Theta + G'QG) w = b: the minimiser of 1/2 w'Theta w + 1/2 sum_j x_j'Q_j x_j - b'w over
    x_{j+1} = Phi x_j + E_j w_j, x_0 = 0 (``effect`` [n_max, 6, 2G] E_j, ``theta`` [n_max, 2G, 2G], ``q``
    [n_max, 6, 6] at boundaries 1..n_max; any state size and width: ``mpc_momentum`` adds the wheels' momentum to the
    state and the tilts to the decisions).  Backward: with the cost-to-go 1/2 x'Px + p'x after cycle j,
    H_j = Theta_j + E'PE, and P <- Q + Phi'P Phi - M'H^-1 M, M = E'P Phi (Rao, Wright & Rawlings 1998).
    ``stage`` (optional): (Q0 [n_max, s, s], S [n_max, width, s]) a further cost 1/2 x_j'Q0_j x_j + u_j'S_j x_j of
    each cycle's start and decisions together (rows on both: ``mpc_momentum``'s between the burns); then
    M = E'P Phi + S."""

    def backward(p_next, xs):
        e, th, q_here = xs[:3]
        h = th + e.T @ p_next @ e
        chol = lp.cholesky(h)
        m = e.T @ p_next @ phi  # [2G, 6]
        if stage is not None:
            q_here, m = q_here + xs[3], m + xs[4]
        gain = lp.cho_solve(chol, m)
        p_here = q_here + phi.T @ p_next @ phi - m.T @ gain
        return p_here, (chol, gain)

    size, width = phi.shape[0], effect.shape[-1]  # the state (6 here) and one cycle's decisions (2G here)
    q_before = jnp.concatenate([jnp.zeros((1, size, size)), q[:-1]])  # the state cost at each cycle's start
    xs = (effect, theta, q_before) if stage is None else (effect, theta, q_before, *stage)
    _, (chol, gain) = jax.lax.scan(backward, q[-1], xs, reverse=True)

    def solve(b):
        def costate(p_next, xs):  # p of the cost-to-go, backward: p_j = Phi'p_{j+1} - gain_j' g_j
            e, ch, k, b_j = xs
            g_j = e.T @ p_next - b_j
            return phi.T @ p_next - k.T @ g_j, lp.cho_solve(ch, g_j)

        xs = (effect, chol, gain, b.reshape(n_max, width))
        _, h_inv_g = jax.lax.scan(costate, jnp.zeros(size), xs, reverse=True)

        def forward(x, xs):
            e, k, hg = xs
            u = -k @ x - hg
            return phi @ x + e @ u, u

        return jax.lax.scan(forward, jnp.zeros(size), (effect, gain, h_inv_g))[1].reshape(-1)

    return solve


def program(model: Model, leaves: dict, shape: Shape):
    """(c [n], lower [m], upper [m], penalty [m]) of the program on ``operator(model, shape)``'s rows."""
    n, caps = shape.n_max * 2 * shape.generators, 2 * shape.n_max
    lower = jnp.concatenate([jnp.zeros(n), jnp.full(caps, -jnp.inf), model.lower.reshape(-1)])
    upper = jnp.concatenate([jnp.full(n, jnp.inf), jnp.ones(caps), model.upper.reshape(-1)])
    penalty = jnp.concatenate([jnp.full(n + caps, jnp.inf),
                               jnp.full(model.lower.size, 1.0) * leaves["penalty_mps"]])
    # Later Delta-V is discounted by a hair (``defer`` per cycle): the timing of a correction is otherwise
    # degenerate, and the interior point would return the centre of the optimal face (every cycle a share).
    discount = 1.0 - leaves["defer"] * jnp.arange(shape.n_max)
    return jnp.repeat(discount, 2 * shape.generators), lower, upper, penalty


class Plan(NamedTuple):
    """A cycle's plan: the burns flown and what the program said."""

    flown: burns_mod.BurnPlan
    solved: jnp.ndarray  # [] bool: no row of the plan violated by more than SOLVED_VIOLATION of its half-width
    fuel_mps: jnp.ndarray  # [] the program's objective (Delta-V over the horizon, discounted, plus penalties)
    violation: jnp.ndarray  # [] the largest row violation, in half-widths
    iterations: jnp.ndarray  # [] interior-point iterations run
    certified: jnp.ndarray  # [] bool: the solver certified the optimum (``lp.certify``)


def first_burns(model: Model, w, limits) -> BurnPair:
    """The burns of the first cycle from the weights ``w`` [2, G]: each resultant sum_g w_g d_g flown as one
    burn; a direction outside the arm's rectangle is moved to its nearest (yaw, pitch) in it (Li 2022 eq.
    (14) inverted, then clipped), with the planned magnitude."""
    dv = jnp.einsum("bg,bgv->bv", w, model.directions)
    v = jnp.linalg.norm(dv, axis=-1)
    (a_lo, a_hi), (b_lo, b_hi) = alpha_beta_bounds(limits)
    alpha = jnp.clip(jnp.arctan2(-dv[:, 1], -dv[:, 0]), a_lo, a_hi)
    beta = jnp.clip(jnp.arcsin(jnp.clip(-dv[:, 2] / jnp.where(v > 0, v, 1.0), -1.0, 1.0)), b_lo, b_hi)
    dv = v[:, None] * delta_v_direction_rsw(alpha, beta)
    return BurnPair(dv, v, alpha, beta, model.l_rad, jnp.asarray(0.0), jnp.all(jnp.isfinite(dv)))


def plan(x0, target, ref_mean, l_start_rad, limits, accel_mps2, cycle_s, leaves: dict, station: dict,
         shape: Shape):
    """Solve the cycle's program; returns (the first cycle's ``BurnPair``, the ``lp.Solution``, the ``Model``)."""
    model = build(x0, target, ref_mean, l_start_rad, limits, accel_mps2, cycle_s, leaves, station, shape)
    c, lower, upper, penalty = program(model, leaves, shape)
    solution = lp.solve(c, operator(model, shape), lower, upper, penalty, tolerance=leaves["tolerance"],
                        settings=lp.Settings(iterations=shape.iterations))
    w = solution.x.reshape(shape.n_max, 2, shape.generators)[0]
    w = jnp.where(jnp.all(jnp.isfinite(w)), jnp.maximum(w, 0.0), 0.0)  # never fly a failed solve
    return first_burns(model, w, limits), solution, model


def row_violation(model: Model, rows):
    """The largest violation of the state rows ``rows`` [n_max R] (their values) of ``model``, in half-widths."""
    return jnp.max(jnp.maximum(model.lower.reshape(-1) - rows, 0.0) + jnp.maximum(rows - model.upper.reshape(-1), 0.0))


def flown_plan(params, target, burns: BurnPair, solution: lp.Solution, violation, estimate, context, key) -> Plan:
    """The cycle's ``Plan``: the first cycle's ``burns`` flown by ``control.burns`` (as the QFFC's) from the
    prediction of the next boundary, with what the program (``solution``, its rows' largest ``violation``) said."""
    prediction = predict_next(estimate.mean, context.reference[0], context.reference[1], context.cycle_s)
    prediction = prediction.at[0].set(wrap_angle(prediction[0]))
    full = 2 * V_SYNC_MPS * jnp.hypot(target[4] - prediction[4], target[5] - prediction[5])
    ns_fraction = jnp.sum(jnp.abs(burns.dv_rsw_mps[:, 2])) / jnp.maximum(full, 1e-12)
    flown = burns_mod.fly(params, burns, prediction, ns_fraction, estimate, context, key)
    solved = (violation <= SOLVED_VIOLATION) & jnp.all(jnp.isfinite(solution.x))
    return Plan(flown, solved, solution.objective, violation, solution.iterations, solution.converged)


def make(tables: list[dict]) -> Controller:
    """The MPC for a batch of ``[controller]`` tables: its horizon padded to their largest N (a sweep over N
    compiles once), the static sizes shared."""
    return controller(shape_of(tables))


def shape_of(tables: list[dict]) -> Shape:
    """The compiled plan's ``Shape`` for a batch of ``[controller]`` tables: the largest horizon, the static sizes
    (one value per batch, else ``ValueError`` naming the key)."""
    for key in ("iterations", "yaw_points", "pitch_points", "facets"):
        if len({t[key] for t in tables}) > 1:
            raise ValueError(f"controller.{key}: sets the shape of the compiled plan; one value per sweep, "
                             f"got {sorted({t[key] for t in tables})}")
    first = tables[0]
    return Shape(max(t["horizon"] for t in tables), first["yaw_points"], first["pitch_points"], first["facets"],
                 first["iterations"])


def validate(config: dict) -> None:
    """Bad input the field bounds cannot see: an odd number of facets, and limits that leave no longitude box."""
    c, station = config["controller"], config["station"]
    if c["facets"] % 2:
        raise ValueError(f"controller.facets: must be even (the polygons' sides come in opposite pairs), "
                         f"got {c['facets']}")
    libration_deg = math.degrees(2 * (math.hypot(station["ex"], station["ey"]) + c["e_max"]))
    room_deg = station["box_half_width_deg"] - libration_deg - c["lon_margin_deg"]
    if room_deg <= 0:
        raise ValueError(f"controller.e_max: the daily libration 2 (|e_T| + e_max) = {libration_deg:.4g} deg plus "
                         f"controller.lon_margin_deg = {c['lon_margin_deg']:g} leave no room in the "
                         f"+-{station['box_half_width_deg']:g} deg longitude box")


SPEC = Spec(FIELDS, validate, THRUSTERS, REDUNDANT_THRUSTERS)


@functools.lru_cache(maxsize=None)
def controller(shape: Shape = Shape()) -> Controller:
    """The MPC with static sizes ``shape`` (stateless: the interior-point method starts afresh every cycle)."""

    solve = lane_by_lane(lambda *args: plan(*args, shape))  # its numbers one lane's at every width

    def init(params, context):
        return jnp.zeros(())

    def plan_cycle(params, controller_state, estimate, context, key):
        limits = arm_limits(params.thrusters)
        target = station_target(params.station)
        accel = params.thrusters["thrust_n"] / estimate.mass_kg
        burns, solution, model = solve(estimate.mean, target, context.reference, estimate.fix_mee[5], limits, accel,
                                       context.cycle_s, params.controller, params.station)
        violation = row_violation(model, solution.ax[-model.lower.size:])
        return flown_plan(params, target, burns, solution, violation, estimate, context, key), controller_state

    def thrust(params, plan_: Plan, t, state, environment):
        return burns_mod.thrust(params, plan_.flown, t, state, environment)

    def record(plan_: Plan) -> dict:
        return {**burns_mod.record(plan_.flown), "solved": plan_.solved, "planned_fuel_mps": plan_.fuel_mps,
                "violation": plan_.violation, "iterations": plan_.iterations, "certified": plan_.certified}

    # Plans N_max cycles ahead: the reference at the cycle's start boundary and the n_max after it.
    # Widths and memory (``geojax.lanes``): the interior point's matrices dominate (10 days, 2 loaded cores: 7.5-8.9e-3 s
    # per orbit per sample at 8 lanes, 1.0e-2 at 32 and 64), so 8 lanes per CPU core; XLA's memory_analysis at 8
    # lanes, 4 and 12 cycles (li2022-mpc's horizon): 1.73 MB per lane and 0.33 kB more per cycle.
    return Controller(init, plan_cycle, thrust, SPEC, reference_cycles=shape.n_max + 1, record=record, metrics=burn_metrics.metrics,
                      sizing=Sizing(lanes_cpu=8, working_bytes=1_750_000, one_sample_opt_level=1))
