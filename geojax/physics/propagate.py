"""Orbit representations, the shared environment grid and one-cycle mean GEO elements.

The orbit representations (MEE or Cartesian), the environment grid shared by a
batch, and the one-cycle mean elements (Li 2022, eqs. (8)-(9)) that the closed
loop (``geojax.loop.simulate``) records for every cycle.
"""

from __future__ import annotations

from functools import partial
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.physics.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S
from geojax.physics.dynamics import cartesian_rhs, mee_rhs
from geojax.physics.elements import cartesian_to_mee, mee_to_cartesian, mee_to_rv_xyz, wrap_angle
from geojax.physics.ephemeris import de421_sun_moon_eci_m, moon_position_eci_m, sun_position_eci_m
from geojax.physics.forces import Environment
from geojax.physics.frames import earth_rotation_angle_rad, latitude_rad


class Dynamics(NamedTuple):
    """An orbit representation: its equations of motion and conversions to and from MEE."""

    rhs: Callable
    to_mee: Callable  # (orbit [6], mu) -> MEE [6]
    from_mee: Callable  # (MEE [6], mu) -> orbit [6]
    to_cartesian: Callable  # (orbit [6], mu) -> ECI (r m, v m/s) [6]
    rv_xyz: Callable  # (orbit [6] or its six components, mu) -> ((x, y, z), (vx, vy, vz)), m and m/s
    rk4_stages_in_loop: bool = False  # the loop's RK4 stages as a loop (``integrate.rk4_step``): ``for_one_sample``


def _mee_to_rv(mee, mu):
    return jnp.concatenate(mee_to_cartesian(mee, mu), axis=-1)


MEE = Dynamics(mee_rhs, lambda orbit, mu: orbit, lambda mee, mu: mee, _mee_to_rv,
               lambda orbit, mu: mee_to_rv_xyz(*orbit, mu))
CARTESIAN = Dynamics(
    cartesian_rhs,
    lambda orbit, mu: cartesian_to_mee(orbit[..., :3], orbit[..., 3:], mu),
    _mee_to_rv,
    lambda orbit, mu: orbit,
    lambda orbit, mu: (tuple(orbit[:3]), tuple(orbit[3:])),
)
DYNAMICS = {"mee": MEE, "cartesian": CARTESIAN}
# With fusion boundaries in the right-hand side (``physics.fusion``): from BOUNDARY_LANES vmapped lanes per
# device the step runs 2.5-4x faster (benchmarks/core.py); a batch of one runs 2x slower (each boundary is a
# conditional of a few microseconds).  From RATES_BOUNDARY_LANES the MEE rates get their own boundary too
# (with cos L and sin L in plain arithmetic, ``physics.trig``; measured at batch 16/32/64/128/256/1024, one
# core: 0.91/0.97/1.01/1.35/1.49/1.62x the speed without it).  The numbers are the same to rounding.
BOUNDARY_LANES = 8
RATES_BOUNDARY_LANES = 64
_WITH_BOUNDARIES = {
    (id(d), tier): d._replace(rhs=partial(d.rhs, boundaries=True, **({"rates_boundary": True} if tier == 2 else {})))
    for d in (MEE, CARTESIAN) for tier in (1, 2)
}


def for_lanes(dynamics: Dynamics, lanes: int) -> Dynamics:
    """The dynamics to compile for ``lanes`` vmapped samples per device: with fusion boundaries from
    ``BOUNDARY_LANES`` on, and more from ``RATES_BOUNDARY_LANES`` (MEE)."""
    tier = 2 if lanes >= RATES_BOUNDARY_LANES and dynamics is MEE else 1 if lanes >= BOUNDARY_LANES else 0
    return _WITH_BOUNDARIES.get((id(dynamics), tier), dynamics)


def for_one_sample(dynamics: Dynamics) -> Dynamics:
    """The dynamics to compile for a single sample's program (``simulate``, whose compilation is the wait): the
    RK4 stages in a loop, the right-hand side compiled once (``integrate.rk4_step``)."""
    return dynamics._replace(rk4_stages_in_loop=True)


class CycleMeans(NamedTuple):
    """One-cycle mean elements (Li 2022, eq. (8)), SI units, leading axis = cycle."""

    t_s: jnp.ndarray  # mid-cycle time since the start of the propagation
    lon_rad: jnp.ndarray  # mean sub-satellite longitude, wrapped to [-pi, pi)
    drift_rad_s: jnp.ndarray  # longitude change over the cycle / cycle length
    ex: jnp.ndarray
    ey: jnp.ndarray
    ix: jnp.ndarray
    iy: jnp.ndarray
    a_m: jnp.ndarray
    max_abs_lat_rad: jnp.ndarray  # largest |sub-satellite latitude| sampled in the cycle (not a mean)


def steps_per_cycle(step_s: float) -> int:
    """Number of integration steps per sidereal day for a requested step (rounded to the nearest)."""
    if not step_s > 0:
        raise ValueError(f"integration.step_s: must be > 0 s, got {step_s}")
    return max(1, round(SIDEREAL_DAY_S / step_s))


def cycle_count(days: float) -> int:
    """Control cycles (sidereal days) of a closed-loop run of ``days`` solar days."""
    return max(1, round(days * SECONDS_PER_DAY / SIDEREAL_DAY_S))


def environment_at(t_tt_s, frame_epoch_tt_s, tt_minus_ut1_s) -> Environment:
    """Sun, Moon and Earth angle (and its cosine and sine) at TT times of any shape (leaves [..., 3] and [...])."""
    angle = earth_rotation_angle_rad(t_tt_s, frame_epoch_tt_s, tt_minus_ut1_s)
    return Environment(
        sun_position_eci_m(t_tt_s, frame_epoch_tt_s),
        moon_position_eci_m(t_tt_s, frame_epoch_tt_s),
        angle,
        jnp.cos(angle),
        jnp.sin(angle),
    )


EPHEMERIDES = ("meeus", "de421")


def environment_grid(start_tt_s, frame_epoch_tt_s, tt_minus_ut1_s, step_s, n_cycles: int, n_steps: int,
                     ephemeris: str = "meeus") -> Environment:
    """Environment at the RK4 stage times of every step from ``start_tt_s``: leaves [n_cycles, n_steps, 3, ...].

    Evaluated once per scenario (and per step size), shared by every sample of a batch.  ``ephemeris``: the
    Sun and Moon from the analytic series ("meeus") or from JPL DE421 ("de421", NumPy, outside the step).
    """
    env = _environment_grid(start_tt_s, frame_epoch_tt_s, tt_minus_ut1_s, step_s, n_cycles, n_steps)
    if ephemeris == "meeus":
        return env
    if ephemeris != "de421":
        raise ValueError(f"forces.ephemeris: must be one of {', '.join(map(repr, EPHEMERIDES))}, got {ephemeris!r}")
    half_steps = float(start_tt_s) + np.arange(2 * n_cycles * n_steps + 1) * (float(step_s) / 2)
    sun, moon = de421_sun_moon_eci_m(half_steps, float(frame_epoch_tt_s))
    return env._replace(r_sun_eci_m=_on_stages(jnp.asarray(sun), n_cycles, n_steps),
                        r_moon_eci_m=_on_stages(jnp.asarray(moon), n_cycles, n_steps))


def environment_shape(start_tt_s, frame_epoch_tt_s, tt_minus_ut1_s, step_s, n_cycles: int, n_steps: int) -> Environment:
    """The shapes (``jax.ShapeDtypeStruct``) of ``environment_grid``'s leaves, from either ephemeris, without
    computing it."""
    return jax.eval_shape(_environment_grid, start_tt_s, frame_epoch_tt_s, tt_minus_ut1_s, step_s, n_cycles, n_steps)


@partial(jax.jit, static_argnums=(4, 5))
def _environment_grid(start_tt_s, frame_epoch_tt_s, tt_minus_ut1_s, step_s, n_cycles: int, n_steps: int):
    half_steps = jnp.arange(2 * n_cycles * n_steps + 1)
    env = environment_at(start_tt_s + half_steps * (step_s / 2), frame_epoch_tt_s, tt_minus_ut1_s)
    return jax.tree_util.tree_map(lambda x: _on_stages(x, n_cycles, n_steps), env)


def _on_stages(half_step_values, n_cycles: int, n_steps: int):
    """Values at the half steps [2 n_cycles n_steps + 1, ...] -> at each step's three RK4 stage times
    [n_cycles, n_steps, 3, ...]."""
    index = 2 * jnp.arange(n_cycles * n_steps)[:, None] + jnp.arange(3)[None, :]
    return half_step_values[index].reshape((n_cycles, n_steps, 3) + half_step_values.shape[1:])


def cycle_means(fghk_mean, a_mean_m, lon_rad, tan_lat, cycle_s, t_mid_s) -> CycleMeans:
    """One cycle's mean elements: the one-cycle means (``cycle_mean``'s trapezoid rule) of MEE (f, g, h, k)
    [4] and of the semi-major axis, which the loop sums as it steps, and the sub-satellite longitude and the
    tangent of the latitude at [n + 1] samples equally spaced over the cycle, both ends included
    (``frames.subsatellite_lon_tan_lat_xyz``: the loop has them from its step records).

    The longitude is unwrapped relative to the first sample (it moves < pi between samples); the trapezoid
    mean of that unwrapped longitude is a fixed weighting of the per-interval changes (each counts at every
    later sample, half at the last), so no cumulative sum is formed.
    """
    turns = wrap_angle(jnp.diff(lon_rad))  # [n], each |.| < pi
    n = turns.shape[0]
    dlon_mean = jnp.sum(turns * ((n - 0.5 - jnp.arange(n)) / n))
    return CycleMeans(
        t_s=t_mid_s,
        lon_rad=wrap_angle(lon_rad[0] + dlon_mean),
        drift_rad_s=jnp.sum(turns) / cycle_s,
        ex=fghk_mean[0],
        ey=fghk_mean[1],
        ix=fghk_mean[2],
        iy=fghk_mean[3],
        a_m=a_mean_m,
        max_abs_lat_rad=latitude_rad(jnp.max(jnp.abs(tan_lat))),
    )
