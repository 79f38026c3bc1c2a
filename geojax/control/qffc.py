"""Quick feedforward controller, the per-cycle solve (Li 2022, Sec. 4.2, eqs. (28)-(35)).

Given the predictive deviation dx = (d lambda, d lambda_dot, d e_x, d e_y, d i_x, d i_y)
of eq. (28) (target minus predicted, lambda in rad, lambda_dot in rad/s, e and i
vectors as MEE f, g, h, k), find two burns v_1, v_2 (RSW, m/s) at right
ascensions l_1 and l_2 = l_1 + pi with B_1 v_1 + B_2 v_2 = dx (eq. (29)), using
the re-derived B of ``geojax.control.effects``.  With
V_R = v_r1 - v_r2, V_ET = v_t1 - v_t2, V_DT = v_t1 + v_t2, V_RS = v_r1 + v_r2 and
V_N = v_n1 - v_n2, the rows of eq. (29) read (compare eqs. (32)-(33)):

    V_R  = V_s (de_x sin l_1 - de_y cos l_1)
    V_ET = V_s / 2 (de_x cos l_1 + de_y sin l_1)
    V_DT = -R_s / 3 d lambda_dot
    V_RS = -V_s / 2 d lambda - 3 V_s / (2 R_s) (T_1 v_t1 + T_2 v_t2)
    V_N  = 2 V_s (di_x cos l_1 + di_y sin l_1) = -2 V_s |di|,   l_2 = atan2(di_y, di_x)  (eq. (31))

The remaining freedom is how V_N is shared (v_n1 <= 0 <= v_n2), and V_DT,
which eq. (35) lets us raise when the burns cannot both point away from the
Earth (v_r1, v_r2 <= 0, eq. (34)) or the arms cannot reach the directions.
This solve is a bounded, vectorised search (jittable, vmappable): V_DT takes
the predicted value plus ``vdt_raise_mps`` steps (the smallest raise that works
wins, "increasing V_DT until we obtain a solution"), the north-south share
takes ``n_split`` values, and among the feasible candidates with the smallest
raise we keep the one of least V_1 + V_2.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.control.effects import R_SYNC_M, V_SYNC_MPS, cycle_coast_s, effect_matrix
from geojax.propulsion import ArmLimits, within_limits


class BurnPair(NamedTuple):
    """The control solution S of eq. (12) for one cycle, thruster 1 then thruster 2."""

    dv_rsw_mps: jnp.ndarray  # [2, 3] velocity increments, RSW
    v_mps: jnp.ndarray  # [2] V_1, V_2
    alpha_rad: jnp.ndarray  # [2]
    beta_rad: jnp.ndarray  # [2]
    l_rad: jnp.ndarray  # [2] right ascensions of the burn mid-points
    vdt_raise_mps: jnp.ndarray  # [] how much V_DT was raised above the prediction
    feasible: jnp.ndarray  # [] bool: a candidate met every constraint


def default_vdt_raises(max_raise_mps: float = 0.2, count: int = 101):
    """Raises of V_DT tried, m/s: 0 first, then upwards."""
    return jnp.linspace(0.0, max_raise_mps, count)


def solve(delta_x, l_start_rad, limits: ArmLimits, vdt_raises_mps=None, n_split: int = 33, coast_offset_s=0.0) -> BurnPair:
    """Two burns that cancel the predictive deviation ``delta_x`` [6] (see module docstring).

    ``coast_offset_s`` is added to the coast T_i of eq. (20) when the deviation
    refers to a time after the end of the cycle (a mean over the next cycle).
    """
    vdt_raises_mps = default_vdt_raises() if vdt_raises_mps is None else vdt_raises_mps
    d_lon, d_drift, dex, dey, dix, diy = (delta_x[j] for j in range(6))
    v_s, r_s = V_SYNC_MPS, R_SYNC_M

    l2 = jnp.arctan2(diy, dix)  # eq. (31)
    l1 = l2 - jnp.pi
    coast = jnp.stack([cycle_coast_s(l1, l_start_rad), cycle_coast_s(l2, l_start_rad)]) + coast_offset_s

    v_r_diff = v_s * (dex * jnp.sin(l1) - dey * jnp.cos(l1))
    v_t_diff = 0.5 * v_s * (dex * jnp.cos(l1) + dey * jnp.sin(l1))
    v_n_total = 2 * v_s * jnp.hypot(dix, diy)  # |v_n1| + |v_n2|

    # Candidates: [raises, splits].
    v_dt = (-r_s / 3 * d_drift + vdt_raises_mps)[:, None]
    v_t1 = 0.5 * (v_dt + v_t_diff)
    v_t2 = 0.5 * (v_dt - v_t_diff)
    v_r_sum = -0.5 * v_s * d_lon - 1.5 * v_s / r_s * (coast[0] * v_t1 + coast[1] * v_t2)
    v_r1 = 0.5 * (v_r_sum + v_r_diff)
    v_r2 = 0.5 * (v_r_sum - v_r_diff)
    share = jnp.linspace(0.0, 1.0, n_split)[None, :]
    v_n1 = -share * v_n_total
    v_n2 = (1 - share) * v_n_total

    dv = jnp.stack(
        [jnp.stack(jnp.broadcast_arrays(v_r1, v_t1, v_n1), -1), jnp.stack(jnp.broadcast_arrays(v_r2, v_t2, v_n2), -1)],
        -2,
    )  # [raises, splits, 2, 3]
    v = jnp.linalg.norm(dv, axis=-1)
    # Eq. (14): dv = -V (cos b cos a, cos b sin a, sin b).
    alpha = jnp.arctan2(-dv[..., 1], -dv[..., 0])
    beta = jnp.arcsin(jnp.clip(-dv[..., 2] / jnp.where(v > 0, v, 1.0), -1.0, 1.0))
    idle = v < 1e-9  # a thruster with nothing to do has no direction to check
    ok = (within_limits(alpha, beta, limits) | idle) & ((dv[..., 0] <= 1e-12) | idle)
    feasible = jnp.all(ok, axis=-1)  # [raises, splits]

    # Smallest raise that works, then least V_1 + V_2 at that raise.
    any_at_raise = jnp.any(feasible, axis=1)
    raise_index = jnp.argmax(any_at_raise)
    cost = jnp.where(feasible[raise_index], jnp.sum(v[raise_index], axis=-1), jnp.inf)
    split_index = jnp.argmin(cost)
    pick = lambda x: x[raise_index, split_index]  # noqa: E731
    return BurnPair(
        dv_rsw_mps=pick(dv),
        v_mps=pick(v),
        alpha_rad=pick(alpha),
        beta_rad=pick(beta),
        l_rad=jnp.stack([l1, l2]),
        vdt_raise_mps=vdt_raises_mps[raise_index],
        feasible=jnp.any(any_at_raise),
    )


def effect(burns: BurnPair, l_start_rad, coast_offset_s=0.0):
    """B_1 v_1 + B_2 v_2 (eq. (29)) of a solution, for checking it."""
    coast = cycle_coast_s(burns.l_rad, l_start_rad) + coast_offset_s
    matrices = effect_matrix(burns.l_rad, coast)  # [2, 6, 3]
    return jnp.einsum("nij,nj->i", matrices, burns.dv_rsw_mps)

