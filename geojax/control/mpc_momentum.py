"""The MPC over orbit and wheel momentum: one linear program per cycle, the thrust lines' tilts as decisions.

Caverly, Di Cairano & Weiss (IEEE TCST 2021, doi:10.1109/TCST.2020.3014601) hold a GEO satellite's station and
keep its reaction wheels' momentum bounded with the same electric thrusters, one MPC over both.  This is that
program on ``control.mpc``'s minimum-fuel LP (Gazzino 2016's Problem 3 on Li 2022's predictor; read ``mpc`` first):

* Decisions per cycle j of the horizon: the orbit MPC's burn weights w_j (2G, m/s along the arms' grid of
  directions) and, per burn b, a tilt z_jb [2] (m/s): the Delta-V that tilting the burn's line of action about
  its nozzle (``states.momentum``) puts across the line, in a basis (e_1, e_2) perpendicular to the burn's nominal
  line u_b (the middle of its arm's rectangle).  A tilt by sin(delta) = |z| / v of a burn of Delta-V v:
  |z_jb|_1 <= sin(delta_max) sum_g w_jbg (u_b . a_g) (the L1 ball inside the cone on the Delta-V along the line,
  at most v: linear, within the loop's clip), t_jb >= |z_jb| per component (the L1 norm's epigraph).
* The torque, linearised: a burn flown with the tilt z puts the impulse -L m (u_b x z) into the body (L the nozzle's
  distance from the centre of mass, ``attitude.thrust_arm_m``; m the mass: F T = m v), the external torque the
  wheels then hold; its product with v (the tilt angle times the Delta-V) is exactly z, so the impulse is linear
  in the decisions.  The impulse turns with the orbit during the burn; it is taken at the burn's centre, whose
  right ascension is the plan's (an error of 1 - sinc(T n / 2), 1.1 % for a 2 h burn).
* The momentum state: the wheels' momentum in inertial axes, g = C' h_w (C the ECI -> body rotation), given in
  the RSW axes of the cycle's start (fixed over the horizon: the body turns once per cycle, which is one orbit).
  Without external torque g changes only by the burns' impulses (the total momentum I omega + h_w is conserved in
  ECI and I omega is constant there: ``states.momentum``), so g_{j+1} = g_j + d + K z_j, with d the other
  torques' impulse per cycle (SRP at an offset, gravity gradient, the centre of mass's shift) and K [3, 4] the
  tilts' impulses in the cycle-start RSW axes (each burn's rotated by its right ascension past the start).
* Rows on g at every boundary 1..N: the body turns about the orbit normal once per cycle, so its x (S) and z
  (-R) wheels see the in-plane part of g at every angle within the cycle: |g_RS| <= h_max as an inscribed polygon
  of ``facets`` sides, and |g_W| <= h_max (the y wheel, -W); h_max = ``momentum_band_nms``, at most
  ``momentum_fraction`` of the capacity (the rest the margin for what is taken up between the boundaries; not a
  share: a larger wheel flies the same plan).  The same rows just before each cycle's second burn (g_j + f d + the first
  burn's impulse: rows on a cycle's start state and its decisions together, ``mpc.riccati``'s stage terms).
  Soft, with the orbit rows' penalty.
* A price on g along the burns' common line l (their unit difference, start axes), ``momentum_line_price`` m/s
  per N m s at every boundary (a soft row, lower = upper = 0): no tilt reaches g . l but through the small angle
  between the lines, so the program empties it while the angle lets it, as the law does (docs/momentum.md).
* The orbit sees the tilts' Delta-V as any other (``effects.effect_matrix``); they cost ``tilt_cost`` per m/s of
  |z|_1 (else the interior point returns the centre of a face of tilts that cost nothing).
* d is estimated from the wheels as the controller measures them (``Estimate.states["wheels"]``): the change of
  g over the cycle just flown less the impulse the plan commanded in it, smoothed by ``disturbance_gain`` per
  cycle (an exponential filter: the SRP torque turns with the Sun, 1 deg a day); 0 before the second cycle.
* The lines: the torque is bilinear in a burn's line and its tilt, and the program takes the lines as given; it
  solves up to ``line_solves`` times (2), first on last cycle's planned lines, then on the lines the solve before
  planned, stopping early once a solve plans the lines it was solved on to within ``line_tolerance_deg`` (0: never),
  and flies the solve whose planned lines are closest to the lines it assumed (the most self-consistent torque).
  The iteration need not settle, so the last solve flown as it came decided at the edge whether the wheels
  saturated (docs/momentum.md, ``studies/momentum/mpc_line_solves.py``).

The first cycle's burns are flown as the MPC's, each with its planned tilt (``Thrust.tilt_rsw``) across the line
flown.  The solver: ``control.lp``'s interior point, its normal matrix factored by ``mpc.riccati``.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control import burn_metrics
from geojax.control import burns as burns_mod
from geojax.control import lp, mpc
from geojax.control.base import Controller, Sizing, Spec
from geojax.control.effects import V_SYNC_MPS, cycle_coast_s, effect_matrix
from geojax.control.momentum_frames import across_basis, body_to_rsw, rotate_to_start, rsw_basis
from geojax.control.predictor import predict_next
from geojax.states.base import DUMPING, WHEEL_MOMENTUM
from geojax.params import NUMBER, Field, station_target
from geojax.physics.elements import mee_to_cartesian, wrap_angle
from geojax.physics.propulsion import arm_limits

THRUSTERS = mpc.THRUSTERS
REDUNDANT_THRUSTERS = mpc.REDUNDANT_THRUSTERS
UNREAD = ("attitude.dump_gain_per_s", "attitude.dump_transient_fraction")
TILTS = 4  # per cycle: two burns x two components across the line

FIELDS = {
    **mpc.FIELDS,
    # The momentum the plan may hold per wheel at the boundaries and between the burns: ``momentum_band_nms``, at
    # most ``momentum_fraction`` of the capacity (module docstring: not a share of it; docs/momentum.md).
    "momentum_band_nms": Field(NUMBER, 35.0, lower=0.0, upper=1e6, si="momentum_band_nms"),
    "momentum_fraction": Field(NUMBER, 0.7, lower=0.0, upper=1.0, si="momentum_fraction"),
    # The price of the momentum along the burns' common line, m/s per N m s at each boundary (module docstring).
    "momentum_line_price": Field(NUMBER, 1e-3, lower=0.0, lower_inclusive=True, upper=1.0, si="momentum_line_price"),
    # The price of a tilt per m/s of |z|_1, against 1 per m/s of burn: at 1 the program tilts for the wheels alone
    # (a burn in the tilt's direction costs no more).
    "tilt_cost": Field(NUMBER, 1.0, lower=0.0, lower_inclusive=True, upper=100.0, si="tilt_cost"),
    # Up to ``line_solves`` solves a cycle, each on the lines the one before planned, fewer once a solve's lines
    # move less than ``line_tolerance_deg`` (0: never); the solve whose lines moved least is flown (module docstring).
    "line_solves": Field(int, 2, lower=1, upper=13, lower_inclusive=True, si="line_solves"),
    "line_tolerance_deg": Field(NUMBER, 0.0, lower=0.0, lower_inclusive=True, upper=10.0, si="line_tolerance_rad",
                                to_si=math.pi / 180.0),
    # The gain per cycle of the external momentum's filter (1: the last cycle's; 0: none; stable below 2).
    "disturbance_gain": Field(NUMBER, 0.5, lower=0.0, lower_inclusive=True, upper=2.0, si="disturbance_gain"),
}


class Momentum(NamedTuple):
    """What the momentum part of one plan adds to ``mpc.Model`` (leaves of one sample)."""

    lines: jnp.ndarray  # [2, 3] the burns' nominal lines u_b (RSW at each burn)
    across: jnp.ndarray  # [2, 2, 3] the basis (e_1, e_2) across each line (RSW at each burn)
    effect: jnp.ndarray  # [9, 2G + 8] one cycle's decisions (w, z, t) -> (elements, g) at the cycle's end
    cycle_rows: jnp.ndarray  # [C, 2G + 8] the rows on one cycle's decisions
    cycle_lower: jnp.ndarray  # [C]
    cycle_upper: jnp.ndarray  # [C]
    rows: jnp.ndarray  # [n_max, R + F / 2 + 1, 9] state rows of boundaries 1..n_max, half-width 1
    lower: jnp.ndarray  # [n_max, R + F / 2 + 1]
    upper: jnp.ndarray  # [n_max, R + F / 2 + 1]
    impulse: jnp.ndarray  # [3, 4] K: g's change (cycle-start RSW, N m s) per m/s of each tilt component
    mid_x: jnp.ndarray  # [F / 2 + 1, 9] the rows between the burns on the cycle's start state (its g)
    mid_u: jnp.ndarray  # [F / 2 + 1, 2G + 8] and on the cycle's decisions (the first burn's tilts)
    mid_lower: jnp.ndarray  # [n_max, F / 2 + 1]
    mid_upper: jnp.ndarray  # [n_max, F / 2 + 1]
    row_penalty: jnp.ndarray  # [R + F / 2 + 2] each boundary row's penalty (m/s per half-width)


def build(model: mpc.Model, lines, g0, d, l_start_rad, mass_kg, dumping: dict, leaves: dict,
          shape: mpc.Shape) -> Momentum:
    """The momentum part of the program of the cycle whose orbit part is ``model``: ``lines`` [2, 3] the burns'
    nominal lines (unit, RSW at each burn), ``g0`` [3] the wheels' momentum (cycle-start RSW, N m s), ``d`` [3] the
    other torques' impulse per cycle there."""
    g, k = shape.generators, shape.facets // 2
    across = across_basis(lines)  # [2, 2, 3]
    # orbit effect of the tilt components: B(l_b) e_bk
    b = effect_matrix(model.l_rad, cycle_coast_s(model.l_rad, l_start_rad))  # [2, 6, 3]
    effect_z = jnp.einsum("bsv,bkv->sbk", b, across).reshape(6, TILTS)
    # momentum impulse per m/s of tilt: -L m (u x e), turned to the cycle start's axes
    past = jnp.mod(model.l_rad - l_start_rad, 2 * jnp.pi)
    impulse = -dumping["thrust_arm_m"] * mass_kg * jnp.cross(lines[:, None, :], across)  # [2, 2, 3]
    impulse = rotate_to_start(impulse, past[:, None]).reshape(TILTS, 3).T  # [3, 4]
    width = 2 * g + 2 * TILTS
    effect = jnp.zeros((9, width))
    effect = effect.at[:6, :2 * g].set(model.effect).at[:6, 2 * g:2 * g + TILTS].set(effect_z)
    effect = effect.at[6:, 2 * g:2 * g + TILTS].set(impulse)

    # Rows on one cycle's decisions (w, z, t): w >= 0; each burn's capacity; t >= |z|; |z_b|_1 <= sin(delta) v_b.
    eye_w = jnp.eye(2 * g, width)
    burn_sum = jnp.kron(jnp.eye(2), jnp.ones((1, g)))  # [2, 2G]
    caps = jnp.concatenate([burn_sum / model.cap_scale, jnp.zeros((2, 2 * TILTS))], 1)
    z_part, t_part = jnp.eye(TILTS), jnp.eye(TILTS)
    minus = jnp.concatenate([jnp.zeros((TILTS, 2 * g)), -z_part, t_part], 1)  # t - z >= 0
    plus = jnp.concatenate([jnp.zeros((TILTS, 2 * g)), z_part, t_part], 1)  # t + z >= 0
    sin_max = jnp.sin(dumping["dump_angle_max_rad"])
    along = jnp.maximum(jnp.einsum("bv,bgv->bg", lines, model.directions), 0.0).reshape(1, 2 * g)  # u_b . a_g
    cone = jnp.concatenate([-sin_max * burn_sum * along, jnp.zeros((2, TILTS)),
                            jnp.kron(jnp.eye(2), jnp.ones((1, 2)))], 1)
    cycle_rows = jnp.concatenate([eye_w, caps, minus, plus, cone])
    inf = jnp.inf
    cycle_lower = jnp.concatenate([jnp.zeros(2 * g), jnp.full(2, -inf), jnp.zeros(2 * TILTS), jnp.full(2, -inf)])
    cycle_upper = jnp.concatenate([jnp.full(2 * g, inf), jnp.ones(2), jnp.full(2 * TILTS, inf), jnp.zeros(2)])

    # State rows: the orbit's (on the elements) and the momentum's (on g) at boundaries 1..n_max.
    h_half = jnp.minimum(leaves["momentum_band_nms"], leaves["momentum_fraction"] * dumping["wheel_capacity_nms"])
    angles = 2 * jnp.pi * jnp.arange(k) / shape.facets
    facet = jnp.stack([jnp.cos(angles), jnp.sin(angles), jnp.zeros(k)], -1) / (h_half * math.cos(math.pi / shape.facets))
    common = -jnp.diff(rotate_to_start(lines, past), axis=0)[0]  # the priced row: g along the common line
    common = common / jnp.linalg.norm(common)
    g_rows = jnp.concatenate([facet, jnp.array([[0.0, 0.0, 1.0]]), common[None]]) / jnp.concatenate(
        [jnp.full(k, 1.0), jnp.full(2, h_half)])[:, None]  # [k + 2, 3]
    k = k + 1  # the rows on g: k + 1
    n_max = shape.n_max
    rows = jnp.concatenate([
        jnp.concatenate([model.rows, jnp.zeros((n_max, model.rows.shape[1], 3))], -1),
        jnp.concatenate([jnp.zeros((n_max, k + 1, 6)), jnp.broadcast_to(g_rows, (n_max, k + 1, 3))], -1)], 1)
    horizon = jnp.sum(model.mask)
    boundary = jnp.arange(1, n_max + 1)
    free = g0 + boundary[:, None] * d  # [n_max, 3] g without tilts
    value = free @ g_rows.T  # [n_max, k + 1]
    active = (boundary <= horizon)[:, None]
    lower = jnp.concatenate([model.lower, jnp.where(active, -1.0 - value, -inf)], 1)
    upper = jnp.concatenate([model.upper, jnp.where(active, 1.0 - value, inf)], 1)
    # Between the burns, just before the second: g_j + f d + (the first burn's impulse), f the second's place in
    # the cycle (g's extremes within a cycle are at its boundaries and here: linear in between).
    first = jnp.argmin(past)
    f_second = jnp.max(past) / (2 * jnp.pi)
    first_columns = (jnp.arange(TILTS) // 2 == first).astype(impulse.dtype)
    mid_u = jnp.zeros((k + 1, width)).at[:, 2 * g:2 * g + TILTS].set(g_rows @ (impulse * first_columns))
    mid_x = jnp.concatenate([jnp.zeros((k + 1, 6)), g_rows], 1)
    start = jnp.arange(n_max)
    mid_value = (g0 + (start[:, None] + f_second) * d) @ g_rows.T  # [n_max, k + 1]
    mid_active = (start < horizon)[:, None]
    mid_lower = jnp.where(mid_active, -1.0 - mid_value, -inf).at[:, -1].set(-inf)
    mid_upper = jnp.where(mid_active, 1.0 - mid_value, inf).at[:, -1].set(inf)
    priced = active[:, 0] & (leaves["momentum_line_price"] > 0)  # a price of 0: no row (the program without it)
    lower = lower.at[:, -1].set(jnp.where(priced, -value[:, -1], -inf))
    upper = upper.at[:, -1].set(jnp.where(priced, -value[:, -1], inf))
    row_penalty = jnp.full(lower.shape[1], leaves["penalty_mps"]).at[-1].set(leaves["momentum_line_price"] * h_half)
    return Momentum(lines, across, effect, cycle_rows, cycle_lower, cycle_upper, rows, lower, upper, impulse,
                    mid_x, mid_u, mid_lower, mid_upper, row_penalty)


def operator(model: mpc.Model, momentum: Momentum, shape: mpc.Shape) -> lp.Operator:
    """The program's rows as an ``lp.Operator`` on u [n_max * (2G + 8)] (ordered cycle, then w, z, t): each
    cycle's rows on its own decisions (``Momentum.cycle_rows``, dense and small), the rows between each cycle's
    burns (on its start state and its decisions), then the state rows at the boundaries.  The normal matrix is
    Theta + G'QG plus the between-burn rows' terms, Theta block-diagonal per cycle (dense blocks): the solve is
    ``mpc.riccati``'s over the state (elements, g) [9], with the between-burn rows as its stage terms."""
    n_max = shape.n_max
    width = momentum.effect.shape[1]
    n = n_max * width
    cycle_rows, rows, mid_x, mid_u = momentum.cycle_rows, momentum.rows, momentum.mid_x, momentum.mid_u
    rc, rm, r = cycle_rows.shape[0], mid_x.shape[0], rows.shape[1]
    phi = jax.scipy.linalg.block_diag(mpc.transition(model.cycle_s), jnp.eye(3))
    effect = model.mask[:, None, None] * momentum.effect  # [n_max, 9, width]: no burns beyond the horizon

    def state_change(u):  # [n] -> [n_max, 9] at boundaries 1..n_max
        def one(x, e_u):
            x = phi @ x + e_u
            return x, x

        return jax.lax.scan(one, jnp.zeros(9), jnp.einsum("jsv,jv->js", effect, u.reshape(n_max, width)))[1]

    def state_change_t(v):  # [n_max, 9] -> [n]
        def one(lam, v_j):
            lam = phi.T @ lam + v_j
            return lam, lam

        lam = jax.lax.scan(one, jnp.zeros(9), v, reverse=True)[1]
        return jnp.einsum("jsv,js->jv", effect, lam).reshape(-1)

    condensed = jax.vmap(state_change, out_axes=-1)(jnp.eye(n))  # [n_max, 9, n]
    abs_rows = jnp.abs(jnp.einsum("jrs,jsn->jrn", rows, condensed)).reshape(-1, n)
    abs_cycle = jnp.abs(cycle_rows)
    # the between-burn rows as a dense matrix [n_max rm, n]: on the start state (boundary j, 0 for j = 0) and on u_j
    starts = jnp.concatenate([jnp.zeros((1, 9, n)), condensed[:-1]])
    mid = jnp.einsum("rs,jsn->jrn", mid_x, starts) \
        + jnp.einsum("rv,jk->jrkv", mid_u, jnp.eye(n_max)).reshape(n_max, rm, n)
    mid = mid.reshape(-1, n)
    abs_mid = jnp.abs(mid)

    def split(v):
        a, b = n_max * rc, n_max * (rc + rm)
        return v[:a].reshape(n_max, rc), v[a:b], v[b:].reshape(n_max, r)

    def matvec(u):
        per_cycle = jnp.einsum("rv,jv->jr", cycle_rows, u.reshape(n_max, width))
        at_boundaries = jnp.einsum("jrs,js->jr", rows, state_change(u))
        return jnp.concatenate([per_cycle.reshape(-1), mid @ u, at_boundaries.reshape(-1)])

    def rmatvec(y):
        y_cycle, y_mid, y_rows = split(y)
        return jnp.einsum("rv,jr->jv", cycle_rows, y_cycle).reshape(-1) + mid.T @ y_mid \
            + state_change_t(jnp.einsum("jrs,jr->js", rows, y_rows))

    def factor(rho, sigma):
        rho_cycle, rho_mid, rho_rows = split(rho)
        rho_mid = rho_mid.reshape(n_max, rm)
        q = jnp.einsum("jrs,jr,jrt->jst", rows, rho_rows, rows)
        theta = jax.vmap(jnp.diag)(sigma.reshape(n_max, width)) \
            + jnp.einsum("rv,jr,rw->jvw", cycle_rows, rho_cycle, cycle_rows) \
            + jnp.einsum("rv,jr,rw->jvw", mid_u, rho_mid, mid_u)
        stage = (jnp.einsum("rs,jr,rt->jst", mid_x, rho_mid, mid_x), jnp.einsum("rv,jr,rs->jvs", mid_u, rho_mid, mid_x))
        return mpc.riccati(phi, effect, theta, q, n_max, stage)

    def norms(d, e):
        d_cycle, d_mid, d_rows = split(d)
        e_cycle = e.reshape(n_max, width)
        cycle_abs = d_cycle[:, :, None] * abs_cycle[None] * e_cycle[:, None, :]  # [n_max, rc, width]
        mid_abs = d_mid[:, None] * abs_mid * e
        rows_abs = d_rows.reshape(-1, 1) * abs_rows * e
        row_norms = jnp.concatenate([jnp.max(cycle_abs, 2).reshape(-1), jnp.max(mid_abs, 1), jnp.max(rows_abs, 1)])
        col_norms = jnp.maximum(jnp.maximum(jnp.max(cycle_abs, 1).reshape(-1), jnp.max(mid_abs, 0)),
                                jnp.max(rows_abs, 0))
        return row_norms, col_norms

    return lp.Operator(matvec, rmatvec, factor, norms)


def program(model: mpc.Model, momentum: Momentum, leaves: dict, shape: mpc.Shape):
    """(c [n], lower [m], upper [m], penalty [m]) of the program on ``operator``'s rows."""
    n_max, g = shape.n_max, shape.generators
    discount = 1.0 - leaves["defer"] * jnp.arange(n_max)
    per_cycle = jnp.concatenate([jnp.ones(2 * g), jnp.zeros(TILTS), jnp.full(TILTS, 1.0) * leaves["tilt_cost"]])
    c = (discount[:, None] * per_cycle).reshape(-1)
    rc = momentum.cycle_rows.shape[0]
    lower = jnp.concatenate([jnp.tile(momentum.cycle_lower, n_max), momentum.mid_lower.reshape(-1),
                             momentum.lower.reshape(-1)])
    upper = jnp.concatenate([jnp.tile(momentum.cycle_upper, n_max), momentum.mid_upper.reshape(-1),
                             momentum.upper.reshape(-1)])
    penalty = jnp.concatenate([jnp.full(n_max * rc, jnp.inf), jnp.full(momentum.mid_lower.size, leaves["penalty_mps"]),
                               jnp.tile(momentum.row_penalty, n_max)])
    return c, lower, upper, penalty


class State(NamedTuple):
    """What the controller carries from cycle to cycle (ECI axes)."""

    g_eci_nms: jnp.ndarray  # [3] the wheels' momentum in inertial axes measured at the last cycle start
    impulse_eci_nms: jnp.ndarray  # [3] the impulse the last cycle's tilts were planned to put in
    disturbance_eci_nms: jnp.ndarray  # [3] the estimated impulse of the other torques per cycle
    cycles_seen: jnp.ndarray  # [] cycles planned so far
    lines_rsw: jnp.ndarray  # [2, 3] each burn's latest planned direction (unit, RSW at the burn): the next lines


class Plan(NamedTuple):
    """A cycle's plan: the burns and tilts flown and what the program said."""

    flown: burns_mod.BurnPlan
    tilts_rsw: jnp.ndarray  # [2, 3] each burn's planned tilt (sine of the angle, across the line, RSW)
    solved: jnp.ndarray
    fuel_mps: jnp.ndarray
    violation: jnp.ndarray
    iterations: jnp.ndarray
    certified: jnp.ndarray
    momentum_violation: jnp.ndarray  # [] the largest momentum row's violation, in half-widths
    wheels_rsw_nms: jnp.ndarray  # [2, 3] g at the cycle's start as measured, and expected at its end (start RSW)
    line_solves: jnp.ndarray  # [] the program's solves this cycle
    line_change_rad: jnp.ndarray  # [] the flown solve's largest line change (chord of unit vectors, ~ the angle)


def disturbance(state: State, g_eci, gain):
    """The other torques' impulse per cycle, updated with the cycle just flown (ECI; 0 before it)."""
    measured = g_eci - state.g_eci_nms - state.impulse_eci_nms
    updated = state.disturbance_eci_nms + gain * (measured - state.disturbance_eci_nms)
    return jnp.where(state.cycles_seen > 0, updated, 0.0)


def plan(x0, target, ref_mean, l_start_rad, limits, accel_mps2, cycle_s, leaves: dict, station: dict, lines, g0,
         d, mass_kg, dumping: dict, shape: mpc.Shape):
    """The cycle's program solved: (the first cycle's ``BurnPair``, tilts z [2, 2] m/s, ``lp.Solution``, the
    ``mpc.Model``, the ``Momentum``)."""
    model = mpc.build(x0, target, ref_mean, l_start_rad, limits, accel_mps2, cycle_s, leaves, station, shape)
    momentum = build(model, lines, g0, d, l_start_rad, mass_kg, dumping, leaves, shape)
    c, lower, upper, penalty = program(model, momentum, leaves, shape)
    solution = lp.solve(c, operator(model, momentum, shape), lower, upper, penalty, tolerance=leaves["tolerance"],
                        settings=lp.Settings(iterations=shape.iterations))
    g = shape.generators
    first = solution.x.reshape(shape.n_max, -1)[0]
    ok = jnp.all(jnp.isfinite(solution.x))
    w = jnp.where(ok, jnp.maximum(first[:2 * g].reshape(2, g), 0.0), 0.0)  # never fly a failed solve
    z = jnp.where(ok, first[2 * g:2 * g + TILTS].reshape(2, 2), 0.0)
    return mpc.first_burns(model, w, limits), z, solution, model, momentum


def planned_lines(burns, lines):
    """[2, 3] each burn's planned direction (unit, RSW at the burn); ``lines`` for a burn not planned."""
    fired = (burns.v_mps > 0)[:, None]
    return jnp.where(fired, burns.dv_rsw_mps / jnp.where(fired, burns.v_mps[:, None], 1.0), lines)


def line_change_squared(a, b):
    """The largest squared chord between two sets of unit lines [2, 3] (the sums written out: width-independent)."""
    d = a - b
    return jnp.max(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])


def make(tables: list[dict]) -> Controller:
    """The momentum MPC for a batch of ``[controller]`` tables (``mpc.shape_of``'s shapes)."""
    return controller(mpc.shape_of(tables))


def needs(config: dict) -> dict:
    """The wheels' momentum to plan and a thrust line that tilts to unload them, told by a part
    (``states.base``: ``WHEEL_MOMENTUM``, ``DUMPING``)."""
    kind = "controller.kind = 'mpc_momentum'"
    return {WHEEL_MOMENTUM: f"{kind}: plans the wheels' momentum",
            DUMPING: f"{kind}: tilts the thrust lines to unload the wheels"}


SPEC = Spec(FIELDS, mpc.validate, THRUSTERS, REDUNDANT_THRUSTERS, unread=UNREAD, needs=needs)


@functools.lru_cache(maxsize=None)
def controller(shape: mpc.Shape = mpc.Shape()) -> Controller:
    """The momentum MPC with static sizes ``shape``."""

    def init(params, context):
        zero = jnp.zeros(3)
        lines = jnp.mean(mpc.generators(arm_limits(params.thrusters), shape), axis=1)  # the rectangles' middles
        return State(zero, zero, zero, jnp.asarray(0), lines / jnp.linalg.norm(lines, axis=-1, keepdims=True))

    def plan_cycle(params, state: State, estimate, context, key):
        limits = arm_limits(params.thrusters)
        target = station_target(params.station)
        mass = estimate.mass_kg
        accel = params.thrusters["thrust_n"] / mass
        r, v = mee_to_cartesian(estimate.fix_mee, context.force_model.mu_m3_s2)
        basis = rsw_basis(r, v)  # rows R0, S0, W0 in ECI
        g_eci = basis.T @ body_to_rsw(estimate.states[WHEEL_MOMENTUM])
        d_eci = disturbance(state, g_eci, params.controller["disturbance_gain"])
        def solve(lines):
            return plan(estimate.mean, target, context.reference, estimate.fix_mee[5], limits, accel, context.cycle_s,
                        params.controller, params.station, lines, basis @ g_eci, basis @ d_eci, mass,
                        estimate.states[DUMPING], shape)

        def again(carry):  # a solve on the lines the one before planned (the first on last cycle's lines); kept
            i, lines, last, best, kept = carry  # if its lines moved least so far
            out = solve(lines)
            planned = planned_lines(out[0], state.lines_rsw)
            change = line_change_squared(planned, lines)
            better = change < best
            kept = jax.tree_util.tree_map(lambda new, old: jnp.where(better, new, old), (out, planned), kept)
            return i + 1, planned, change, jnp.where(better, change, best), kept

        def more(carry):
            (i, _, last, _, _), tolerance = carry, params.controller["line_tolerance_rad"]
            return (i < params.controller["line_solves"]) & (last > tolerance * tolerance)

        blank = jax.tree_util.tree_map(lambda a: jnp.zeros(a.shape, a.dtype), jax.eval_shape(solve, state.lines_rsw))
        solves, _, _, change_squared, ((burns, z, solution, model, momentum), lines) = jax.lax.while_loop(
            more, again, (jnp.asarray(0), state.lines_rsw, jnp.inf, jnp.inf, (blank, state.lines_rsw)))
        prediction = predict_next(estimate.mean, context.reference[0], context.reference[1], context.cycle_s)
        prediction = prediction.at[0].set(wrap_angle(prediction[0]))
        full = 2 * V_SYNC_MPS * jnp.hypot(target[4] - prediction[4], target[5] - prediction[5])
        ns_fraction = jnp.sum(jnp.abs(burns.dv_rsw_mps[:, 2])) / jnp.maximum(full, 1e-12)
        flown = burns_mod.fly(params, burns, prediction, ns_fraction, estimate, context, key)
        # Each burn's tilt about the line u flown (after the clip and the attitude error): s = (u x J) / (L m v) for
        # the planned J = -L m (u x z), so -L m v (u x s) is J less its part along u; 0 for a burn not fired.
        fired = flown.burn_s > 0
        arm_mass = estimate.states[DUMPING]["thrust_arm_m"] * mass
        impulse = -arm_mass * jnp.cross(momentum.lines, jnp.einsum("bk,bkv->bv", z, momentum.across))  # [2, 3] J
        u = flown.directions_rsw
        tilts = jnp.cross(u, impulse) / (arm_mass * jnp.where(fired, burns.v_mps, 1.0))[:, None]
        tilts = jnp.where(fired[:, None], tilts, 0.0)
        flown_impulse = jnp.where(fired[:, None], impulse - jnp.sum(u * impulse, -1, keepdims=True) * u, 0.0)
        past = jnp.mod(model.l_rad - estimate.fix_mee[5], 2 * jnp.pi)
        impulse_eci = basis.T @ jnp.sum(rotate_to_start(flown_impulse, past), 0)

        def excess_of(values, lower, upper):  # each row's violation, in half-widths
            return jnp.maximum(lower - values, 0.0) + jnp.maximum(values - upper, 0.0)

        boundary_rows = solution.ax[-momentum.lower.size:].reshape(momentum.lower.shape)
        between = solution.ax[-momentum.lower.size - momentum.mid_lower.size:-momentum.lower.size]
        excess = excess_of(boundary_rows, momentum.lower, momentum.upper)
        r_orbit = model.lower.shape[1]
        violation = jnp.max(excess[:, :r_orbit])
        momentum_violation = jnp.maximum(jnp.max(excess[:, r_orbit:-1]), jnp.max(excess_of(
            between, momentum.mid_lower.reshape(-1), momentum.mid_upper.reshape(-1))))
        solved = (violation <= mpc.SOLVED_VIOLATION) & jnp.all(jnp.isfinite(solution.x))
        # the end the plan expects of what is flown (a burn under ``thrusters.min_burn_s`` is not: no LP says so)
        g_start = basis @ g_eci
        g_end = g_start + basis @ (d_eci + impulse_eci)
        plan_ = Plan(flown, tilts, solved, solution.objective, violation, solution.iterations, solution.converged,
                     momentum_violation, jnp.stack([g_start, g_end]), solves, jnp.sqrt(change_squared))
        return plan_, State(g_eci, impulse_eci, d_eci, state.cycles_seen + 1, lines)

    def thrust(params, plan_: Plan, t, state, environment):
        return burns_mod.thrust(params, plan_.flown, t, state, environment, plan_.tilts_rsw)

    def record(plan_: Plan) -> dict:
        return {**burns_mod.record(plan_.flown), "solved": plan_.solved, "planned_fuel_mps": plan_.fuel_mps,
                "violation": plan_.violation, "iterations": plan_.iterations, "certified": plan_.certified,
                "momentum_violation": plan_.momentum_violation, "wheels_rsw_nms": plan_.wheels_rsw_nms,
                "tilts_rsw": plan_.tilts_rsw, "line_solves": plan_.line_solves,
                "line_change_rad": plan_.line_change_rad}

    # Widths as the MPC's (8 lanes per CPU core); the lane's bytes the MPC's measured 1.73 MB scaled by the
    # decisions per cycle (20 against 12): an estimate, read by the GPU's batch sizing alone.
    return Controller(init, plan_cycle, thrust, SPEC, reference_cycles=shape.n_max + 1, record=record, metrics=burn_metrics.metrics,
                      sizing=Sizing(lanes_cpu=8, working_bytes=2_500_000, one_sample_opt_level=1))
