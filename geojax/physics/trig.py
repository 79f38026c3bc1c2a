"""Cosine and sine of per-sample angles in plain XLA arithmetic.

XLA's CPU compiler evaluates float64 ``cos`` and ``sin`` one element at a time
(about 13 ns for the pair per element, measured on 1024 lanes); the same
functions written as a range reduction and two polynomials are elementwise
multiply-adds that it vectorises and fuses (about 2.4 ns for the pair).  The
MEE step evaluates cos L and sin L of every sample at every RK4 stage; with
these it needs no fusion boundary for them either (``physics.dynamics.mee_rhs``).

The kernels are fdlibm's (``e_rem_pio2.c``, ``k_sin.c``, ``k_cos.c``, Sun
Microsystems 1993, as in every libm derived from it): the angle is reduced by
pi/2 split in three parts of 33 bits, so n pi/2 is exact for |n| < 2^20 (angles
up to 1.6e6 rad, 4,500 years of a GEO true longitude), and the remainder in
[-pi/4, pi/4] goes through the minimax polynomials.  The result is within 2 ulp
of numpy's libm over that range, 1 ulp below 10 rad (``tests/test_trig.py``).  Beyond it the error grows as
n x 8.5e-32; no orbit in the engine comes near.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

# pi/2 = PIO2_1 + PIO2_2 + PIO2_3 + O(1e-31), the first two with 33 significant bits (fdlibm e_rem_pio2.c).
PIO2_1 = 1.57079632673412561417e+00
PIO2_2 = 6.07710050630396597660e-11
PIO2_3 = 2.02226624871116645580e-21
# sin r = r + r^3 (S1 + r^2 S2 + ...), cos r = 1 - r^2/2 + r^4 (C1 + r^2 C2 + ...) on |r| <= pi/4 (k_sin.c, k_cos.c).
SIN_COEFFICIENTS = (-1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04,
                    2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10)
COS_COEFFICIENTS = (4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05,
                    -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11)


@jax.custom_jvp
def sincos(angle_rad):
    """(cos, sin) of ``angle_rad`` (any shape), elementwise; derivatives (-sin, cos)."""
    n = jnp.round(angle_rad * (2 / np.pi))
    r = ((angle_rad - n * PIO2_1) - n * PIO2_2) - n * PIO2_3
    z = r * r
    sin_r = r + r * z * _horner(SIN_COEFFICIENTS, z)
    half_z = 0.5 * z
    w = 1.0 - half_z
    cos_r = w + (((1.0 - w) - half_z) + z * z * _horner(COS_COEFFICIENTS, z))  # k_cos.c's split of 1 - z/2
    quadrant = n - 4 * jnp.floor(0.25 * n)  # n mod 4, as a float
    odd = (quadrant == 1) | (quadrant == 3)
    cos_a = jnp.where(odd, sin_r, cos_r)
    sin_a = jnp.where(odd, cos_r, sin_r)
    return (jnp.where((quadrant == 1) | (quadrant == 2), -cos_a, cos_a),
            jnp.where(quadrant >= 2, -sin_a, sin_a))


@sincos.defjvp
def _sincos_jvp(primals, tangents):
    (angle,), (d_angle,) = primals, tangents
    cos_a, sin_a = sincos(angle)
    return (cos_a, sin_a), (-sin_a * d_angle, cos_a * d_angle)


def _horner(coefficients, z):
    acc = coefficients[-1]
    for c in coefficients[-2::-1]:
        acc = acc * z + c
    return acc
