"""Cosine, sine, tangent and arc tangents of per-sample values in plain XLA arithmetic.

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

The same holds for ``atan2`` (about 15 ns per element against 2-3 in plain arithmetic): the sub-satellite
longitude and latitude of every sample at every step and the QFFC's burn nodes (``control.qffc``), solved
thousands of times per cycle by the FOMPC's annealing, go through ``atan2`` below, fdlibm's ``e_atan2.c``
and ``s_atan.c``: |y / x| reduced to one of five intervals and an odd polynomial of degree 21, within 1 ulp
of libm (``tests/test_trig.py``).

``tan`` and ``atan`` are here for the batch's width: XLA:CPU's own float64 ``tan`` and ``atan`` take a
vectorised path for the elements of a loop that fill a vector and libm's for the rest, and the two differ in the
last bit (measured: ``jnp.arctan`` over a [288, 70] array against [10080, 2], 271 of 20160 values apart; ``jnp.tan``
in a scalar loop against a vector, 656 of 2000), so a sample's value depended on how many lanes it was batched
with. Built from ``sincos`` and ``atan2``'s kernel, each is the same plain arithmetic in every lane.
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


@jax.custom_jvp
def atan2(y, x):
    """The angle of (x, y) in [-pi, pi], elementwise, with ``numpy.arctan2``'s signs and special values (zeros,
    infinities); derivatives (x dy - y dx) / (x^2 + y^2)."""
    ax, ay = jnp.abs(x), jnp.abs(y)
    both_inf = jnp.isinf(ax) & jnp.isinf(ay)
    # atan(|y| / |x|) in [0, pi/2] (0 / 0 read as 0, inf / inf as 1: the angles of (+-0, +-0) and (+-inf, +-inf))
    t = jnp.where(both_inf, 1.0, ay / jnp.where((ax == 0) & (ay == 0), 1.0, ax))
    z = _atan_nonnegative(t)
    # e_atan2.c: pi - (z - pi_lo) for x < 0 (signbit: -0 counts), except where |y / x| > 2^60 (x = 0
    # included): there the angle is pi/2 whatever the sign of x; then the sign of y
    z = jnp.where(jnp.signbit(x) & (t <= 2.0**60), PI_HI - (z - PI_LO), z)
    return jnp.where(jnp.signbit(y), -z, z)


@atan2.defjvp
def _atan2_jvp(primals, tangents):
    (y, x), (dy, dx) = primals, tangents
    r2 = x * x + y * y
    return atan2(y, x), (x * dy - y * dx) / jnp.where(r2 > 0, r2, 1.0)


def tan(angle_rad):
    """tan ``angle_rad`` as sin / cos of ``sincos`` (within 3 ulp of libm below 1.5 rad; the same at every width)."""
    cos_a, sin_a = sincos(angle_rad)
    return sin_a / cos_a


@jax.custom_jvp
def atan(t):
    """atan ``t`` in [-pi/2, pi/2], elementwise (fdlibm's ``s_atan.c``, as ``atan2``); derivative 1 / (1 + t^2)."""
    z = _atan_nonnegative(jnp.abs(t))
    return jnp.where(jnp.signbit(t), -z, z)


@atan.defjvp
def _atan_jvp(primals, tangents):
    (t,), (dt,) = primals, tangents
    return atan(t), dt / (1.0 + t * t)


# s_atan.c: atan(t) = ATAN_HI[i] + atan((t - c_i) / (1 + c_i t)) on five intervals of t >= 0 (c = 1/2, 1, 3/2,
# inf); atan(r) = r - r^3 (T0 + r^2 T1 + ...) for |r| <= 7/16.
ATAN_HI = (4.63647609000806093515e-01, 7.85398163397448278999e-01, 9.82793723247329054082e-01,
           1.57079632679489655800e+00)
ATAN_LO = (2.26987774529616870924e-17, 3.06161699786838301793e-17, 1.39033110312309984516e-17,
           6.12323399573676603587e-17)
ATAN_COEFFICIENTS = (3.33333333333329318027e-01, -1.99999999998764832476e-01, 1.42857142725034663711e-01,
                     -1.11111104054623557880e-01, 9.09088713343650656196e-02, -7.69187620504482999495e-02,
                     6.66107313738753120669e-02, -5.83357013379057348645e-02, 4.97687799461593236017e-02,
                     -3.65315727442169155270e-02, 1.62858201153657823623e-02)
PI_HI = 3.1415926535897931160e+00  # pi = PI_HI + PI_LO
PI_LO = 1.2246467991473531772e-16


def _atan_nonnegative(t):
    """atan(t) for t >= 0 (or NaN), s_atan.c's reduction and polynomial, branch-free.

    The interval picks its constants with ``lax.select_n`` on the interval index, elementwise (``jnp.select``
    finds the first true condition with a reduction, which XLA compiles as a kernel of its own).
    """
    interval = ((t >= 0.4375).astype(jnp.int32) + (t >= 0.6875) + (t >= 1.1875) + (t >= 2.4375))
    pick = lambda *cases: jax.lax.select_n(interval, *jnp.broadcast_arrays(*cases))  # noqa: E731
    # the reduced argument (t - c) / (1 + c t) as s_atan.c writes it per interval (interval 0: t itself)
    one = jnp.ones_like(t)
    r = pick(t, 2.0 * t - 1.0, t - 1.0, t - 1.5, -one) / pick(one, 2.0 + t, t + 1.0, 1.0 + 1.5 * t, t)
    z = r * r
    w = z * z
    odd, even = ATAN_COEFFICIENTS[0::2], ATAN_COEFFICIENTS[1::2]
    s = z * _horner(odd, w) + w * _horner(even, w)
    hi = pick(*(jnp.full_like(t, c) for c in (0.0, *ATAN_HI)))
    lo = pick(*(jnp.full_like(t, c) for c in (0.0, *ATAN_LO)))
    return jnp.where(interval == 0, r - r * s, hi - ((r * s - lo) - r))


def _horner(coefficients, z):
    acc = coefficients[-1]
    for c in coefficients[-2::-1]:
        acc = acc * z + c
    return acc
