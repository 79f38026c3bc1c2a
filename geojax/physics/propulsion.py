"""Robotic-arm thrusters (Li 2022, Sec. 2.1 and 3.2).

Two thrusters on arms at the anti-nadir face.  A thrust direction is given by
its yaw alpha (in the R-S plane, from +R) and pitch beta (out of that plane);
thruster 1 works in the (+, +/-, +) half-space and thruster 2 in (+, +/-, -),
within the limits of eq. (1):

    -alpha_min <= alpha_1 <= alpha_max,   -alpha_max <= alpha_2 <= alpha_min,
     beta_min  <= beta_1  <= beta_max,    -beta_max  <= beta_2  <= -beta_min.

The velocity increment is opposite to the thrust direction, eq. (14):
dv = -V (cos b cos a, cos b sin a, sin b) in RSW, so every burn pushes the
satellite towards the Earth (v_r <= 0, eq. (34)), thruster 1 southwards
(v_n <= 0) and thruster 2 northwards.

Burns in Earth shadow are suspended and resumed (constraint 6): a burn of
firing time D that starts at t0 fires during the first D seconds of *sunlit*
time after t0.  ``sunlit_clock`` turns the shadow history of a cycle into a
clock that only runs in sunlight, so a burn is an interval on that clock and
each integration step gets the exact firing time it contains.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp

# Li 2022, Table 1: (beta_max, beta_min, alpha_max, alpha_min) in degrees.
PRESETS_DEG = {
    "weak": (90.0, 0.0, 90.0, 90.0),
    "normal": (70.0, 0.0, 60.0, 30.0),
    "strong": (60.0, 0.0, 45.0, 25.0),
}


class ArmLimits(NamedTuple):
    """Yaw and pitch limits of eq. (1), radians; array leaves so a sweep can vary them."""

    beta_max_rad: jnp.ndarray
    beta_min_rad: jnp.ndarray
    alpha_max_rad: jnp.ndarray
    alpha_min_rad: jnp.ndarray


def arm_limits_deg(beta_max_deg, beta_min_deg, alpha_max_deg, alpha_min_deg) -> ArmLimits:
    """Validated limits from degrees; ``ValueError`` names the field at fault."""
    values = {"beta_max_deg": beta_max_deg, "beta_min_deg": beta_min_deg,
              "alpha_max_deg": alpha_max_deg, "alpha_min_deg": alpha_min_deg}
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise ValueError(f"thrusters.{name}: must be a number, got {value!r}")
    for name in ("beta_max_deg", "beta_min_deg"):
        if not 0.0 <= values[name] <= 90.0:
            raise ValueError(f"thrusters.{name}: must be >= 0 and <= 90, got {values[name]!r}")
    for name in ("alpha_max_deg", "alpha_min_deg"):
        if not 0.0 <= values[name] <= 90.0:
            raise ValueError(f"thrusters.{name}: must be >= 0 and <= 90, got {values[name]!r}")
    if beta_min_deg > beta_max_deg:
        raise ValueError(
            f"thrusters.beta_min_deg: must be <= thrusters.beta_max_deg ({beta_max_deg!r}), got {beta_min_deg!r}"
        )
    if beta_max_deg == 0.0:
        raise ValueError("thrusters.beta_max_deg: must be > 0; with no pitch the arms cannot control the inclination")
    if beta_min_deg == 90.0 and alpha_max_deg + alpha_min_deg == 0.0:
        raise ValueError("thrusters.beta_min_deg: 90 leaves no in-plane thrust; the longitude cannot be controlled")
    # math.radians is jnp.deg2rad's product bit for bit; eagerly, jnp.deg2rad compiled a program of its own
    return ArmLimits(*(jnp.asarray(math.radians(float(v))) for v in (beta_max_deg, beta_min_deg, alpha_max_deg,
                                                                      alpha_min_deg)))


def arm_limits(thrusters: dict) -> ArmLimits:
    """The ``ArmLimits`` of a ``Params.thrusters`` table (radian leaves)."""
    return ArmLimits(thrusters["beta_max_rad"], thrusters["beta_min_rad"], thrusters["alpha_max_rad"],
                     thrusters["alpha_min_rad"])


def delta_v_direction_rsw(alpha_rad, beta_rad):
    """Unit velocity increment of a thrust direction (alpha, beta), Li 2022, eq. (14)."""
    cos_b = jnp.cos(beta_rad)
    return -jnp.stack([cos_b * jnp.cos(alpha_rad), cos_b * jnp.sin(alpha_rad), jnp.sin(beta_rad)], -1)


def alpha_beta_bounds(limits: ArmLimits):
    """Eq. (1) as ((alpha_lo, alpha_hi), (beta_lo, beta_hi)) for thruster 1 and thruster 2, each [2]."""
    alpha_lo = jnp.stack([-limits.alpha_min_rad, -limits.alpha_max_rad])
    alpha_hi = jnp.stack([limits.alpha_max_rad, limits.alpha_min_rad])
    beta_lo = jnp.stack([limits.beta_min_rad, -limits.beta_max_rad])
    beta_hi = jnp.stack([limits.beta_max_rad, -limits.beta_min_rad])
    return (alpha_lo, alpha_hi), (beta_lo, beta_hi)


def within_limits(alpha_rad, beta_rad, limits: ArmLimits, tol_rad: float = 1e-12):
    """True where thruster j's (alpha[j], beta[j]) satisfies eq. (1); arrays [..., 2]."""
    (alpha_lo, alpha_hi), (beta_lo, beta_hi) = alpha_beta_bounds(limits)
    return (
        (alpha_rad >= alpha_lo - tol_rad) & (alpha_rad <= alpha_hi + tol_rad)
        & (beta_rad >= beta_lo - tol_rad) & (beta_rad <= beta_hi + tol_rad)
    )


def sunlit_clock(step_start_sunlit_fraction, step_s):
    """Cumulative sunlit time at every step boundary of a cycle, [n + 1], from per-step sunlit fractions [n]."""
    return jnp.concatenate([jnp.zeros(1), jnp.cumsum(step_start_sunlit_fraction * step_s)])


def firing_fraction(clock_start, clock_end, burn_on_clock_s, burn_firing_s, step_s):
    """Fraction of a step spent firing for a burn that starts at sunlit-clock time ``burn_on_clock_s``.

    The step covers sunlit-clock times [clock_start, clock_end]; the burn fires
    for ``burn_firing_s`` seconds of sunlit time.  The fraction is exact in the
    total (the fractions of all steps add up to burn_firing_s / step_s).
    """
    overlap = jnp.minimum(clock_end, burn_on_clock_s + burn_firing_s) - jnp.maximum(clock_start, burn_on_clock_s)
    return jnp.clip(overlap, 0.0, step_s) / step_s
