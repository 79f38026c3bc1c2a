"""Quick feedforward controller (Li 2022, Sec. 4.2, eqs. (28)-(39)): the cycle model and the controller.

``model_cycle`` plans one cycle on the predictor model (eq. (25)): the predictive deviation of eq. (28), the
drift goal of eqs. (37)-(38) (``estimated_drift_rad_s``), and the burn pair of ``geojax.control.qffc_solve``
(eqs. (29)-(36)); the QFFC flies it every cycle with the full inclination correction, the FOMPC (``fompc``)
N times per candidate sequence of north-south corrections.  The solver's names are re-exported here.
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp

from geojax.control import around_passes
from geojax.control import burn_metrics
from geojax.control import burns as burns_mod
from geojax.control.base import Controller, Sizing, Spec, stateless_init
from geojax.control.effects import R_SYNC_M, V_SYNC_MPS, cycle_coast_s, effect_columns, remaining_fraction
from geojax.control.predictor import predict_next
from geojax.states.base import STATION_PASSES
from geojax.physics.elements import wrap_angle
from geojax.params import LOG, NUMBER, Field, station_target
from geojax.physics.propulsion import arm_limits
from geojax.physics.trig import atan2, sincos
from geojax.control.qffc_solve import (ArmTrig, BurnPair, _log_at_least_one, _stage, arm_trig, default_raise_index,
                                       default_vdt_raises, full_correction_mps, solve)

# The solver's names (``qffc_solve``) are the QFFC's too: ``qffc.solve``, ``qffc.BurnPair`` ...
__all__ = ["ArmTrig", "BurnPair", "CONTROLLER", "FIELDS", "SPEC", "_log_at_least_one", "arm_trig", "default_raise_index",
           "default_vdt_raises", "effect", "estimated_drift_rad_s", "full_correction_mps", "make", "model_cycle",
           "model_inputs", "solve", "needs", "around_passes_plan", "around_passes_of"]

# The [controller] keys of Li 2022's planners.  The QFFC reads vdt_estimate only; it accepts the FOMPC's keys
# (and ignores them) so that one scenario and one sweep file run both controllers on the same grid.
THRUSTERS = (2, "Li 2022's two robotic arms, one burn each per cycle")  # control.base: honoured or refused
# thrusters.count may also be 4: two per arm (thrusters k and k + 2 on arm k), ``control.burns`` allocating
REDUNDANT_THRUSTERS = 4

FIELDS = {
    # Start V_DT from the estimate of Li 2022, eqs. (37)-(39), instead of the drift target.
    "vdt_estimate": Field(bool, False, si="vdt_estimate"),
    # FOMPC (Li 2022, eqs. (40)-(42)): horizon N <= 10 cycles, Delta i_max in MEE (h, k), penalty P in
    # (m/s)^2 per unit (h, k)^2; simulated annealing with `chains` chains of `iterations` moves.
    "horizon": Field(int, 6, lower=1, upper=11, lower_inclusive=True, si="horizon", symbol="horizon N",
                     unit="cycles"),
    "di_max": Field(NUMBER, 8e-5, lower=0.0, si="di_max", transform=LOG, symbol="Δi_max", unit=""),
    "penalty": Field(NUMBER, 1e8, lower=0.0, si="penalty", transform=LOG),
    # The power of each burn's Delta-V in J: 2 as eq. (42) prints it (V_1k^2 + V_2k^2); 1 scores the fuel itself.
    "dv_exponent": Field(NUMBER, 2.0, lower=1.0, upper=3.0, lower_inclusive=True, si="dv_exponent"),
    "chains": Field(int, 8, lower=1, upper=1025, lower_inclusive=True, static=True),
    "iterations": Field(int, 64, lower=0, upper=100001, lower_inclusive=True, static=True),
    # Move both burn nodes off eq. (31)'s by the least shift that keeps the burns out of the stations' passes
    # (``control.around_passes``; needs navigation.model = "ekf" with stations); the FOMPC for its flown cycle.
    "around_passes": Field(bool, False, static=True),
}


def estimated_drift_rad_s(next_deviation, l_start_rad):
    """The drift to leave at the end of a cycle, eqs. (37)-(38) with the corrected B.

    ``next_deviation`` is the predictive deviation of the *next* cycle as the
    natural drift alone will make it (e and i: minus their natural change over
    that cycle).  Eq. (37) asks which V_L that cycle could absorb with V_DT = 0
    and both radial components inward: with the longitude row of
    ``control.effects`` (T_i / R_s = 2 pi c_i / V_s) eq. (35) reads
    V_L - 3 pi / 2 [(c_1 + c_2) V_DT + (c_1 - c_2) V_ET] + |V_R| <= 0, so
    V~_L = 3 pi / 2 (c_1 - c_2) V_ET - |V_R|.  A drift lambda_dot moves the
    longitude by -d lambda = lambda_dot T_s over that cycle, which asks for
    V_L = -V_s / 2 d lambda = pi R_s lambda_dot (eq. (38) prints 2 / R_s, without
    the 2 pi of T_s = 2 pi R_s / V_s, the same slip as in eq. (22)).
    """
    dex, dey, dix, diy = (next_deviation[j] for j in range(2, 6))
    v_s = V_SYNC_MPS
    l2 = atan2(diy, dix)
    l1 = l2 - jnp.pi
    cos_l2, sin_l2 = sincos(l2)
    cos_l1, sin_l1 = -cos_l2, -sin_l2
    v_r = v_s * (dex * sin_l1 - dey * cos_l1)
    v_et = 0.5 * v_s * (dex * cos_l1 + dey * sin_l1)
    c1, c2 = remaining_fraction(l1, l_start_rad), remaining_fraction(l1 + jnp.pi, l_start_rad)
    v_l = 1.5 * jnp.pi * (c1 - c2) * v_et - jnp.abs(v_r)
    return v_l / (jnp.pi * R_SYNC_M)


def effect(burns: BurnPair, l_start_rad, coast_offset_s=0.0):
    """B_1 v_1 + B_2 v_2 (eq. (29)) of a solution, for checking it."""
    return jnp.stack(_effect_terms(*_effect_inputs(burns, l_start_rad, coast_offset_s)))


def _dv_rows(burns: BurnPair):
    """The burns' components, ((v_r, v_t, v_n) of thruster 1, then of thruster 2)."""
    return tuple(tuple(burns.dv_rsw_mps[n, j] for j in range(3)) for n in range(2))


def _effect_inputs(burns: BurnPair, l_start_rad, coast_offset_s=0.0):
    """``_effect_terms``'s arguments for a solution."""
    coast = cycle_coast_s(burns.l_rad, l_start_rad) + coast_offset_s
    return _dv_rows(burns), (burns.l_rad[0], burns.l_rad[1]), (coast[0], coast[1])


def _effect_terms(dv_rows, l_rad, coast_s):
    """B_1 v_1 + B_2 v_2 as a tuple of six, from the burns' components ``dv_rows`` ((v_r, v_t, v_n) per
    thruster), nodes and coasts (pairs).  Term by term (no matrix, no dot): inside a vmapped planner a
    [2, 6, 3] B is a kernel of its own that evaluates the trigonometry per entry, and a dot_general adds
    transposes around it."""
    total = [0.0] * 6
    for n in range(2):
        columns = effect_columns(*sincos(l_rad[n]), coast_s[n])
        for j in range(3):
            total = [t if isinstance(b, float) and b == 0 else t + b * dv_rows[n][j]
                     for t, b in zip(total, columns[j])]
    return tuple(total)


def model_cycle(x_prev, ref_window, target, l_start_rad, limits, cycle_s, vdt_estimate=0.0, v_n_fraction=None,
                anchor=None, node_shift_rad=None):
    """Plan one cycle on the predictor model: eq. (25) with the QFFC's solution (eqs. (25)-(40)).

    Both planners use it: the QFFC once per cycle with the full inclination
    correction, the FOMPC N times per candidate sequence of north-south
    corrections (eq. (41)).  ``x_prev`` [6] is the mean state at the cycle's
    start; ``ref_window`` [3, 7] the uncontrolled reference's mean (lon, drift,
    a, f, g, h, k) at the cycle's start boundary and the two after it: the
    natural drift of this cycle (eqs. (26)-(27)) and of the next one (for the
    V_DT estimate of eqs. (37)-(39)).  ``vdt_estimate`` (0 or 1, or a blend)
    sets the drift goal: 0 cancels the drift (target drift), 1 leaves the drift
    of eqs. (37)-(38).  ``v_n_fraction`` scales the north-south correction (the
    FOMPC's action, eq. (40)): |V_N| = fraction * 2 V_s |di|; ``None`` is the
    QFFC's full correction.  ``anchor``: see ``solve``.  ``node_shift_rad`` moves both burn nodes
    (``control.around_passes``): the north-south correction is then the deviation's projection on the moved
    nodes' line, cos(shift) x |V_N|.

    Returns (prediction without burns [6], BurnPair, predicted state after the burns [6]).
    An infeasible cycle flies nothing (eq. (40): S = 0).
    """
    prediction = predict_next(x_prev, ref_window[0], ref_window[1], cycle_s)
    prediction = prediction.at[0].set(wrap_angle(prediction[0]))
    deviation = target - prediction  # eq. (28)
    next_deviation = jnp.zeros(6).at[2:].set(ref_window[1, 3:] - ref_window[2, 3:])
    drift_goal = target[1] + vdt_estimate * (estimated_drift_rad_s(next_deviation, l_start_rad) - target[1])
    deviation = deviation.at[0].set(wrap_angle(deviation[0])).at[1].set(drift_goal - prediction[1])
    v_n = None if v_n_fraction is None else v_n_fraction * full_correction_mps(deviation)
    if node_shift_rad is not None:
        v_n = jnp.cos(node_shift_rad) * (full_correction_mps(deviation) if v_n is None else v_n)
    burns, coast = solve(deviation, l_start_rad, limits, v_n_mps=v_n, anchor=anchor, with_coast=True,
                         node_shift_rad=node_shift_rad)
    effect_terms = _stage(lambda b, coast: _effect_terms(_dv_rows(b), (b.l_rad[0], b.l_rad[1]), coast), burns, coast,
                          anchor=anchor)
    after = prediction + jnp.where(burns.feasible, jnp.stack(effect_terms), 0.0)
    return prediction, burns, after.at[0].set(wrap_angle(after[0]))


def model_inputs(params, estimate, context):
    """The arguments of ``model_cycle`` that a planner reads from the loop: (x, window, target, l, limits, cycle, vdt)."""
    return (estimate.mean, context.reference, station_target(params.station), estimate.fix_mee[5],
            arm_limits(params.thrusters), context.cycle_s, params.controller["vdt_estimate"])


def _plan(params, controller_state, estimate, context, key):
    prediction, burns, _ = model_cycle(*model_inputs(params, estimate, context))
    return burns_mod.fly(params, burns, prediction, jnp.asarray(1.0), estimate, context, key), controller_state


def needs(config: dict) -> dict:
    """``controller.around_passes`` plans around the tracking stations' passes, which a part must tell
    (``states.base.STATION_PASSES``)."""
    if config["controller"]["around_passes"]:
        return {STATION_PASSES: "controller.around_passes: plans the burns around the stations' passes"}
    return {}


SPEC = Spec(FIELDS, None, THRUSTERS, REDUNDANT_THRUSTERS, needs=needs)

# Reads the reference at the cycle's start boundary and the two after it (``model_cycle``).
# Widths and memory (``geojax.lanes``): 128 lanes per CPU core (simulated years/s over 30 days on one pinned core: 77 at
# 64 lanes, 89 at 128, 100 at 256); XLA's memory_analysis at 64 lanes, 10 and 40 cycles: 15.6 and 21.3 kB per lane.
CONTROLLER = Controller(stateless_init, _plan, burns_mod.thrust, SPEC, reference_cycles=3, record=burns_mod.record, metrics=burn_metrics.metrics,
                        sizing=Sizing(lanes_cpu=128, working_bytes=16_000))


def around_passes_plan(params, estimate, context, inputs, plain: BurnPair, v_n_fraction=None):
    """(prediction, burns) of the cycle with its burn nodes moved off the passes (``control.around_passes``): the
    burns ``plain`` planned at eq. (31)'s nodes give their durations (eq. (13)), the least clear shift, then the
    plan at the moved nodes (``inputs``: ``model_inputs``; ``v_n_fraction``: the FOMPC's, None for the QFFC's full
    correction)."""
    burn_s = jnp.where(plain.feasible, plain.v_mps * estimate.mass_kg / params.thrusters["thrust_n"], 0.0)
    shift, _ = around_passes.node_shift_rad(plain.l_rad[1], estimate.fix_mee[5], estimate.t_s, context.cycle_s,
                                            burn_s, context.step_s, estimate.states[STATION_PASSES])
    prediction, burns, _ = model_cycle(*inputs, v_n_fraction=v_n_fraction, node_shift_rad=shift)
    return prediction, burns


def _plan_around_passes(params, controller_state, estimate, context, key):
    """The QFFC with its burn nodes moved off the passes (``around_passes_plan``)."""
    inputs = model_inputs(params, estimate, context)
    _, plain, _ = model_cycle(*inputs)
    prediction, burns = around_passes_plan(params, estimate, context, inputs, plain)
    plan = burns_mod.fly(params, burns, prediction, jnp.asarray(1.0), estimate, context, key)
    return plan, controller_state


CONTROLLER_AROUND_PASSES = dataclasses.replace(CONTROLLER, plan=_plan_around_passes)


def around_passes_of(tables: list[dict]) -> bool:
    """``around_passes`` of a batch's ``[controller]`` tables (static: one value per sweep)."""
    chosen = {bool(t["around_passes"]) for t in tables}
    if len(chosen) > 1:
        raise ValueError("controller.around_passes: sets the compiled planner; one value per sweep, got both")
    return chosen.pop()


def make(tables: list[dict]) -> Controller:
    """The QFFC, or the QFFC planning around the passes (``around_passes``)."""
    return CONTROLLER_AROUND_PASSES if around_passes_of(tables) else CONTROLLER
