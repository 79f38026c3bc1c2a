"""Closed loop with a feedback law (Katz 2025): the acceleration is recomputed from the state at every step.

One rollout is an outer ``lax.scan`` over sidereal days around an inner scan
over RK4 steps (``integrate.rk4_step``).  The inner day is wrapped in
``jax.checkpoint``, so reverse-mode gradients of a year keep only the state at
day boundaries plus one day of residuals: memory grows with the number of days,
not steps (a batch of 16 one-year gradients fits in well under 4 GB).

At the start of each step the law reads the true state, rotated into ECEF
(position, and the inertial velocity in ECEF axes, Katz eq. (1)), commands u
(``control.lyapunov.accel``), the thrust implementation delivers part of it
(``thrust_laws.apply``), and the delivered acceleration is held constant in the
orbit (RSW) frame for the step -- a sample-and-hold at the integration step,
as a flight computer would apply it.  For a synchronous orbit the RSW frame
turns with the Earth, so this is also a hold in ECEF.  Holding the command
makes the discontinuous laws (eqs. (5)-(7)) well defined within an RK4 step,
and the delivered Delta-V is exactly sum |u_k| h (integrated with the orbit in
``SpacecraftState.dv_mps``).  The mass decreases with the scenario's Isp; the
law commands accelerations, so the mass only enters the thrust bookkeeping.

The environment (Sun, Moon, Earth angle) comes from the shared
``propagate.environment_grid``: nothing astronomical is evaluated per sample.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax import thrust_laws
from geojax.constants import SECONDS_PER_DAY
from geojax.control import lyapunov
from geojax.dynamics import SpacecraftState, Thrust
from geojax.elements import mee_to_cartesian, wrap_angle
from geojax.frames import rotate_z, rsw_basis, subsatellite_lon_lat_rad
from geojax.integrate import rk4_step
from geojax.propagate import CARTESIAN, Dynamics

SECONDS_PER_YEAR = 365.25 * SECONDS_PER_DAY


class FeedbackParams(NamedTuple):
    """Everything a tuning or a sweep may vary in a feedback rollout (array leaves)."""

    gains: lyapunov.LyapunovGains
    limits: thrust_laws.ThrustLimits
    station: lyapunov.Station
    isp_s: jnp.ndarray
    temperature: jnp.ndarray = jnp.asarray(0.05)  # of the smooth surrogate (``smooth=True`` only)


class StepRecord(NamedTuple):
    """Per step, leading axes [n_days, n_steps]: at the step start, and the acceleration held over it."""

    lon_rad: jnp.ndarray  # geocentric sub-satellite longitude
    lat_rad: jnp.ndarray  # geocentric sub-satellite latitude
    u_ecef_mps2: jnp.ndarray  # [..., 3] delivered acceleration, ECEF axes


def rollout(dynamics: Dynamics, state: SpacecraftState, env_grid, fm, step_s: float, params: FeedbackParams,
            mode: str, smooth: bool = False):
    """Closed loop over the days of ``env_grid`` (leaves [n_days, n_steps, 3, ...]).

    ``dynamics``, ``step_s``, ``mode`` (``thrust_laws.MODES``) and ``smooth`` are static.
    Returns (final state, StepRecord [n_days, n_steps]).
    """
    mu = fm.mu_m3_s2

    def step(state, env3):
        r_eci, v_eci = position_velocity(dynamics, state.orbit, mu)
        angle = env3.earth_angle_rad[0]
        r_ecef = rotate_z(r_eci, angle)
        u_cmd = lyapunov.accel(params.gains, params.station, r_ecef, rotate_z(v_eci, angle))
        u_ecef = thrust_laws.apply(mode, u_cmd, params.limits, smooth, params.temperature)
        u_rsw = rsw_basis(r_eci, v_eci) @ rotate_z(u_ecef, -angle)
        u_norm = thrust_laws.safe_norm(u_rsw)
        thrust = Thrust(u_rsw / u_norm, u_norm * state.mass_kg, params.isp_s, jnp.asarray(1.0))
        lon, lat = subsatellite_lon_lat_rad(r_ecef)
        return rk4_step(dynamics.rhs, state, env3, fm, thrust, step_s), StepRecord(lon, lat, u_ecef)

    @jax.checkpoint
    def one_day(state, env_steps):
        return jax.lax.scan(jax.checkpoint(step), state, env_steps)

    return jax.lax.scan(one_day, state, env_grid)


def position_velocity(dynamics: Dynamics, orbit, mu):
    """ECI position and velocity [3] of an orbit state of ``dynamics`` (Cartesian or MEE)."""
    if dynamics is CARTESIAN:
        return orbit[:3], orbit[3:]
    return mee_to_cartesian(dynamics.to_mee(orbit, mu), mu)


class FeedbackMetrics(NamedTuple):
    """Summary of a rollout (JAX scalars, so a batch computes them inside ``vmap``)."""

    dv_per_year_mps: jnp.ndarray  # delivered Delta-V scaled to 365.25 days
    max_abs_dlon_deg: jnp.ndarray  # max |lambda - lambda_d| over every step
    max_abs_dlat_deg: jnp.ndarray  # max |latitude| over every step
    mean_dlon_deg: jnp.ndarray  # mean lambda - lambda_d (the longitude loop's offset, set by lambda_b)
    dlon_half_range_deg: jnp.ndarray  # (max - min) / 2 of lambda - lambda_d: the "+-" of Katz Table 1
    dlat_half_range_deg: jnp.ndarray  # (max - min) / 2 of the latitude
    duty_x: jnp.ndarray  # fraction of the time each ECEF component of the delivered u is non-zero
    duty_y: jnp.ndarray
    duty_z: jnp.ndarray
    box_ok: jnp.ndarray  # 1.0 when both excursions stay within the box half-width


def metrics(initial: SpacecraftState, final: SpacecraftState, records: StepRecord, step_s: float,
            station_lon_rad, box_half_width_rad) -> FeedbackMetrics:
    """Katz 2025 eqs. (8)-(10): yearly Delta-V and the box, from a rollout's records."""
    span_s = records.lon_rad.size * step_s
    dlon_all = wrap_angle(records.lon_rad - station_lon_rad)
    dlon = jnp.max(jnp.abs(dlon_all))
    dlat = jnp.max(jnp.abs(records.lat_rad))
    half_range = lambda x: jnp.degrees(jnp.max(x) - jnp.min(x)) / 2  # noqa: E731
    duty = jnp.mean(records.u_ecef_mps2.reshape(-1, 3) != 0.0, axis=0)
    return FeedbackMetrics(
        dv_per_year_mps=(final.dv_mps - initial.dv_mps) * SECONDS_PER_YEAR / span_s,
        max_abs_dlon_deg=jnp.degrees(dlon),
        max_abs_dlat_deg=jnp.degrees(dlat),
        mean_dlon_deg=jnp.degrees(jnp.mean(dlon_all)),
        dlon_half_range_deg=half_range(dlon_all),
        dlat_half_range_deg=half_range(records.lat_rad),
        duty_x=duty[0], duty_y=duty[1], duty_z=duty[2],
        box_ok=((dlon <= box_half_width_rad) & (dlat <= box_half_width_rad)).astype(float),
    )
