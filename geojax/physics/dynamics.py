"""Equations of motion: Gauss variational equations in MEE (Li 2022, eqs. (6)-(7)) and Cartesian.

The spacecraft state is a pytree ``SpacecraftState(orbit, mass_kg, dv_mps)``:
``orbit`` is MEE [6] (p in m, L in rad) for ``mee_rhs`` or ECI position and
velocity [6] (m, m/s) for ``cartesian_rhs``; ``dv_mps`` accumulates the
delivered thrust acceleration integral(F/m dt), so the delivered Delta-V is
integrated with the orbit and is exact for any burn window (see
``geojax.physics.integrate``).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from geojax.physics.constants import G0_MPS2
from geojax.physics.elements import mee_radius_m, mee_rsw_basis
from geojax.physics.forces import Environment, ForceModel, perturbing_acceleration, point_mass
from geojax.physics.frames import rsw_to_eci


class SpacecraftState(NamedTuple):
    orbit: jnp.ndarray  # [6] MEE or Cartesian ECI
    mass_kg: jnp.ndarray  # []
    dv_mps: jnp.ndarray  # [], delivered Delta-V so far


class Thrust(NamedTuple):
    """Thrust held constant over one integration step.

    ``on_fraction`` is the fraction of the step during which the thruster
    fires; the thrust is spread over the whole step at that duty so the step
    delivers exactly F/m times the firing time (overlap weighting).
    """

    direction_rsw: jnp.ndarray  # [3] unit vector along (R, S, W)
    thrust_n: jnp.ndarray  # []
    isp_s: jnp.ndarray  # []
    on_fraction: jnp.ndarray  # [] in [0, 1]


def no_thrust() -> Thrust:
    return Thrust(jnp.array([0.0, 1.0, 0.0]), jnp.array(0.0), jnp.array(1.0), jnp.array(0.0))


def mee_gauss_rates(mee, a_rsw, mu):
    """Li 2022, eqs. (6)-(7): d(p, f, g, h, k, L)/dt for an RSW acceleration [3] (m/s^2)."""
    p, f, g, h, k, true_lon = (mee[..., j] for j in range(6))
    a_r, a_t, a_n = a_rsw[..., 0], a_rsw[..., 1], a_rsw[..., 2]
    cos_l, sin_l = jnp.cos(true_lon), jnp.sin(true_lon)
    w = 1 + f * cos_l + g * sin_l
    s2 = 1 + h**2 + k**2
    q = jnp.sqrt(p / mu)
    hk = h * sin_l - k * cos_l
    return jnp.stack(
        [
            q * 2 * p / w * a_t,
            q * (a_r * sin_l + ((1 + w) * cos_l + f) * a_t / w - hk * g * a_n / w),
            q * (-a_r * cos_l + ((1 + w) * sin_l + g) * a_t / w + hk * f * a_n / w),
            q * s2 * a_n / (2 * w) * cos_l,
            q * s2 * a_n / (2 * w) * sin_l,
            jnp.sqrt(mu * p) * (w / p) ** 2 + q * hk * a_n / w,
        ],
        -1,
    )


def _thrust_rates(state, thrust: Thrust):
    accel = thrust.on_fraction * thrust.thrust_n / state.mass_kg
    mass_rate = -thrust.on_fraction * thrust.thrust_n / (thrust.isp_s * G0_MPS2)
    return accel * thrust.direction_rsw, mass_rate, accel


def mee_rhs(state: SpacecraftState, env: Environment, fm: ForceModel, thrust: Thrust) -> SpacecraftState:
    """Time derivative of a MEE spacecraft state.

    The perturbations depend on position only, so the RSW basis comes straight
    from the elements (no velocity, no cross products).
    """
    basis = mee_rsw_basis(state.orbit)
    r_eci = mee_radius_m(state.orbit)[..., None] * basis[..., 0, :]
    a_thrust_rsw, mass_rate, accel = _thrust_rates(state, thrust)
    a_pert_eci = perturbing_acceleration(r_eci, state.mass_kg, env, fm)
    a_rsw = jnp.einsum("...ij,...j->...i", basis, a_pert_eci) + a_thrust_rsw
    return SpacecraftState(mee_gauss_rates(state.orbit, a_rsw, fm.mu_m3_s2), mass_rate, accel)


def cartesian_rhs(state: SpacecraftState, env: Environment, fm: ForceModel, thrust: Thrust) -> SpacecraftState:
    """Time derivative of a Cartesian ECI spacecraft state."""
    r_eci, v_eci = state.orbit[:3], state.orbit[3:]
    a_thrust_rsw, mass_rate, accel = _thrust_rates(state, thrust)
    a_eci = (
        point_mass(r_eci, fm.mu_m3_s2)
        + perturbing_acceleration(r_eci, state.mass_kg, env, fm)
        + rsw_to_eci(a_thrust_rsw, r_eci, v_eci)
    )
    return SpacecraftState(jnp.concatenate([v_eci, a_eci]), mass_rate, accel)
