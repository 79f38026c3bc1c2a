"""Acceleration limits of a feedback law (Katz 2025, eqs. (5)-(7)) and their smooth surrogates.

A feedback law commands an acceleration u; the propulsion system can only
deliver part of it.  Four implementations, all functions of u [3] (m/s^2, ECEF
axes, so the discrete thresholds act on the Earth-fixed x, y, z):

- ``"continuous"`` (eq. (5) as printed): u where |u| <= u0, and **zero** where
  |u| > u0 -- the thruster switches off when asked for more than it has.
  That is what the equation says; a real system would rather saturate, so
- ``"continuous-clipped"``: u scaled back to |u| = u0 where |u| > u0 (the usual
  saturation; Lipschitz in u, the configuration the gradient checks use).
- ``"discrete"`` (eq. (6), Guelman 2014): per axis, sigma_i sign(u_i) where
  |u_i| >= sigma_i, else 0, with |sigma| = u0 (all three axes firing at once
  deliver u0).
- ``"constant"`` (eq. (7)): u0 u/|u| where |u| >= u0, else 0 (a gimballed
  thruster, on or off).

Tuning needs gradients through the on/off decisions, which are step functions.
``smooth=True`` replaces each indicator by a logistic sigmoid of the relative
margin with temperature ``temperature`` (e.g. 1[|u| >= u0] ->
sigmoid((|u| - u0) / (T u0))); as T -> 0 the surrogate tends to the exact law.
Reported objectives and box checks always use ``smooth=False``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

# |u| below this (m/s^2) counts as zero when a direction is needed (1e-9 of u0 for 10 mN on 2205 kg).
_TINY_MPS2 = 1e-15


class ThrustLimits(NamedTuple):
    """Acceleration limits (SI): u0 = F_max / m, and the per-axis thresholds of eq. (6) (|sigma| = u0)."""

    u0_mps2: jnp.ndarray
    sigma_mps2: jnp.ndarray  # [3], x, y, z of ECEF; used by "discrete" only


def continuous(u, limits: ThrustLimits, smooth: bool = False, temperature=0.05):
    """Eq. (5) as printed: off where |u| > u0."""
    u0 = limits.u0_mps2
    return u * _step(u0 - safe_norm(u), u0, smooth, temperature)


def continuous_clipped(u, limits: ThrustLimits, smooth: bool = False, temperature=0.05):
    """Saturation at |u| = u0 (smooth already: ``smooth`` and ``temperature`` are not used)."""
    return u * jnp.minimum(1.0, limits.u0_mps2 / safe_norm(u))


def discrete(u, limits: ThrustLimits, smooth: bool = False, temperature=0.05):
    """Eq. (6): sigma_i sign(u_i) on each ECEF axis where |u_i| >= sigma_i."""
    sigma = limits.sigma_mps2
    return sigma * jnp.sign(u) * _step(jnp.abs(u) - sigma, sigma, smooth, temperature)


def constant(u, limits: ThrustLimits, smooth: bool = False, temperature=0.05):
    """Eq. (7): u0 u / |u| where |u| >= u0."""
    u0, norm = limits.u0_mps2, safe_norm(u)
    return u0 * u / norm * _step(norm - u0, u0, smooth, temperature)


LAWS = {"continuous": continuous, "continuous-clipped": continuous_clipped, "discrete": discrete, "constant": constant}
MODES = tuple(LAWS)


def law(mode: str):
    """The implementation of a thrust mode, chosen once outside the traced loop:
    ``law(mode)(u, limits, smooth, temperature)`` is the acceleration [3] delivered for a commanded ``u`` [3]."""
    if mode not in LAWS:
        raise ValueError(f"controller.thrust_mode: must be one of {', '.join(MODES)}, got {mode!r}")
    return LAWS[mode]


def safe_norm(u):
    """|u| with a finite gradient at u = 0 (where it returns _TINY_MPS2)."""
    return jnp.sqrt(jnp.sum(u**2, axis=-1) + _TINY_MPS2**2)


def _step(margin, scale, smooth: bool, temperature):
    """1[margin >= 0], or its sigmoid surrogate of relative width ``temperature``."""
    if smooth:
        return jax.nn.sigmoid(margin / (temperature * scale))
    return (margin >= 0).astype(margin.dtype)


def check_thresholds(u0_mps2: float, sigma_mps2, field: str = "controller.sigma_km_per_s2", rtol: float = 1e-6) -> None:
    """ValueError unless every threshold is > 0 and |sigma| = u0 (eq. (6))."""
    sigma = [float(s) for s in sigma_mps2]
    if len(sigma) != 3 or min(sigma) <= 0:
        raise ValueError(f"{field}: must be three thresholds > 0, got {sigma}")
    norm = sum(s * s for s in sigma) ** 0.5
    if abs(norm - u0_mps2) > rtol * u0_mps2:
        raise ValueError(f"{field}: the norm of the thresholds must equal u0 = {u0_mps2:.6g} (Katz 2025, eq. (6)), "
                         f"got {norm:.6g}")
