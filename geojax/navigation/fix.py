"""Li 2022's Gaussian fix, the navigation part's first model (``navigation.model = "gaussian_fix"``): at each cycle
start the controller is told the true position and velocity with Gaussian errors of the sizes
``errors.sigma3_r_m`` and ``errors.sigma3_v_mps`` (3 sigma per component; ``errors.h_rv`` their preset, Li 2022
eqs. (47)-(48)).  It carries no state, so the loop draws it itself wherever no part of the loop navigates
(``StateModel.navigates``: the extended Kalman filter, ``states.navigation``, the part's second model): the draw
is row 0 of ``normal(key_k, (2, 6))``, the cycle's key (row 1: the burns' pointing errors)."""

from __future__ import annotations


from geojax.physics.elements import cartesian_to_mee, wrap_angle


def fix_mee(true_mee, r, v, noise, errors: dict, mu):
    """The fix as MEE from the true state (its MEE ``true_mee`` [6], ECI ``r``, ``v`` [3]) and ``noise`` [6] ~
    N(0, 1): 1 sigma ``sigma3_r_m`` / 3 per position component, ``sigma3_v_mps`` / 3 per velocity component; the
    true longitude kept continuous (``cartesian_to_mee`` wraps it)."""
    r = r + errors["sigma3_r_m"] / 3 * noise[:3]
    v = v + errors["sigma3_v_mps"] / 3 * noise[3:]
    fix = cartesian_to_mee(r, v, mu)
    return fix.at[5].set(true_mee[5] + wrap_angle(fix[5] - true_mee[5]))
