"""The distance between two satellites: the closest approach within an integration step, and the linearised
relative motion of two near-geostationary orbits (the closed form the collocation checks compare with).

Within a step the relative position is the cubic Hermite interpolant of the relative positions and velocities
at the step's two ends.  The relative motion of two GEO satellites is a sinusoid of one sidereal day, so the
cubic's error is at most step^4 / 384 x omega^4 x its amplitude (900 s steps, 10 km: 0.5 mm).  Sampling at the
step ends alone misses a node crossing by up to a x di x sin(omega x step / 2) (1.2 km for di = 0.05 deg at 900
s), what the interpolant finds.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

# Points of the step at which the cubic is sampled (then refined by Newton's method on |p|^2 from the nearest):
# more than the relative motion's curvature needs within a step (one 96th of its period at 900 s steps).
SAMPLES_PER_STEP = 16
NEWTON_ITERATIONS = 3


def hermite_coefficients(p0, v0, p1, v1, step_s):
    """The cubic c0 + c1 s + c2 s^2 + c3 s^3 (s in [0, 1] over the step) through positions ``p0``, ``p1`` with
    velocities ``v0``, ``v1`` (per second) at the step's ends: ([..., 3] each) -> [4, ..., 3]."""
    d0, d1 = step_s * v0, step_s * v1
    return jnp.stack([p0, d0, 3 * (p1 - p0) - 2 * d0 - d1, 2 * (p0 - p1) + d0 + d1])


def _cubic(c, s):
    """The cubic ``c`` [4, ..., 3] and its first two derivatives in s at ``s`` [...]: three [..., 3]."""
    s = s[..., None]
    p = c[0] + s * (c[1] + s * (c[2] + s * c[3]))
    dp = c[1] + s * (2 * c[2] + 3 * s * c[3])
    return p, dp, 2 * c[2] + 6 * s * c[3]


def closest_in_step(p0, v0, p1, v1, step_s, alert_m):
    """Within one step of ``step_s``, the least distance between two satellites and when, and the time spent
    closer than ``alert_m``, from their relative position and velocity at the step's ends ([..., 3], m and m/s).

    Returns (distance m, time from the step start s, seconds below ``alert_m``) [...] each: the cubic sampled at
    ``SAMPLES_PER_STEP`` midpoints (the time below the alert counts the samples below it) and the ends, then
    refined by Newton's method on the squared distance from the nearest sample, kept within the step."""
    c = hermite_coefficients(p0, v0, p1, v1, step_s)
    shape = p0.shape[:-1]
    grid = jnp.concatenate([jnp.array([0.0, 1.0]), (jnp.arange(SAMPLES_PER_STEP) + 0.5) / SAMPLES_PER_STEP])
    grid = jnp.broadcast_to(grid, (*shape, grid.size))
    c_grid = jnp.expand_dims(c, -2)  # [4, ..., 1, 3]: against every sample
    distances = jnp.linalg.norm(_cubic(c_grid, grid)[0], axis=-1)
    below_s = jnp.sum(distances[..., 2:] < alert_m, axis=-1) * (step_s / SAMPLES_PER_STEP)
    s = jnp.take_along_axis(grid, jnp.argmin(distances, axis=-1)[..., None], axis=-1)[..., 0]

    def newton(s, _):
        p, dp, ddp = _cubic(c, s)
        slope, curvature = jnp.sum(p * dp, axis=-1), jnp.sum(dp * dp + p * ddp, axis=-1)
        step = jnp.where(curvature > 0, slope / jnp.where(curvature > 0, curvature, 1.0), 0.0)
        return jnp.clip(s - step, 0.0, 1.0), None

    s, _ = jax.lax.scan(newton, s, None, length=NEWTON_ITERATIONS)
    refined = jnp.linalg.norm(_cubic(c, s)[0], axis=-1)
    best = jnp.min(distances, axis=-1)
    s_best = jnp.where(refined <= best, s, jnp.take_along_axis(grid, jnp.argmin(distances, axis=-1)[..., None],
                                                               axis=-1)[..., 0])
    return jnp.minimum(refined, best), s_best * step_s, below_s


def linear_relative_rtn(a_m, d_lon_rad, d_ex, d_ey, d_ix, d_iy, mean_lon_rad):
    """The linearised relative position (radial, along-track, cross-track; m) of a near-geostationary satellite
    with respect to another of the same semi-major axis ``a_m``, from the differences of their mean longitude
    offset and of their MEE e vector (f, g) and inclination vector (h, k), at the mean (sidereal) longitude
    ``mean_lon_rad`` of the orbit (Soop, Handbook of Geostationary Orbits, 1994, on e/i-vector separation: r = a (1 - f cos l - g sin l),
    l = L - 2 f sin L + 2 g cos L, z = 2 a (h sin L - k cos L) to first order, with h, k = tan(i/2) (cos, sin)
    Omega).  Parallel e/i separation (d_e along d_i) keeps the radial separation at its largest where the
    cross-track one vanishes: the least distance is a |d_e| (with no longitude offset)."""
    c, s = jnp.cos(mean_lon_rad), jnp.sin(mean_lon_rad)
    radial = -a_m * (d_ex * c + d_ey * s)
    along = a_m * (d_lon_rad + 2 * d_ex * s - 2 * d_ey * c)
    cross = 2 * a_m * (d_ix * s - d_iy * c)
    return jnp.stack([radial, along, cross], axis=-1)
