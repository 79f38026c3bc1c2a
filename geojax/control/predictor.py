"""State predictor (Li 2022, Sec. 4.1, eqs. (24)-(27)) and the mean-element estimate it starts from.

Uncontrolled propagations (``geojax.runner.setup.reference``: the closed loop
with the null controller), done once per scenario and shared by a batch, give
at every cycle boundary the osculating elements and the mean elements
(eq. (9)).  From them:

* the natural drift of the mean elements over a cycle, Delta x_d (eq. (26)),
  is the change of the reference's boundary means;
* the controller's estimate of the mean elements at a boundary is the
  osculating elements of the (measured) state less the reference's
  short-period offset (osculating minus mean) at that boundary.  The offsets
  come from the Sun, Moon, J2 and SRP and hardly depend on the small
  differences between the controlled orbit and the reference, as long as the
  eccentricity term is taken out of the longitude first (``boundary_elements``).

Both hold only while the reference stays near the controlled orbit.  One
uncontrolled run from the initial state does not: its inclination grows by
~0.9 deg a year, and the lunisolar and J2 precession of a 2-3 deg orbit turns
the inclination drift by ~4 deg/yr x i, so the drift it predicts in a run's
third year is no longer the controlled satellite's.  The reference is therefore
re-started from the station's nominal state (``station_mee``) every
``runner.setup.REFERENCE_SEGMENT_CYCLES`` cycles; each cycle reads the segment it
falls in (``Reference``).

Boundary means are the average of the two cycle means around a boundary
(the cycle means refer to mid-cycle times).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.physics.elements import semi_major_axis_m, wrap_angle


class Reference(NamedTuple):
    """What the predictor reads at each control cycle k (leading axis = cycle): the uncontrolled reference
    segment that cycle k falls in, at boundary k and the ``width - 1`` boundaries after it."""

    osc: jnp.ndarray  # [n_cycles, 6] osculating (lon, a, f, g, h, k) at boundary k, lon as in ``boundary_elements``
    window: jnp.ndarray  # [n_cycles, width, 7] mean (lon, drift rad/s, a, f, g, h, k) at boundaries k .. k + width - 1


def station_mee(station: dict, p_m, earth_angle_rad):
    """Osculating MEE [6] (p m, f, g, h, k, L rad) of the station's nominal orbit at an Earth angle: the
    targets' e and i vectors (MEE (f, g), (h, k)), semi-latus rectum ``p_m``, and the mean longitude at the
    station's longitude (``boundary_elements``' l = L - 2 f sin L + 2 g cos L inverted to first order in e)."""
    mean_lon = station["lon_rad"] + earth_angle_rad
    f, g = station["ex"], station["ey"]
    true_lon = mean_lon + 2 * f * jnp.sin(mean_lon) - 2 * g * jnp.cos(mean_lon)
    return jnp.stack([p_m, f, g, station["ix"], station["iy"], true_lon])


def boundary_elements(mee, earth_angle_rad):
    """(lon, a, f, g, h, k) of an osculating MEE state [6].

    lon is the mean longitude less the Earth angle; the mean longitude removes
    the state's own eccentricity term from the true longitude,
    l = L - 2 f sin L + 2 g cos L + O(e^2).
    """
    true_lon = mee[5]
    lon = wrap_angle(true_lon - 2 * mee[1] * jnp.sin(true_lon) + 2 * mee[2] * jnp.cos(true_lon) - earth_angle_rad)
    return jnp.stack([lon, semi_major_axis_m(mee), mee[1], mee[2], mee[3], mee[4]])


def estimate_mean(osc, osc_ref, mean_ref, mu):
    """Mean (lon, drift, e_x, e_y, i_x, i_y) at a boundary from osculating (lon, a, f, g, h, k).

    The drift follows the mean semi-major axis: d(lambda_dot)/da = -3/2 n / a.
    """
    lon = wrap_angle(osc[0] - (osc_ref[0] - mean_ref[0]))
    a = osc[1] - (osc_ref[1] - mean_ref[2])
    drift = mean_ref[1] - 1.5 * jnp.sqrt(mu / a**3) / a * (a - mean_ref[2])
    return jnp.concatenate([jnp.stack([lon, drift]), osc[2:] - (osc_ref[2:] - mean_ref[3:])])


def predict_next(estimate, mean_ref, mean_ref_next, cycle_s):
    """Eq. (25) without burns: the estimate plus the natural drift of one cycle (eqs. (26)-(27))."""
    d_drift = mean_ref_next[1] - mean_ref[1]
    lon = estimate[0] + cycle_s * (estimate[1] + 0.5 * d_drift)
    return jnp.concatenate([jnp.stack([lon, estimate[1] + d_drift]), estimate[2:] + (mean_ref_next[3:] - mean_ref[3:])])
