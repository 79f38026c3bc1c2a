"""The extended Kalman filter's pure pieces on the Cartesian state x = (r m, v m/s) [6], ECI.

* ``process_noise``: state-noise compensation (SNC), white acceleration of density q = sigma_a^2 per axis
  (m^2/s^3): Q(dt) = q [[dt^3/3 I, dt^2/2 I], [dt^2/2 I, dt I]] (Tapley, Schutz & Born 2004, Sec. 4.9; the
  covariance of the position and velocity a white acceleration integrates to over dt);
* ``measurement_update``: Joseph form, (I - K H) P (I - K H)^T + K R K^T, symmetric and positive definite for
  any gain, weighted 0/1 by the schedule and visibility (a weight of 0 leaves x and P as they are);
* ``nees`` / ``nis`` and ``chi2_bounds``: the filter's consistency (outside jit for the bounds).
"""

from __future__ import annotations

import jax.numpy as jnp


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
