"""The QFFC's one-cycle solution (Li 2022, Sec. 4.2, eqs. (29)-(36)): two burns that meet the predictive deviation.


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

The in-plane parts (v_r, v_t) of both burns follow from V_DT alone.  With a
pitch floor beta_min > 0 a small |V_N| cannot be flown at all (both burns need
|v_n| >= p tan beta_min); it is then raised to that floor (see ``solve``) instead
of leaving the cycle without a solution, which made the loop run away from
beta_min = 20 deg (weak preset otherwise, one year; Li 2022 Fig. 10 finds
beta_min harmless up to 40 deg).  What is
left is how |V_N| is shared (|v_n1| = n_1, |v_n2| = |V_N| - n_1; v_n1 <= 0 <= v_n2)
and V_DT, which eq. (35) lets us raise when the burns cannot both point away
from the Earth (v_r1, v_r2 <= 0, eq. (34)) or the arms cannot reach the directions.

Both are solved without trigonometry on candidates:

* Yaw limits (eq. (1)) and v_r <= 0 constrain only the in-plane part; with
  (x, y) = (-v_r, -v_t) and x >= 0, alpha <= a_hi is y cos a_hi <= x sin a_hi, and
  alpha >= a_lo likewise.
* Pitch limits: beta_min <= beta <= beta_max is p tan beta_min <= n <= p tan beta_max
  with p = |(v_r, v_t)| the in-plane magnitude.  So n_1 lies in an interval, and
  V_1 + V_2 = sqrt(p_1^2 + n_1^2) + sqrt(p_2^2 + (|V_N| - n_1)^2) is convex in n_1
  with its free minimum at equal pitch, n_1 = |V_N| p_1 / (p_1 + p_2): the least
  V_1 + V_2 is that point clipped to the interval (exact, no search).
* V_DT takes the starting value plus ``vdt_raises_mps`` (by default 0 to 0.1 m/s
  in 2 mm/s steps, then to 2 m/s in 6 % steps): the smallest raise with a solution wins ("increasing V_DT
  until we obtain a solution").

The starting V_DT is the one that cancels the predicted drift, or, with the
estimate of eqs. (37)-(39) (``estimated_drift_rad_s``), the one that leaves the
drift the next cycle needs.  ``v_n_mps`` overrides |V_N| (the FOMPC's action,
eq. (40)): the inclination is then corrected along the same direction by
|V_N| / (2 V_s) instead of |di|.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from geojax.control.effects import R_SYNC_M, V_SYNC_MPS, cycle_coast_s
from geojax.physics.fusion import materialized
from geojax.physics.propulsion import ArmLimits
from geojax.physics.trig import atan2, sincos, tan


class BurnPair(NamedTuple):
    """The control solution S of eq. (12) for one cycle, thruster 1 then thruster 2."""

    dv_rsw_mps: jnp.ndarray  # [2, 3] velocity increments, RSW
    v_mps: jnp.ndarray  # [2] V_1, V_2
    alpha_rad: jnp.ndarray  # [2]
    beta_rad: jnp.ndarray  # [2]
    l_rad: jnp.ndarray  # [2] right ascensions of the burn mid-points
    vdt_raise_mps: jnp.ndarray  # [] how much V_DT was raised above its starting value
    feasible: jnp.ndarray  # [] bool: a candidate met every constraint


def default_vdt_raises(fine_up_to_mps: float = 0.1, fine_count: int = 51, max_raise_mps: float = 2.0,
                       coarse_count: int = 50):
    """Raises of V_DT tried, m/s: 0 first, then 2 mm/s steps to 0.1 m/s, then 6 % steps to 2 m/s (101 in all).

    Li 2022 raises V_DT "until we obtain a solution", without a bound.  A
    nominal cycle needs a few mm/s at most; a cycle planned from a noisy orbit
    determination can need tenths of a m/s, and a search that stops short
    leaves it without a solution: it flies nothing, drifts, and the loop runs
    away.  Measured on li2022-qffc over a year, 16 error draws each: with a
    0.2 m/s cap, samples leave the +-0.05 deg box from H_rv = 300 and 8 of 16 at
    H_rv = 500; with this search none at H_rv = 500 (largest excursion 0.035 deg)
    and 2 of 16 at H_rv = 800, near the paper's limit of stability.
    """
    fine = jnp.linspace(0.0, fine_up_to_mps, fine_count)
    return jnp.concatenate([fine, jnp.geomspace(fine_up_to_mps, max_raise_mps, coarse_count + 1)[1:]])


def default_raise_index(raises_mps, x, side: str = "left"):
    """``jnp.searchsorted(raises_mps, x, side)`` for ``raises_mps = default_vdt_raises()``, in closed form.

    The grid is linear to 0.1 m/s and geometric above, so the index is the ceiling of an affine or
    logarithmic map of x, off by at most one where rounding puts x next to a grid value; one comparison
    with the grid value on each side of the estimate corrects it, with searchsorted's semantics (ties,
    -inf -> 0, +inf and NaN -> the length).  Three searches over the 101 raises were a third of the FOMPC's
    annealing (each compares x with every raise); ``tests/test_qffc.py`` checks it against searchsorted.
    """
    n = raises_mps.shape[0]
    fine_step = raises_mps[50] / 50  # the default grid only: 51 linear raises, then 50 geometric ones
    ratio = jnp.log(raises_mps[n - 1] / raises_mps[50]) / 50
    linear = x / fine_step
    geometric = 50 + _log_at_least_one(jnp.maximum(x, raises_mps[50]) / raises_mps[50]) / ratio
    estimate = jnp.ceil(jnp.clip(jnp.where(x <= raises_mps[50], linear, geometric), 0.0, n))
    i = jnp.where(jnp.isnan(estimate), n, estimate).astype(jnp.int32)
    above = raises_mps[jnp.minimum(i, n - 1)]  # the raise at the estimate, +inf past the end
    below = raises_mps[jnp.maximum(i - 1, 0)]  # the one before it, -inf before the start
    if side == "left":
        up, down = (i < n) & (above < x), (i > 0) & (below >= x)
    else:
        up, down = (i < n) & (above <= x), (i > 0) & (below > x)
    return jnp.where(jnp.isnan(x), n, i + up.astype(i.dtype) - down.astype(i.dtype))


def _log_at_least_one(y):
    """log y for y >= 1 within 2e-5 (inf and NaN give NaN), in multiply-adds: the index above needs it only
    to well within one grid step (log 1.06), and XLA's log costs 4 ns per element against 1 here.
    y = m 2^e with m in [1/2, 1); log m = 2 atanh(s), s = (m - 1) / (m + 1) in [-1/3, 0), to s^7."""
    m, e = jnp.frexp(y)
    s = (m - 1) / (m + 1)
    s2 = s * s
    return e * np.log(2.0) + 2 * s * (1 + s2 * (1 / 3 + s2 * (1 / 5 + s2 / 7)))


def full_correction_mps(delta_x):
    """|V_N| = 2 V_s |di| that cancels the inclination deviation in one cycle (eq. (30))."""
    return 2 * V_SYNC_MPS * jnp.hypot(delta_x[4], delta_x[5])


def solve(delta_x, l_start_rad, limits: ArmLimits | ArmTrig, vdt_raises_mps=None, coast_offset_s=0.0,
          v_n_mps=None, search: str = "structured", anchor=None, with_coast: bool = False, node_shift_rad=None):
    """Two burns that cancel the predictive deviation ``delta_x`` [6] (see module docstring).

    ``coast_offset_s`` is added to the coast T_i of eq. (20) when the deviation
    refers to a time after the end of the cycle (a mean over the next cycle).
    ``v_n_mps`` (>= 0) replaces the north-south total 2 V_s |di| of eq. (30).
    ``search`` (static) finds the smallest feasible raise of V_DT: ``"all"`` tests every candidate,
    ``"structured"`` (the default) the few that ``first_feasible_index`` brackets; both return the same
    candidate (``tests/test_qffc.py`` checks them against each other on random deviations).
    ``anchor`` (a traced scalar shared by the batch, e.g. a loop counter; optional) puts each stage of the
    solve in a kernel of its own (``physics.fusion.materialized``): XLA's CPU fusion otherwise recomputes
    the node angles and the in-plane parts in every kernel that reads them (measured on the FOMPC's
    annealing, see ``control.fompc``).  ``with_coast`` (static): return (burns, (T_1, T_2)), the coasts of
    eq. (20) that the solve used, for ``effect`` without computing them again.  ``node_shift_rad`` (optional)
    moves both burn nodes off eq. (31)'s by that angle (``control.around_passes``); ``v_n_mps`` then says what
    the moved pair corrects.
    """
    search_raises = default_raise_index if vdt_raises_mps is None else None
    vdt_raises_mps = default_vdt_raises() if vdt_raises_mps is None else vdt_raises_mps
    trig = arm_trig(limits)
    stage = functools.partial(_stage, anchor=anchor)
    l2 = stage(_node, delta_x)
    if node_shift_rad is not None:
        l2 = l2 + node_shift_rad
    l_rad = (l2 - jnp.pi, l2)
    plane, v_n_total = stage(_in_plane, delta_x, l_rad, l_start_rad, coast_offset_s, v_n_mps)
    if search != "all":
        n = vdt_raises_mps.shape[0]
        first = stage(functools.partial(first_feasible_index, search=search_raises), plane, vdt_raises_mps,
                      v_n_total, trig)
        vdt_raises_mps = vdt_raises_mps[jnp.clip(first + jnp.arange(WINDOW), 0, n - 1)]
    dv_rows, v, raise_mps, feasible = stage(_burns, plane, vdt_raises_mps, v_n_total, trig)
    dv = jnp.stack([jnp.stack(row) for row in dv_rows])
    # Eq. (14): dv = -V (cos b cos a, cos b sin a, sin b).
    alpha = atan2(-dv[:, 1], -dv[:, 0])
    beta = atan2(-dv[:, 2], jnp.hypot(dv[:, 0], dv[:, 1]))
    burns = BurnPair(dv, jnp.stack(v), alpha, beta, jnp.stack(l_rad), raise_mps, feasible)
    return (burns, plane.coast_s) if with_coast else burns


# A stage (``_stage`` with an anchor) returns a tuple of per-sample scalars, never a stacked vector: XLA's
# CPU fusion writes a stacked output in one kernel that picks the component per element (no vector
# instructions) and evaluates every component's inputs again for each (the FOMPC's effect stage spent 57 ns
# per candidate cycle there, the node and window stages as much again).
WINDOW = 4  # candidates from ``first_feasible_index`` on


def _stage(fn, *args, anchor):
    return fn(*args) if anchor is None else materialized(fn, *args, anchor=anchor)


def _node(delta_x):
    """l_2 = atan2(di_y, di_x), eq. (31) (a stage of its own: everything after reads it)."""
    return atan2(delta_x[5], delta_x[4])


def _in_plane(delta_x, l_rad, l_start_rad, coast_offset_s, v_n_mps):
    """The ``InPlane`` terms of ``delta_x`` for the burn nodes (l_1, l_2), and |V_N| (eqs. (30)-(33))."""
    d_lon, d_drift, dex, dey = (delta_x[j] for j in range(4))
    v_s = V_SYNC_MPS
    l1, l2 = l_rad
    coast = (cycle_coast_s(l1, l_start_rad) + coast_offset_s, cycle_coast_s(l2, l_start_rad) + coast_offset_s)
    cos_l2, sin_l2 = sincos(l2)
    cos_l1, sin_l1 = -cos_l2, -sin_l2
    plane = InPlane(-R_SYNC_M / 3 * d_drift, v_s * (dex * sin_l1 - dey * cos_l1),
                    0.5 * v_s * (dex * cos_l1 + dey * sin_l1), d_lon, coast)
    v_n_total = full_correction_mps(delta_x) if v_n_mps is None else jnp.maximum(v_n_mps, 0.0)
    return plane, v_n_total


def _burns(plane: InPlane, raises_mps, v_n_total, trig: ArmTrig):
    """The burns ((v_r, v_t, v_n) of thruster 1, then of thruster 2) and (V_1, V_2) of the smallest feasible
    raise of ``raises_mps``, that raise, and whether any was feasible."""
    c = candidates(plane, raises_mps, v_n_total, trig)
    i = jnp.argmax(c.feasible)  # the smallest raise that works (the first tried if none does)
    (v_r1, v_r2), (v_t1, v_t2), (p1, p2) = ((a[i], b[i]) for a, b in (c.v_r, c.v_t, c.in_plane))
    v_n, lo, hi = c.v_n[i], c.lo[i], c.hi[i]
    equal_pitch = jnp.where(p1 + p2 > 0, v_n * p1 / jnp.where(p1 + p2 > 0, p1 + p2, 1.0), 0.5 * v_n)
    n1 = jnp.clip(equal_pitch, lo, jnp.maximum(lo, hi))
    rows = ((v_r1, v_t1, -n1), (v_r2, v_t2, v_n - n1))
    norms = tuple(jnp.sqrt(x * x + y * y + z * z) for x, y, z in rows)
    return rows, norms, raises_mps[i], jnp.any(c.feasible)


class InPlane(NamedTuple):
    """What fixes the in-plane parts of both burns as functions of the raise r of V_DT (all affine in r)."""

    v_dt_mps: jnp.ndarray  # [] starting V_DT = -R_s / 3 d lambda_dot
    v_r_diff_mps: jnp.ndarray  # [] V_R
    v_t_diff_mps: jnp.ndarray  # [] V_ET
    d_lon_rad: jnp.ndarray  # []
    coast_s: tuple  # (T_1, T_2)


class Candidates(NamedTuple):
    """Burns for raises r [m] of V_DT (axis: candidate); a pair (thruster 1, thruster 2) where per thruster
    (two arrays, not a last axis of two: on the CPU each reduction or stack over it is a kernel of its own)."""

    v_r: tuple  # ([m], [m])
    v_t: tuple  # ([m], [m])
    in_plane: tuple  # ([m], [m]) p = |(v_r, v_t)|
    v_n: jnp.ndarray  # [m] |V_N| flown (raised to the pitch floor where needed)
    lo: jnp.ndarray  # [m] bounds on n_1 = |v_n1|
    hi: jnp.ndarray  # [m]
    feasible: jnp.ndarray  # [m] bool


def candidates(plane: InPlane, raises_mps, v_n_total, trig: ArmTrig) -> Candidates:
    """The burns of each raise of V_DT [m] and whether every constraint holds (eqs. (1), (34))."""
    v_dt = plane.v_dt_mps + raises_mps
    v_t = (0.5 * (v_dt + plane.v_t_diff_mps), 0.5 * (v_dt - plane.v_t_diff_mps))
    v_r_sum = -0.5 * V_SYNC_MPS * plane.d_lon_rad - 1.5 * V_SYNC_MPS / R_SYNC_M * (v_t[0] * plane.coast_s[0] + v_t[1] * plane.coast_s[1])
    v_r = (0.5 * (v_r_sum + plane.v_r_diff_mps), 0.5 * (v_r_sum - plane.v_r_diff_mps))
    in_plane = tuple(jnp.hypot(r, t) for r, t in zip(v_r, v_t))
    scale = tuple(jnp.maximum(p, 1e-9) for p in in_plane)
    ok_in_plane = [(v_r[b] <= 1e-12 * scale[b]) & _yaw_ok(-v_r[b], -v_t[b], _thruster(trig, b), 1e-12 * scale[b])
                   for b in range(2)]
    (lo1, hi1), (lo2, hi2) = (_pitch_interval(p, trig) for p in in_plane)
    # The pitch floor: both burns at beta >= beta_min need |V_N| >= tan(beta_min) (p_1 + p_2).  A smaller
    # correction is raised to it (the inclination overshoots by the excess and the next cycle takes it
    # back) rather than flying nothing; with beta_min = 0 this never acts.
    v_n = jnp.maximum(v_n_total, lo1 + lo2)
    # n_1 within its own interval and V_N - n_1 within thruster 2's.
    lo = jnp.maximum(lo1, v_n - hi2)
    hi = jnp.minimum(hi1, v_n - lo2)
    ok_pitch = lo <= hi + 1e-12 * (v_n + scale[0] + scale[1])
    return Candidates(v_r, v_t, in_plane, v_n, lo, hi, ok_in_plane[0] & ok_in_plane[1] & ok_pitch)


def _thruster(trig: ArmTrig, b: int) -> ArmTrig:
    """The yaw limits of thruster ``b`` alone."""
    return trig._replace(cos_yaw_hi=trig.cos_yaw_hi[b], sin_yaw_hi=trig.sin_yaw_hi[b],
                         cos_yaw_lo=trig.cos_yaw_lo[b], sin_yaw_lo=trig.sin_yaw_lo[b])


def in_plane_coefficients(plane: InPlane):
    """(v_r, v_t) of both burns as q0 + q1 r and t0 + r / 2 [2] (eqs. (32)-(33) with V_DT raised by r)."""
    k = -1.5 * V_SYNC_MPS / R_SYNC_M
    t0 = 0.5 * jnp.stack([plane.v_dt_mps + plane.v_t_diff_mps, plane.v_dt_mps - plane.v_t_diff_mps])
    s0 = -0.5 * V_SYNC_MPS * plane.d_lon_rad + k * (t0[0] * plane.coast_s[0] + t0[1] * plane.coast_s[1])
    s1 = k * 0.5 * (plane.coast_s[0] + plane.coast_s[1])
    return 0.5 * jnp.stack([s0 + plane.v_r_diff_mps, s0 - plane.v_r_diff_mps]), 0.5 * s1, t0


def first_feasible_index(plane: InPlane, raises_mps, v_n_total, trig: ArmTrig, search=None):
    """The index into the sorted ``raises_mps`` of a window that holds its first feasible candidate, found
    without testing them all.

    The in-plane parts are affine in the raise r, so the sign and yaw constraints (v_r <= 0, eq. (1)) each
    bound r on one side: together an interval [r_lo, r_hi].  The pitch limits hold where the north-south
    correction fits under beta_max, |V_N| <= tan(beta_max) P(r) with P = p_1 + p_2 (the floor of beta_min
    only raises |V_N| to tan(beta_min) P <= tan(beta_max) P); P, a sum of norms of affine functions, is
    convex.  So the first feasible candidate is the first one in [r_lo, r_hi] if P is large enough there;
    else P is below the bound from there up to its right root, beyond which it stays above: that root in
    closed form, and the first candidate past it.  The window starts one candidate before it, so that
    ``candidates`` (with its tolerances) makes the final choice; with no feasible candidate it starts at
    the first one, as the exhaustive search returns.  ``search(raises_mps, x, side)`` is searchsorted
    (``default_raise_index`` for the default raises).
    """
    if search is None:
        search = functools.partial(jnp.searchsorted, method="compare_all")
    q0, q1, t0 = in_plane_coefficients(plane)
    n = raises_mps.shape[0]
    # g0 + g1 r <= 0 for each burn: v_r <= 0, alpha <= its upper limit, alpha >= its lower limit.
    g0 = jnp.concatenate([q0, -t0 * trig.cos_yaw_hi + q0 * trig.sin_yaw_hi, t0 * trig.cos_yaw_lo - q0 * trig.sin_yaw_lo])
    g1 = jnp.concatenate([jnp.broadcast_to(q1, (2,)), -0.5 * trig.cos_yaw_hi + q1 * trig.sin_yaw_hi,
                          0.5 * trig.cos_yaw_lo - q1 * trig.sin_yaw_lo])
    bound = -g0 / jnp.where(g1 == 0, 1.0, g1)
    r_lo = jnp.max(jnp.where(g1 < 0, bound, -jnp.inf))
    r_hi = jnp.min(jnp.where(g1 > 0, bound, jnp.inf))
    constant_ok = jnp.all((g1 != 0) | (g0 <= 0))
    j_lo = search(raises_mps, r_lo, side="left")
    j_hi = search(raises_mps, r_hi, side="right") - 1

    need = jnp.where(trig.vertical, 0.0, v_n_total / trig.tan_pitch_max)  # beta_max = 90 deg: no bound
    j_start = jnp.clip(j_lo, 0, n - 1)
    r_start = raises_mps[j_start]
    ok_start = jnp.sum(jnp.hypot(q0 + q1 * r_start, t0 + 0.5 * r_start)) >= need
    # Else the first candidate past the right root of P(r) = c.  P = |A_1 + r B| + |A_2 + r B| with
    # A_b = (q0_b, t0_b), B = (q1, 1/2); squaring twice, (Q_1 - Q_2 - c^2)^2 = 4 c^2 Q_2 with
    # Q_b = |A_b + r B|^2, a quadratic in r (Q_1 - Q_2 is linear), whose roots are where P = c (its other
    # solutions need |f_1 - f_2| = c, and |f_1 - f_2| <= |A_1 - A_2| <= min P < c here).
    b2 = q1 * q1 + 0.25
    a_b = q0 * q1 + 0.5 * t0  # A_b . B
    a_sq = q0 * q0 + t0 * t0
    c2 = need * need
    d0, d1 = a_sq[0] - a_sq[1] - c2, 2 * (a_b[0] - a_b[1])
    quad = d1 * d1 - 4 * c2 * b2
    lin = 2 * d1 * d0 - 8 * c2 * a_b[1]
    const = d0 * d0 - 4 * c2 * a_sq[1]
    root = jnp.sqrt(jnp.maximum(lin * lin - 4 * quad * const, 0.0))
    # quad <= 0 (|d1| <= 2 |A_1 - A_2| |B| <= 2 c |B|): the larger root takes -root
    safe = jnp.where(quad < 0, quad, -1.0)
    r_right = jnp.where(quad < 0, (-lin - root) / (2 * safe), -const / jnp.where(lin == 0, 1.0, lin))
    j_pitch = search(raises_mps, r_right, side="left")
    j = jnp.where(ok_start, j_start, jnp.maximum(j_pitch, j_start))
    found = constant_ok & (j_lo <= j_hi) & (j <= j_hi) & (j_lo < n)
    return jnp.where(found, j - 1, 0)


class ArmTrig(NamedTuple):
    """The trigonometry of the arm limits that ``solve`` reads (``arm_trig``): a planner that solves many
    candidate cycles with the same limits (the FOMPC) computes it once per plan."""

    cos_yaw_hi: jnp.ndarray  # [2] upper yaw limit of each thruster: alpha_max, alpha_min
    sin_yaw_hi: jnp.ndarray
    cos_yaw_lo: jnp.ndarray  # [2] lower yaw limit: -alpha_min, -alpha_max
    sin_yaw_lo: jnp.ndarray
    tan_pitch_min: jnp.ndarray  # []
    tan_pitch_max: jnp.ndarray  # [] (finite; ``vertical`` marks beta_max = 90 deg: no upper bound)
    vertical: jnp.ndarray  # [] bool


def arm_trig(limits: ArmLimits | ArmTrig) -> ArmTrig:
    """``ArmTrig`` of eq. (1)'s limits (an ``ArmTrig`` is returned as it is)."""
    if isinstance(limits, ArmTrig):
        return limits
    hi = jnp.stack([limits.alpha_max_rad, limits.alpha_min_rad])
    lo = jnp.stack([-limits.alpha_min_rad, -limits.alpha_max_rad])
    finite = lambda b: tan(jnp.minimum(b, jnp.pi / 2 - 1e-12))  # noqa: E731
    return ArmTrig(jnp.cos(hi), jnp.sin(hi), jnp.cos(lo), jnp.sin(lo), finite(limits.beta_min_rad),
                   finite(limits.beta_max_rad), jnp.cos(limits.beta_max_rad) < 1e-12)


def _yaw_ok(x, y, trig: ArmTrig, tol):
    """Eq. (1) yaw limits for in-plane vectors (x, y) = (-v_r, -v_t) [..., 2] with x >= 0, without atan2."""
    below_hi = y * trig.cos_yaw_hi - x * trig.sin_yaw_hi <= tol
    above_lo = y * trig.cos_yaw_lo - x * trig.sin_yaw_lo >= -tol
    return below_hi & above_lo


def _pitch_interval(in_plane_mps, trig: ArmTrig):
    """Eq. (1) pitch limits as bounds on |v_n| for in-plane magnitudes p [..., 2]: [p tan b_min, p tan b_max]."""
    hi = jnp.where(trig.vertical, jnp.inf, in_plane_mps * trig.tan_pitch_max)
    return in_plane_mps * trig.tan_pitch_min, hi
