"""Linear effect of a short burn on the mean GEO elements: Li 2022, eqs. (15)-(22), re-derived.

The state is x = (lambda, lambda_dot, e_x, e_y, i_x, i_y) with (e_x, e_y) = (f, g)
and (i_x, i_y) = (h, k) of the modified equinoctial elements (Li 2022, Sec. 3.1),
lambda in rad, lambda_dot in rad/s.  A burn with velocity increment
v = (v_r, v_t, v_n) (m/s, RSW) at right ascension l, followed by T_i seconds of
coasting to the end of the cycle, changes x by B(l, T_i) v.

Derivation, from the Gauss equations in MEE (Li 2022, eq. (6)) at e = i = 0,
p = R_s, w = 1, s^2 = 1, with V_s = sqrt(mu / R_s):

* f' = (a_r sin L + 2 a_t cos L) / V_s and g' = (-a_r cos L + 2 a_t sin L) / V_s,
  as eqs. (16c)-(16d): rows 3-4 of eq. (22) hold as printed.
* h' = s^2 a_n cos L / (2 w V_s) = a_n cos L / (2 V_s), likewise k'.  The factor
  1/2 of eq. (22) rows 5-6 is right *for MEE (h, k) = tan(i/2) (cos, sin)*; eqs.
  (16e)-(16f) without it describe the classical vector i (cos Omega, sin Omega).
* a' = 2 a_t / n (eq. (16a)), so the mean motion changes by
  dn = -3/2 (n / a) da = -3 v_t / R_s (eq. (19)), and lambda_dot with it.
* lambda = l - theta_G; an impulse changes the mean longitude directly by
  -2 v_r / V_s (eq. (16b)), and the new drift accumulates dn T_i until the
  cycle ends, so d lambda = -2 v_r / V_s - 3 v_t T_i / R_s.  With T_i = c_i T_s
  (eq. (20)) and T_s = 2 pi R_s / V_s (a sidereal day, the GEO period) this is
  -2 v_r / V_s - 6 pi c_i v_t / V_s.  Eq. (22) prints -3 c_i / V_s for the
  v_t entry, i.e. it drops the factor 2 pi = V_s T_s / R_s; we keep it, since
  the closed form is what the dynamics give (``tests/test_control_effects.py``
  checks every row against the propagated orbit).

Sign of the north-south pair: with l_2 = l_1 + pi (eq. (31)), eq. (30) gives
(delta i_x, delta i_y) = (v_n1 - v_n2) (cos l_1, sin l_1) / (2 V_s), so the
combination fixed by the inclination target is v_n1 - v_n2, not the printed
v_n1 + v_n2 of eq. (32e); with v_n1 <= 0 <= v_n2 (eq. (14) with eq. (1)) both
thrusters add their north-south Delta-V.
"""

from __future__ import annotations

import jax.numpy as jnp

from geojax.physics.constants import MU_EARTH_M3_S2, OMEGA_EARTH_RAD_S, SIDEREAL_DAY_S
from geojax.physics.trig import sincos

R_SYNC_M = (MU_EARTH_M3_S2 / OMEGA_EARTH_RAD_S**2) ** (1 / 3)  # Keplerian synchronous radius R_s
V_SYNC_MPS = (MU_EARTH_M3_S2 / R_SYNC_M) ** 0.5  # V_s


def effect_matrix(l_rad, coast_s, r_s=R_SYNC_M, v_s=V_SYNC_MPS):
    """B [..., 6, 3]: change of (lambda, lambda_dot, e_x, e_y, i_x, i_y) per unit (v_r, v_t, v_n)."""
    cos_l, sin_l = sincos(l_rad)
    coast = jnp.broadcast_to(coast_s, cos_l.shape)
    columns = effect_columns(cos_l, sin_l, coast, r_s, v_s)
    return jnp.stack([jnp.stack([jnp.broadcast_to(b, cos_l.shape) for b in column], -1) for column in columns], -1)


def effect_columns(cos_l, sin_l, coast_s, r_s=R_SYNC_M, v_s=V_SYNC_MPS):
    """The three columns of B (per unit v_r, v_t, v_n), each a tuple of six rows; a row that is zero is the
    Python 0.0, so that a caller summing B v term by term (``control.qffc.effect``) skips it."""
    return ((-2 / v_s, 0.0, sin_l / v_s, -cos_l / v_s, 0.0, 0.0),
            (-3 * coast_s / r_s, -3 / r_s, 2 * cos_l / v_s, 2 * sin_l / v_s, 0.0, 0.0),
            (0.0, 0.0, 0.0, 0.0, cos_l / (2 * v_s), sin_l / (2 * v_s)))


def remaining_fraction(l_rad, l_start_rad):
    """c_i of Li 2022, eq. (21): the fraction of the cycle left after a burn at right ascension l."""
    two_pi = 2 * jnp.pi
    return 1 - jnp.mod(l_rad - l_start_rad, two_pi) / two_pi


def cycle_coast_s(l_rad, l_start_rad):
    """T_i = c_i T_s, eq. (20)."""
    return remaining_fraction(l_rad, l_start_rad) * SIDEREAL_DAY_S
