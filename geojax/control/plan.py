"""One control cycle of the predictor model: eq. (25) with the QFFC's solution (Li 2022, eqs. (25)-(40)).

Both controllers plan with it: the QFFC runs it once per cycle with the full
inclination correction; the FOMPC runs it N times per candidate sequence of
north-south corrections (eq. (41)).  ``ref_window`` holds the uncontrolled
reference's mean elements (lon, drift, a, f, g, h, k) at the cycle's start
boundary and the two after it: the natural drift of this cycle (eqs. (26)-(27))
and of the next one (for the V_DT estimate of eqs. (37)-(39)).
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.control import qffc
from geojax.control.predictor import predict_next
from geojax.elements import wrap_angle


def model_cycle(x_prev, ref_window, target, l_start_rad, limits, cycle_s, vdt_estimate=0.0, v_n_fraction=None):
    """Plan one cycle from the mean state ``x_prev`` [6] at its start.

    ``vdt_estimate`` (0 or 1, or a blend) sets the drift goal: 0 cancels the
    drift (target drift), 1 leaves the drift of eqs. (37)-(38).
    ``v_n_fraction`` scales the north-south correction (the FOMPC's action,
    eq. (40)): |V_N| = fraction * 2 V_s |di|; ``None`` is the QFFC's full correction.

    Returns (prediction without burns [6], BurnPair, predicted state after the burns [6]).
    An infeasible cycle flies nothing (eq. (40): S = 0).
    """
    prediction = predict_next(x_prev, ref_window[0], ref_window[1], cycle_s)
    prediction = prediction.at[0].set(wrap_angle(prediction[0]))
    deviation = target - prediction  # eq. (28)
    next_deviation = jnp.zeros(6).at[2:].set(ref_window[1, 3:] - ref_window[2, 3:])
    drift_goal = target[1] + vdt_estimate * (qffc.estimated_drift_rad_s(next_deviation, l_start_rad) - target[1])
    deviation = deviation.at[0].set(wrap_angle(deviation[0])).at[1].set(drift_goal - prediction[1])
    v_n = None if v_n_fraction is None else v_n_fraction * qffc.full_correction_mps(deviation)
    burns = qffc.solve(deviation, l_start_rad, limits, v_n_mps=v_n)
    after = prediction + jnp.where(burns.feasible, qffc.effect(burns, l_start_rad), 0.0)
    return prediction, burns, after.at[0].set(wrap_angle(after[0]))
