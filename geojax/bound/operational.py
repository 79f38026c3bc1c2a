"""Gazzino 2016's operational thruster constraints on the bound's relaxed plan, by its two equivalence schemes.

The bound (``geojax.bound``, Gazzino's Problem 3 as a linear program) lets thrusters fire together and for any
time; a real electric thruster (Gazzino Sec. 2.2, after Losa 2014) obeys

    (i)   no two thrusters fire at once;
    (ii)  a firing lasts at least T_l                                     (``t_min_firing_s``);
    (iii) two firings of one thruster are at least T_s apart               (``t_same_gap_s``);
    (iv)  firings of two different thrusters are at least T_d apart        (``t_other_gap_s``);
    (14)  every firing lies within the horizon [0, T].

The paper gives none of T_l, T_s, T_d; ``Constraints`` holds our marked choices.  A firing (a *pulse*) is its
thruster, its centre t_ij and its duration 2 dt_ij (Gazzino eq. (6)).  Step (B) of the paper turns the relaxed
thrust into pulses by one of two equivalences (Sec. 4):

* ``fuel_based`` (Problem 6): each thruster fires as long in total as in the relaxed plan.  Our reading: one
  pulse per *window* (a run of relaxed firing of one thruster), at its firing-weighted centroid and as long as
  its relaxed firing; a window shorter than T_l carries its firing to the thruster's next window (the same
  node a day later), so each thruster's total is kept; then ``schedule`` moves the pulses as little as the
  constraints allow.  The pulses' effect on the orbit is not looked at.
* ``effect_based`` (Problem 7): the pulses at the schedule's positions, their durations chosen for their
  effect on the state.  The paper matches the state at the horizon's end only (its relaxed plan ends at
  x(T) = 0 by a terminal condition the bound does not have); our reading, a choice: the durations are the
  least fuel that holds the box at every step start in the linear model (``bound.linear``), i.e. the bound's
  program with the scheduled pulses as its only columns, each duration in {0} u [T_l, the room the schedule
  leaves it].
* ``effect_matched`` (Problem 7 as the paper writes it): the pulses at the schedule's positions, their durations
  the L1-nearest match of the relaxed plan's effect on the state at the horizon's end, Phi(T, tau) B F of eq.
  (33), in the linear model about the relaxed plan's flight; no box rows.  With the relaxed plan's terminal
  condition (``bound(..., terminal=True)``) that end state is x(T) = x(0).

Times are seconds since the start of the run; ``step_s`` is the integration step, and a pulse flies in the
closed loop as the overlap of each step with it (``step_plan``, flown by ``bound.replay`` with one step per
slot), so its Delta-V is exact and its timing second-order accurate.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize
import scipy.sparse as sp

from geojax.bound.linear import SlotModel, linearize
from geojax.bound.run import BOX_MARGIN, _uncontrolled
from geojax.runner.setup import prepare, unstack

TINY_S = 1e-6  # firing shorter than this (s) is no firing
# Effect-based rounds after the first: cost per second of change from the last durations (per second of firing:
# 1).  Measured on gazzino2016, 28 days: bound's 1e-3 lets the plan hop between equally cheap pulse sets for
# six rounds (0.0508-0.0518 deg flown against 0.05); 0.05 settles in three, 2 % above the relaxed optimum.
PROX = 0.05


class Constraints(NamedTuple):
    """Gazzino Sec. 2.2 (i)-(iv); the paper gives no values: each is a marked choice."""

    # Choice: 30 min (two integration steps): a Hall thruster's start (cathode heating, discharge settling)
    # makes firings shorter than tens of minutes wasteful; the relaxed plan fires 15-45 min per thruster per node.
    t_min_firing_s: float = 1800.0
    # Choice: 3 h: one firing per thruster per node passage (the nodes are 12 h apart), so a node's firing of
    # one thruster is one pulse, never a split one.
    t_same_gap_s: float = 10800.0
    # Choice: 15 min (one integration step): the power processing unit's switch from one thruster to another.
    t_other_gap_s: float = 900.0


class Pulses(NamedTuple):
    """Firings, in time order of ``centre_s``; [P] each."""

    thruster: np.ndarray  # int, index into the geometry's thrusters
    centre_s: np.ndarray  # mid-time of the firing, s since the start (Gazzino's t_ij)
    duration_s: np.ndarray  # firing time, s (Gazzino's 2 dt_ij)


def fuel_based(firing_s, step_s: float, horizon_s: float, constraints: Constraints = Constraints()) -> Pulses:
    """Gazzino's Problem 6 (consumption-based equivalence): ``firing_s`` [N, n_thrusters] the relaxed plan's
    firing time per step and thruster (Delta-V over F/m); returns the scheduled pulses (``windows``, then
    ``schedule``)."""
    return schedule(windows(firing_s, step_s, constraints), horizon_s, constraints)


def windows(firing_s, step_s: float, constraints: Constraints = Constraints()) -> Pulses:
    """One pulse per window of each thruster's relaxed firing, unscheduled (they may overlap).

    A window is a run of steps with firing; runs of one thruster closer than T_s are one window.  A window
    is centred at its firing-weighted centroid (the firing taken at each step's middle) and lasts its total
    firing.  A window shorter than T_l gives its firing to the thruster's next window (the last one to its
    previous), so each thruster's total firing is kept; a thruster whose whole firing is shorter than T_l
    fires T_l once (the only fuel added).
    """
    firing_s = np.asarray(firing_s, float)
    mid_s = (np.arange(len(firing_s)) + 0.5) * step_s
    thruster, centre, duration = [], [], []
    for i in range(firing_s.shape[1]):  # planning, not the engine: a loop over four thrusters and their windows
        on = np.flatnonzero(firing_s[:, i] > TINY_S)
        if len(on) == 0:
            continue
        new = np.concatenate([[True], np.diff(on) * step_s > constraints.t_same_gap_s])  # window starts
        label = np.cumsum(new) - 1
        weight = firing_s[on, i]
        total = np.bincount(label, weight)
        where = np.bincount(label, weight * mid_s[on]) / total
        total, where = _carry_short(total, where, constraints.t_min_firing_s)
        thruster += [i] * len(total)
        centre += list(where)
        duration += list(total)
    order = np.lexsort((thruster, centre))
    return Pulses(np.asarray(thruster, int)[order], np.asarray(centre, float)[order], np.asarray(duration, float)[order])


def _carry_short(total_s, centre_s, t_min_s):
    """Windows shorter than ``t_min_s`` give their firing to the next window (the last to the previous one)."""
    total_s, keep = total_s.copy(), np.ones(len(total_s), bool)
    for j in range(len(total_s) - 1):
        if total_s[j] < t_min_s:
            total_s[j + 1] += total_s[j]
            keep[j] = False
    kept_before = np.flatnonzero(keep[:-1])
    if total_s[-1] < t_min_s and len(kept_before):
        total_s[kept_before[-1]] += total_s[-1]
        keep[-1] = False
    total_s = np.maximum(total_s, t_min_s)  # only a thruster whose whole firing is below T_l
    return total_s[keep], centre_s[keep]


def schedule(pulses: Pulses, horizon_s: float, constraints: Constraints = Constraints()) -> Pulses:
    """The pulses moved as little as (i)-(iv) and (14) allow: min sum |t_j - t_j,wanted| over the centres t,
    the durations and the time order of the wanted centres kept (a linear program; planning, not the engine).

    In time order, (iv) between neighbours and (iii) between a pulse and its thruster's previous one imply
    every pairwise condition (a pulse between two others lasts at least T_l > 0).  Raises ``ValueError`` if
    the firings cannot fit in the horizon.
    """
    p = len(pulses.centre_s)
    if p == 0:
        return pulses
    half = pulses.duration_s / 2
    # Rows t_a - t_b <= -(half_a + half_b + gap) for every pair (b before a) that must be apart.
    previous_same = np.array([np.flatnonzero(pulses.thruster[:j] == pulses.thruster[j])[-1]
                              if np.any(pulses.thruster[:j] == pulses.thruster[j]) else -1 for j in range(p)])
    pairs = [(j, j + 1, constraints.t_same_gap_s if pulses.thruster[j] == pulses.thruster[j + 1]
              else constraints.t_other_gap_s) for j in range(p - 1)]
    pairs += [(previous_same[j], j, constraints.t_same_gap_s) for j in range(p) if previous_same[j] >= 0]
    first, second, gap = (np.array(x) for x in zip(*pairs)) if pairs else (np.zeros(0, int),) * 3
    n = len(first)
    # Variables: centres t [P], displacements s [P] >= |t - wanted|.
    rows = np.arange(n)
    a_gap = sp.csr_matrix((np.r_[np.ones(n), -np.ones(n)], (np.r_[rows, rows], np.r_[first, second])), shape=(n, 2 * p))
    eye = sp.identity(p, format="csr")
    a_abs = sp.vstack([sp.hstack([eye, -eye]), sp.hstack([-eye, -eye])])
    a_ub = sp.vstack([a_gap, a_abs]).tocsr()
    b_ub = np.r_[-(half[first] + half[second] + gap), pulses.centre_s, -pulses.centre_s]
    bounds = [(h, horizon_s - h) for h in half] + [(0, None)] * p
    cost = np.r_[np.zeros(p), np.ones(p)]
    result = scipy.optimize.linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if result.status != 0:
        raise ValueError(f"operational: the {p} firings ({pulses.duration_s.sum() / 3600:.1f} h) do not fit in the "
                         f"horizon under the constraints ({result.message})")
    return pulses._replace(centre_s=result.x[:p])


def violations(pulses: Pulses, horizon_s: float, constraints: Constraints = Constraints(), tol_s: float = 1e-6) -> dict:
    """How many pulses or pairs break each constraint, checked over every pair (independently of
    ``schedule``'s rows): ``simultaneous`` (i), ``short`` (ii), ``same_gap`` (iii), ``other_gap`` (iv),
    ``outside`` (14)."""
    start = pulses.centre_s - pulses.duration_s / 2
    end = pulses.centre_s + pulses.duration_s / 2
    # Gap between pulses a and b (negative: overlap), Gazzino eq. (13): |t_a - t_b| - (dt_a + dt_b).
    gap = np.abs(pulses.centre_s[:, None] - pulses.centre_s[None, :]) - (pulses.duration_s[:, None] + pulses.duration_s[None, :]) / 2
    pair = np.triu(np.ones_like(gap, bool), 1)
    same = pulses.thruster[:, None] == pulses.thruster[None, :]
    return {"simultaneous": int(np.sum(pair & ~same & (gap < -tol_s))),
            "short": int(np.sum(pulses.duration_s < constraints.t_min_firing_s - tol_s)),
            "same_gap": int(np.sum(pair & same & (gap < constraints.t_same_gap_s - tol_s))),
            "other_gap": int(np.sum(pair & ~same & (gap < constraints.t_other_gap_s - tol_s))),
            "outside": int(np.sum((start < -tol_s) | (end > horizon_s + tol_s)))}


def overlap_s(pulses: Pulses, step_s: float, n_steps: int) -> np.ndarray:
    """Firing time of each pulse within each step [N, P] (s): the exact overlap of [start, end] with the step."""
    t0 = np.arange(n_steps)[:, None] * step_s
    start = (pulses.centre_s - pulses.duration_s / 2)[None, :]
    end = (pulses.centre_s + pulses.duration_s / 2)[None, :]
    return np.clip(np.minimum(end, t0 + step_s) - np.maximum(start, t0), 0.0, None)


def step_plan(pulses: Pulses, directions_rsw, accel_mps2: float, step_s: float, n_steps: int):
    """The pulses as per-step Delta-V: the resultant u [N, 3] (RSW, m/s) and the fuel [N] (m/s), for
    ``bound.replay(u, fuel, 1, step_s)``.  ``directions_rsw`` [n_thrusters, 3] unit Delta-V directions;
    ``accel_mps2`` F/m."""
    dv = overlap_s(pulses, step_s, n_steps) * accel_mps2  # [N, P]
    return dv @ np.asarray(directions_rsw)[pulses.thruster], dv.sum(axis=1)


def effect_based(scenario, u_relaxed_rsw, pulses: Pulses, directions_rsw, accel_mps2: float, box_rad: float,
                 constraints: Constraints = Constraints(), rounds: int = 6, say=lambda *a, **k: None) -> Pulses:
    """Gazzino's Problem 7 as we read it (module docstring): new durations for the scheduled ``pulses`` (their
    centres kept) that hold |lon - station|, |lat| <= ``box_rad`` at every step start, by sequential
    linearisation as in ``bound``: linearise ``scenario`` about the plan so far (first the relaxed per-step
    plan ``u_relaxed_rsw`` [N, 3]), solve ``effect_durations``, fly the result (the model's nominal is its
    nonlinear flight), until the flight holds the box (less ``bound``'s margin) or after ``rounds``.  From the
    second round on, of the durations of (nearly) least fuel the program takes those nearest the last ones
    (``PROX``), or the plan hops between equally cheap pulse sets and the model never settles.
    """
    model, step_s = linear_model(scenario, u_relaxed_rsw)
    n_steps, u_nominal, shape_s, last = len(u_relaxed_rsw), np.asarray(u_relaxed_rsw), pulses.duration_s, None
    for done in range(1, rounds + 1):
        duration = effect_durations(model, u_nominal, pulses, directions_rsw, accel_mps2, step_s, box_rad,
                                    constraints, shape_s, last)
        shape_s, last = np.where(duration > 0, duration, pulses.duration_s), duration
        u_nominal = step_plan(pulses._replace(duration_s=duration), directions_rsw, accel_mps2, step_s, n_steps)[0]
        model = linear_model(scenario, u_nominal)[0]
        worst = float(np.max(np.abs(model.y)))
        say(f"  effect-based round {done}: {np.sum(duration > 0)} pulses, {duration.sum() * accel_mps2:.4f} m/s; "
            f"flown, max |box| {np.degrees(worst):.5f} deg", flush=True)
        if worst <= box_rad / (1 - BOX_MARGIN):
            break
    keep = duration > 0
    return Pulses(pulses.thruster[keep], pulses.centre_s[keep], duration[keep])


def effect_durations(model: SlotModel, u_nominal_rsw, pulses: Pulses, directions_rsw, accel_mps2: float,
                     step_s: float, box_rad: float, constraints: Constraints = Constraints(), shape_s=None,
                     near_s=None) -> np.ndarray:
    """The least total firing [P] (s, 0 for a dropped pulse) of ``pulses`` at their centres that holds
    |lon - station|, |lat| <= ``box_rad`` at every step start in ``model`` (one step per slot, linearised
    about the per-step plan ``u_nominal_rsw`` [N, 3]); ``near_s`` [P]: plus ``PROX`` x sum |d - near_s|.

    A pulse acts as its overlap with the steps at duration ``shape_s`` (default: its scheduled one), scaled
    by its duration (first order; ``effect_based`` re-linearises).  Its duration lies in {0} u [T_l,
    scheduled + its room] (``_room_s``: every neighbour may grow as well without breaking (iii), (iv), (14)).
    The {0} u [T_l, ...] choice takes two programs: the first over [0, ...], then pulses below T_l / 2 are
    dropped and the rest held at T_l or more.  Raises ``ValueError`` if the pulses cannot hold the box.
    """
    n_steps = len(u_nominal_rsw)
    shape_s = pulses.duration_s if shape_s is None else shape_s
    per_s = overlap_s(pulses._replace(duration_s=shape_s), step_s, n_steps) / shape_s  # [N, P]
    columns = per_s[:, None, :] * np.asarray(directions_rsw)[pulses.thruster].T[None] * accel_mps2  # [N, 3, P]
    y0, gain = linear_response(model, -np.asarray(u_nominal_rsw), columns)
    rows = np.asarray(gain).reshape(-1, len(shape_s))
    offset = np.asarray(model.y).reshape(-1) + np.asarray(y0).reshape(-1)
    upper = pulses.duration_s + _room_s(pulses, n_steps * step_s, constraints)
    duration = _least_firing(rows, offset, box_rad, np.zeros_like(upper), upper, near_s)
    t_min = constraints.t_min_firing_s
    lower = np.where(duration >= t_min / 2, t_min, 0.0)
    duration = _least_firing(rows, offset, box_rad, lower, np.where(lower > 0, upper, 0.0), near_s)
    return np.where(lower > 0, np.maximum(duration, t_min), 0.0)  # (the solver's tolerance)


# Problem 7, tie-break among the best matches: per second of firing (``tie="fuel"``) or of change from the
# scheduled durations (``tie="near"``), against 1 per 1e-4 of scaled end state (``program.STATE_SCALE_REL``); a
# second of firing moves the end state by ~5e-5 of that unit, so the match comes first.
TIE = 1e-8


def effect_matched(scenario, u_relaxed_rsw, pulses: Pulses, directions_rsw, accel_mps2: float,
                   constraints: Constraints = Constraints(), tie: str = "fuel") -> tuple[Pulses, dict]:
    """Gazzino's Problem 7 as written (module docstring): new durations for the scheduled ``pulses`` (their
    centres kept) whose effect on the state at the horizon's end matches the relaxed per-step plan
    ``u_relaxed_rsw`` [N, 3]'s, in the linear model about the relaxed plan's flight (one linearisation, as the
    paper's Phi(T, tau)); no box.  Returns the kept pulses and ``end_effect_durations``'s report."""
    model, step_s = linear_model(scenario, u_relaxed_rsw)
    duration, report = end_effect_durations(model, u_relaxed_rsw, pulses, directions_rsw, accel_mps2, step_s,
                                            constraints, tie)
    keep = duration > 0
    return Pulses(pulses.thruster[keep], pulses.centre_s[keep], duration[keep]), report


def end_effect_durations(model: SlotModel, u_relaxed_rsw, pulses: Pulses, directions_rsw, accel_mps2: float,
                         step_s: float, constraints: Constraints = Constraints(), tie: str = "fuel",
                         scale_p_m: float | None = None):
    """Problem 7's durations [P] (s, 0 for a dropped pulse): min || W (G d - e) ||_1 (+ ``TIE`` x the
    tie-break) over d in {0} u [T_l, scheduled + its room] (``_room_s``), where e = sum_k Phi(T, k + 1) B_k
    u_relaxed_k is the relaxed plan's effect on the end state, G [6, P] the pulses' per second of firing (each
    as its overlap with the steps at its scheduled duration, as ``effect_durations``), and W the program's
    state scale (1e-4 of p (``scale_p_m``, default the model's initial p), of e, of i, rad of L).  A linear
    program with slacks s >= |W (G d - e)|; the {0} u [T_l, ...] choice as in ``effect_durations`` (two
    programs).  ``tie``: ``"fuel"`` the least firing
    among the best matches, ``"near"`` the nearest to the scheduled durations.  Returns the durations and
    {"mismatch": W (G d - e) [6] (units of 1e-4), "relaxed": W e [6]}.
    """
    from geojax.bound.program import STATE_SCALE_REL

    phi, b = np.asarray(model.phi), np.asarray(model.b)
    n_steps = len(u_relaxed_rsw)
    to_end = np.zeros((n_steps, 6, 3))  # Phi(T, k + 1) B_k, by the backward recursion
    carry = np.eye(6)
    for k in range(n_steps - 1, -1, -1):
        to_end[k] = carry @ b[k]
        carry = carry @ phi[k]
    scale_p_m = float(model.x[0, 0]) if scale_p_m is None else scale_p_m
    weight = 1.0 / np.r_[STATE_SCALE_REL * scale_p_m, np.full(5, STATE_SCALE_REL)]
    per_s = overlap_s(pulses, step_s, n_steps) / pulses.duration_s  # [N, P]
    columns = np.asarray(directions_rsw)[pulses.thruster] * accel_mps2  # [P, 3] Delta-V per s of firing
    gain = weight[:, None] * np.einsum("kij,kp,pj->ip", to_end, per_s, columns)  # [6, P]
    relaxed = weight * np.einsum("kij,kj->i", to_end, np.asarray(u_relaxed_rsw))  # [6]
    upper = pulses.duration_s + _room_s(pulses, n_steps * step_s, constraints)
    near = pulses.duration_s if tie == "near" else None
    duration = _matched(gain, relaxed, np.zeros_like(upper), upper, near)
    t_min = constraints.t_min_firing_s
    lower = np.where(duration >= t_min / 2, t_min, 0.0)
    duration = _matched(gain, relaxed, lower, np.where(lower > 0, upper, 0.0), near)
    duration = np.where(lower > 0, np.maximum(duration, t_min), 0.0)
    return duration, {"mismatch": gain @ duration - relaxed, "relaxed": relaxed}


def _matched(gain, target, lower_s, upper_s, near_s=None):
    """min sum s + TIE (sum d or sum |d - near|) over lower <= d <= upper, s >= |gain d - target|;
    variables [d, s, t >= |d - near|]."""
    m, p = gain.shape
    eye_m = np.eye(m)
    a_ub = np.block([[gain, -eye_m], [-gain, -eye_m]])
    b_ub = np.r_[target, -target]
    cost = np.r_[np.full(p, 0.0 if near_s is not None else TIE), np.ones(m)]
    bounds = list(zip(lower_s, upper_s)) + [(0, None)] * m
    return _durations_lp(cost, a_ub, b_ub, bounds, near_s, TIE, "Problem 7's program failed")[:p]


def _least_firing(rows, offset, box_rad, lower_s, upper_s, near_s=None):
    """min sum d (+ PROX sum |d - near|) over lower <= d <= upper with |offset + rows d| <= box, rows in rad per
    s of firing (scaled to a unit largest entry each); variables [d, t >= |d - near|]."""
    p = len(lower_s)
    scale = np.max(np.abs(rows), axis=1, initial=0.0)
    keep = scale > 0
    a = rows[keep] / scale[keep, None]
    a_ub = np.vstack([a, -a])
    b_ub = np.r_[(box_rad - offset[keep]) / scale[keep], (box_rad + offset[keep]) / scale[keep]]
    cost, bounds = np.ones(p), list(zip(lower_s, upper_s))
    return _durations_lp(cost, a_ub, b_ub, bounds, near_s, PROX, "the scheduled pulses cannot hold the box")[:p]


def _durations_lp(cost, a_ub, b_ub, bounds, near_s, weight, failure: str):
    """The solution x of min cost x, a_ub x <= b_ub within ``bounds`` (HiGHS), with ``weight`` per unit of
    |d - near| added where ``near_s`` is given (d: x's first len(near_s) entries); ``failure`` names a refusal."""
    if near_s is not None:
        a_ub, b_ub, cost, bounds = _plus_nearness(a_ub, b_ub, cost, bounds, near_s, weight)
    result = scipy.optimize.linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if result.status != 0:
        raise ValueError(f"operational: {failure} ({result.message})")
    return result.x


def _plus_nearness(a_ub, b_ub, cost, bounds, near_s, weight):
    """An LP over [d, ...] (d the first len(near_s) variables) extended by t >= |d - near| at ``weight`` per
    unit of t: the rows d - t <= near and -d - t <= -near, and the columns t >= 0."""
    p, n = len(near_s), a_ub.shape[1]
    pick = np.eye(p, n)  # d out of the variables
    eye = np.eye(p)
    a_ub = np.block([[a_ub, np.zeros((len(a_ub), p))], [pick, -eye], [-pick, -eye]])
    return a_ub, np.r_[b_ub, near_s, -near_s], np.r_[cost, np.full(p, weight)], bounds + [(0, None)] * p


def _room_s(pulses: Pulses, horizon_s: float, constraints: Constraints) -> np.ndarray:
    """How much longer each pulse may fire about its centre [P] (s) so that, however its neighbours grow by
    their own room, (iii), (iv) and (14) still hold: the least slack on either side, each pair's slack shared."""
    p = len(pulses.centre_s)
    start = pulses.centre_s - pulses.duration_s / 2
    end = pulses.centre_s + pulses.duration_s / 2
    need = np.where(pulses.thruster[:, None] == pulses.thruster[None, :], constraints.t_same_gap_s,
                    constraints.t_other_gap_s)
    slack = start[None, :] - end[:, None] - need  # [a, b]: b after a
    later = pulses.centre_s[None, :] > pulses.centre_s[:, None]
    after = np.min(np.where(later, slack, np.inf), axis=1, initial=np.inf) / 2  # shared with b
    before = np.min(np.where(later.T, slack.T, np.inf), axis=1, initial=np.inf) / 2
    edges = np.minimum(start, horizon_s - end)
    room = 2 * np.minimum(np.minimum(after, before), edges)  # grows by room / 2 on each side
    return np.maximum(room, 0.0) if p else room


@jax.jit
def linear_response(model: SlotModel, du0_rsw, columns):
    """(lon, lat) deviations at every step start of a per-step Delta-V change du0 [N, 3] (m/s) and of each
    column [N, 3, P] (per unit of its variable), through ``model``'s x_{k+1} = Phi dx_k + B du_k,
    y = C dx_k + E du_k (``bound.linear``, one step per slot).  Returns y0 [N, T, 2] and gain [N, T, 2, P]."""
    inputs = jnp.concatenate([du0_rsw[:, :, None], columns], axis=2)  # [N, 3, 1 + P]

    def one(dx, xs):
        phi, b, c, e, du = xs
        return phi @ dx + b @ du, jnp.einsum("toj,jp->top", c, dx) + jnp.einsum("toj,jp->top", e, du)

    _, y = jax.lax.scan(one, jnp.zeros((6, inputs.shape[2])), (model.phi, model.b, model.c, model.e, inputs))
    return y[..., 0], y[..., 1:]


def linear_model(scenario, u_rsw_mps) -> tuple[SlotModel, float]:
    """The linear model of ``scenario`` (the uncontrolled closed loop's forces and steps, one step per slot)
    about the per-step plan ``u_rsw_mps`` [N, 3], numpy leaves; and the step (s).  Its ``y`` is the plan's
    nonlinear flight (no mass flow)."""
    batch = prepare([_uncontrolled(scenario)])
    params = unstack(batch.params, 0)
    env = batch.shared.env
    n = env.earth_angle_rad.shape[0] * env.earth_angle_rad.shape[1]
    env_steps = jax.tree_util.tree_map(lambda x: x.reshape((n, 1) + x.shape[2:]), env)
    model = linearize(params.initial.orbit, jnp.asarray(u_rsw_mps), env_steps, params.forces,
                      jnp.full(n, params.initial.mass_kg), params.station["lon_rad"], slot_s=batch.step_s,
                      step_s=batch.step_s, dynamics=batch.dynamics)
    return jax.tree_util.tree_map(np.asarray, model), float(batch.step_s)
