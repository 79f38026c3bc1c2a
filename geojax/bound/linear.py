"""The time-varying linear model of the fuel bound: one slot's transition about a nominal trajectory.

A slot is ``slot_steps`` integration steps over which the thrust acceleration is held constant in RSW,
``u / slot_s`` for a slot Delta-V vector u [3] (m/s).  About a nominal trajectory (the uncontrolled
reference first, then the last plan's re-simulation) each slot k maps

    x_{k+1} = xbar_{k+1} + Phi_k (x_k - xbar_k) + B_k (u_k - ubar_k),
    y_{k,s} = ybar_{k,s} + C_{k,s} (x_k - xbar_k) + E_{k,s} (u_k - ubar_k),   s = 0 .. slot_steps - 1,

where y is the sub-satellite (longitude less the station's, latitude) at every step start, so the box is
held at every step start, as the closed loop's status checks it.  Phi, B, C, E are the forward-mode
Jacobians (``jax.jacfwd``) of the very RK4 steps and force model the closed loop integrates, so the drift is
the real one; the nominal trajectory comes out of the same scan.  The mass (which the solar radiation
pressure reads) is the nominal plan's at each slot's start, held over the slot.
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.physics.dynamics import SpacecraftState, Thrust
from geojax.physics.elements import wrap_angle
from geojax.physics.integrate import rk4_step
from geojax.physics.propagate import Dynamics


class SlotModel(NamedTuple):
    """The linear model about a nominal trajectory, leading axis = slot [S]."""

    x: jnp.ndarray  # [S + 1, 6] nominal orbit state at slot boundaries
    y: jnp.ndarray  # [S, T, 2] nominal (lon - station, lat) at every step start, rad
    phi: jnp.ndarray  # [S, 6, 6]
    b: jnp.ndarray  # [S, 6, 3] per m/s of slot Delta-V
    c: jnp.ndarray  # [S, T, 2, 6]
    e: jnp.ndarray  # [S, T, 2, 3]


def slot_map(x, u, env_slot, fm, mass_kg, station_lon_rad, *, slot_s: float, step_s: float, dynamics: Dynamics):
    """One slot: the orbit state at its end [6] and (lon - station, lat) at its step starts [T, 2].

    ``u`` [3] is the slot's Delta-V (m/s) along R, S, W, delivered at constant acceleration u / slot_s.
    """
    # Thrust of one "newton" per kilogram along the acceleration vector: a_rsw = u / slot_s exactly, no norm
    # (differentiable at u = 0); no mass flow (infinite Isp).
    thrust = Thrust(u / slot_s, mass_kg, jnp.inf, jnp.asarray(1.0))
    mu = fm.mu_m3_s2

    def step(state, env3):
        (x_eci, y_eci, z_eci), _ = dynamics.rv_xyz(state.orbit, mu)
        angle = env3.earth_angle_rad[0]
        x_ecef = jnp.cos(angle) * x_eci + jnp.sin(angle) * y_eci
        y_ecef = -jnp.sin(angle) * x_eci + jnp.cos(angle) * y_eci
        lon = wrap_angle(jnp.arctan2(y_ecef, x_ecef) - station_lon_rad)
        lat = jnp.arctan2(z_eci, jnp.hypot(x_ecef, y_ecef))
        return rk4_step(dynamics.rhs, state, env3, fm, thrust, step_s), jnp.stack([lon, lat])

    final, y = jax.lax.scan(step, SpacecraftState(x, mass_kg, jnp.asarray(0.0)), env_slot)
    return final.orbit, y


@partial(jax.jit, static_argnames=("slot_s", "step_s", "dynamics"))
def linearize(x0, u, env_slots, fm, mass_kg, station_lon_rad, *, slot_s: float, step_s: float,
              dynamics: Dynamics) -> SlotModel:
    """The nominal trajectory of the slot Delta-Vs ``u`` [S, 3] from ``x0`` [6] and its ``SlotModel``;
    ``mass_kg`` [S] the mass at each slot's start.

    ``env_slots``: the environment grid reshaped to [S, T, 3, ...] (``physics.propagate.environment_grid``).
    """
    f = partial(slot_map, fm=fm, station_lon_rad=station_lon_rad, slot_s=slot_s, step_s=step_s, dynamics=dynamics)
    jac = jax.jacfwd(f, argnums=(0, 1))

    def one(x, xs):
        u_k, env_slot, mass_k = xs
        x_next, y = f(x, u_k, env_slot, mass_kg=mass_k)
        (phi, b), (c, e) = jac(x, u_k, env_slot, mass_kg=mass_k)
        return x_next, (x, y, phi, b, c, e)

    x_end, (x, y, phi, b, c, e) = jax.lax.scan(one, x0, (u, env_slots, mass_kg))
    return SlotModel(jnp.concatenate([x, x_end[None]]), y, phi, b, c, e)
