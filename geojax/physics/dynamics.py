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
from geojax.physics.elements import mee_rsw_rows
from geojax.physics.forces import Environment, ForceModel, perturbing_behind_boundary, point_mass_xyz
from geojax.physics.frames import rsw_to_eci_xyz
from geojax.physics.fusion import materialized
from geojax.physics.trig import sincos


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

    direction_rsw: jnp.ndarray  # [3] along (R, S, W): a unit vector, or the mean of time-shared unit directions (norm < 1)
    thrust_n: jnp.ndarray  # []
    isp_s: jnp.ndarray  # []
    on_fraction: jnp.ndarray  # [] in [0, 1]
    # [3] (R, S, W) or None: a tilt of the line of action about its nozzle that the controller plans (sine of the
    # tilt, perpendicular to ``direction_rsw``, the line through the centre of mass; ``control.mpc_momentum``).
    # Flown by the wheels' model (``states.momentum.thrust``), which turns it into the direction and clears it;
    # None (every other controller): no leaf.
    tilt_rsw: jnp.ndarray | None = None
    # [] int or None: which thruster flies it, from 0 (``control.burns``: the burn's arm); None: thruster 0.  Read by
    # the parts that act on one thruster (``states.faults``); no leaf where a controller does not say.
    thruster: jnp.ndarray | None = None
    # [3] and [] or None: the direction and thrust the controller planned, where it flies the burns' execution
    # errors itself (``control.burns``: ``direction_rsw`` and ``thrust_n`` are then the flown ones); read by a
    # navigation filter, which knows the errors' statistics, not the draws.  None: flown as planned.
    planned_direction_rsw: jnp.ndarray | None = None
    planned_thrust_n: jnp.ndarray | None = None


def no_thrust() -> Thrust:
    return Thrust(jnp.array([0.0, 1.0, 0.0]), jnp.array(0.0), jnp.array(1.0), jnp.array(0.0))


def mee_gauss_rates(mee, a_rsw, mu):
    """Li 2022, eqs. (6)-(7): d(p, f, g, h, k, L)/dt [..., 6] for an RSW acceleration [..., 3] (m/s^2)."""
    rates = gauss_rates(*(mee[..., j] for j in range(5)), *sincos(mee[..., 5]),
                        a_rsw[..., 0], a_rsw[..., 1], a_rsw[..., 2], mu)
    return jnp.stack(jnp.broadcast_arrays(*rates), -1)


def gauss_rates(p, f, g, h, k, cos_l, sin_l, a_r, a_t, a_n, mu):
    """Li 2022, eqs. (6)-(7), on components: the rates of (p, f, g, h, k, L) as a tuple."""
    w = 1 + f * cos_l + g * sin_l
    s2 = 1 + h * h + k * k
    q = jnp.sqrt(p / mu)
    hk = h * sin_l - k * cos_l
    q_w = q / w
    return (
        2 * p * q_w * a_t,
        q * a_r * sin_l + q_w * (((1 + w) * cos_l + f) * a_t - hk * g * a_n),
        -q * a_r * cos_l + q_w * (((1 + w) * sin_l + g) * a_t + hk * f * a_n),
        0.5 * q_w * s2 * a_n * cos_l,
        0.5 * q_w * s2 * a_n * sin_l,
        jnp.sqrt(mu * p) * (w / p) ** 2 + q_w * hk * a_n,
    )


def _thrust_rates(state, thrust: Thrust):
    accel = thrust.on_fraction * thrust.thrust_n / state.mass_kg
    mass_rate = -thrust.on_fraction * thrust.thrust_n / (thrust.isp_s * G0_MPS2)
    return accel, mass_rate


def _components(orbit):
    """The six components of an orbit state: a tuple (the loop's step carry) or an array [..., 6]."""
    return tuple(orbit) if isinstance(orbit, (tuple, list)) else tuple(orbit[..., j] for j in range(6))


def _like(orbit, components):
    return tuple(components) if isinstance(orbit, (tuple, list)) else jnp.stack(jnp.broadcast_arrays(*components), -1)


def mee_rhs(state: SpacecraftState, env: Environment, fm: ForceModel, thrust: Thrust,
            boundaries: bool = False, rates_boundary: bool = False) -> SpacecraftState:
    """Time derivative of a MEE spacecraft state (``orbit``: an array [6] or a tuple of six components).

    The perturbations depend on position only, so the RSW basis comes straight from the elements (no
    velocity, no cross products).  The perturbing acceleration is computed behind a fusion boundary
    (``fusion.materialized``) when ``boundaries``, and the six rates too when ``rates_boundary`` (both
    static; ``physics.propagate.for_lanes``): every later term reads them, and XLA's CPU fusion would
    otherwise evaluate them again inside each of the RK4 stage and combination kernels.  cos L and sin L
    are not stored: in plain arithmetic (``physics.trig.sincos``) they cost less to recompute in each
    kernel than a boundary does (at batch 1024, 51 against 61 ns per right-hand side with XLA's cos and
    sin behind a boundary; at 256, 47 against 76).
    """
    p, f, g, h, k, true_lon = _components(state.orbit)
    anchor = env.earth_angle_rad
    cos_l, sin_l = sincos(true_lon)  # plain arithmetic (``physics.trig``): cheaper recomputed than stored
    rows = mee_rsw_rows(h, k, cos_l, sin_l)
    r = p / (1 + f * cos_l + g * sin_l)
    a_eci = perturbing_behind_boundary(r * rows[0][0], r * rows[0][1], r * rows[0][2], state.mass_kg, env, fm,
                                       boundaries)
    accel, mass_rate = _thrust_rates(state, thrust)
    d = thrust.direction_rsw
    a_r, a_t, a_n = (sum(row[j] * a_eci[j] for j in range(3)) + accel * d[..., i] for i, row in enumerate(rows))
    rates = materialized(gauss_rates, p, f, g, h, k, cos_l, sin_l, a_r, a_t, a_n, fm.mu_m3_s2, anchor=anchor,
                         enabled=rates_boundary)
    return SpacecraftState(_like(state.orbit, rates), mass_rate, accel)


def cartesian_rhs(state: SpacecraftState, env: Environment, fm: ForceModel, thrust: Thrust,
                  boundaries: bool = False) -> SpacecraftState:
    """Time derivative of a Cartesian ECI spacecraft state (``orbit``: an array [6] or a tuple)."""
    x, y, z, vx, vy, vz = _components(state.orbit)
    accel, mass_rate = _thrust_rates(state, thrust)
    gx, gy, gz = point_mass_xyz(x, y, z, fm.mu_m3_s2)
    px, py, pz = perturbing_behind_boundary(x, y, z, state.mass_kg, env, fm, boundaries)
    tx, ty, tz = (accel * c for c in rsw_to_eci_xyz(_xyz_of(thrust.direction_rsw), (x, y, z), (vx, vy, vz)))
    return SpacecraftState(_like(state.orbit, (vx, vy, vz, gx + px + tx, gy + py + ty, gz + pz + tz)),
                           mass_rate, accel)


def _xyz_of(vector):
    return vector[..., 0], vector[..., 1], vector[..., 2]
