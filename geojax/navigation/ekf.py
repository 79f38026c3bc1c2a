"""The extended Kalman filter's pure pieces on the Cartesian state x = (r m, v m/s) [6], ECI.

* ``time_update``: x and P carried through one step of a propagation function given as an argument, the state
  transition matrix by ``jax.jacfwd`` of that step, plus ``process_noise``;
* ``process_noise``: state-noise compensation (SNC), white acceleration of density q = sigma_a^2 per axis
  (m^2/s^3): Q(dt) = q [[dt^3/3 I, dt^2/2 I], [dt^2/2 I, dt I]] (Tapley, Schutz & Born 2004, Sec. 4.9; the
  covariance of the position and velocity a white acceleration integrates to over dt);
* ``measurement_update``: Joseph form, (I - K H) P (I - K H)^T + K R K^T, symmetric and positive definite for
  any gain, weighted 0/1 by the schedule and visibility (a weight of 0 leaves x and P as they are);
* ``burn_covariance`` / ``add_burn_uncertainty``: a burn's execution error in the velocity covariance;
* ``nees`` / ``nis`` and ``chi2_bounds``: the filter's consistency (outside jit for the bounds).
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp


def time_update(step: Callable, x, p, q):
    """``step(x) -> x`` [6] one propagation step; returns (x [6], P [6, 6], STM [6, 6]) after the step:
    P = Phi P Phi^T + Q, Phi = d step / d x."""
    stm = jax.jacfwd(step)(x)
    return step(x), _symmetric(stm @ p @ stm.T + q), stm


def process_noise(dt_s, snc_mps2_per_rthz):
    """SNC process noise Q [6, 6] over ``dt_s`` for white acceleration of density ``snc_mps2_per_rthz``^2 per
    axis (m/s^2/sqrt(Hz))."""
    q = snc_mps2_per_rthz**2
    eye = jnp.eye(3)
    return q * jnp.block([[dt_s**3 / 3 * eye, dt_s**2 / 2 * eye], [dt_s**2 / 2 * eye, dt_s * eye]])


def measurement_update(x, p, innovation, h, r, weight=1.0):
    """Joseph-form update with the innovation z - h(x) [m] (angles wrapped), H [m, 6], R [m, m] and a 0/1
    ``weight``.  Returns (x [6], P [6, 6], S [m, m] the innovation covariance, for ``nis``).

    (I - K H) P (I - K H)^T is formed as two rank-m corrections, A = P - K (H P), then A - (A H^T) K^T: the same
    product, in O(n^2 m) operations instead of the O(n^3) of the matrix products (n = 10 in the loop's filter)."""
    hp = h @ p
    s = hp @ h.T + r
    gain = weight * jnp.linalg.solve(s, hp).T  # P H^T S^-1 (S and P symmetric)
    a = p - gain @ hp  # (I - K H) P
    joseph = a - (a @ h.T) @ gain.T + gain @ r @ gain.T  # (I - K H) P (I - K H)^T + K R K^T
    return x + gain @ innovation, _symmetric(joseph), s


def burn_covariance(dv_eci_mps, magnitude_sigma, pointing_sigma_rad):
    """Covariance [3, 3] (m^2/s^2) of a burn's delivered-minus-planned Delta-V.

    Delivered: (1 + eps) |dv| (u + d), eps ~ N(0, magnitude_sigma^2) (a fraction), d the pointing error
    perpendicular to the planned direction u, N(0, pointing_sigma^2) in each of the two perpendicular axes.  To
    first order the error is eps dv + |dv| d: along u variance magnitude_sigma^2 |dv|^2, across it
    (pointing_sigma |dv|)^2 per axis, so Sigma = magnitude_sigma^2 dv dv^T + pointing_sigma^2 (|dv|^2 I - dv dv^T),
    written without u so that it is smooth (and zero) at dv = 0.
    """
    outer = jnp.outer(dv_eci_mps, dv_eci_mps)
    return magnitude_sigma**2 * outer + pointing_sigma_rad**2 * (jnp.dot(dv_eci_mps, dv_eci_mps) * jnp.eye(3) - outer)


def add_burn_uncertainty(p, dv_eci_mps, magnitude_sigma, pointing_sigma_rad):
    """P [6, 6] with a burn's execution covariance (``burn_covariance``) added to its velocity block."""
    return p.at[3:, 3:].add(burn_covariance(dv_eci_mps, magnitude_sigma, pointing_sigma_rad))


def nees(error, p):
    """Normalised estimation error squared e^T P^-1 e (e = estimate - truth [n]): chi^2 with n degrees of
    freedom for a consistent filter."""
    return error @ jnp.linalg.solve(p, error)


def nis(innovation, s):
    """Normalised innovation squared y^T S^-1 y (S from ``measurement_update``): chi^2 with m degrees of freedom."""
    return nees(innovation, s)


def chi2_bounds(dof: int, n_samples: int, probability: float = 0.95):
    """Two-sided ``probability`` bounds on the average of ``n_samples`` independent NEES (or NIS) values of
    ``dof`` degrees of freedom each: n_samples times the average is chi^2 with n_samples dof degrees of freedom
    (Bar-Shalom, Li & Kirubarajan 2001, Sec. 5.4.2).  NumPy floats; call outside jit."""
    from scipy.stats import chi2

    total = dof * n_samples
    tail = (1.0 - probability) / 2
    return float(chi2.ppf(tail, total) / n_samples), float(chi2.ppf(1.0 - tail, total) / n_samples)


def _symmetric(m):
    return 0.5 * (m + jnp.swapaxes(m, -1, -2))
