"""Closed-loop station keeping with the QFFC or the FOMPC (Li 2022, Secs. 3-4): one pure rollout.

An outer ``lax.scan`` over control cycles (one sidereal day each).  At the
start of a cycle the controller estimates the mean elements from the state
(``control.predictor``), predicts them one cycle ahead with the natural drift
of the shared reference and solves the QFFC for two burns (``control.plan``,
``control.qffc``), or, for the FOMPC, plans the north-south corrections of
the next N cycles by simulated annealing (``control.fompc``); and the cycle is integrated with the burns as thrust windows centred on their
right ascensions.  A burn shorter than the minimum (30 s) is not fired.  A
burn that meets the Earth's shadow is suspended and resumed until it has fired
its full time (Li 2022, Sec. 3.2, constraint 6): it runs on a clock that only
advances in sunlight (``propulsion.sunlit_clock``), with the shadow taken at
the station's nominal position (within +-0.05 deg of the satellite, a few
seconds of eclipse timing).  A suspended burn that would run past the end of
the cycle is cut there.

Errors (Li 2022, eqs. (47)-(48)) enter where a satellite gets them: the
orbit-determination fix read at the start of a cycle carries Gaussian errors
on every component of r and v (1-sigma ``sigma_r_m``, ``sigma_v_mps``), and
the controller's whole estimate is built from that fix; each burn is flown
with Gaussian yaw and pitch errors (``sigma_att_rad``) on the planned
direction.  The key of cycle k is ``fold_in(key, k)``; the FOMPC's annealing
uses ``fold_in(fold_in(key, k), 1)``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from geojax.control import fompc, qffc
from geojax.control.effects import R_SYNC_M
from geojax.control.plan import model_cycle
from geojax.control.predictor import Reference, boundary_elements, estimate_mean
from geojax.dynamics import Thrust
from geojax.elements import cartesian_to_mee, mee_to_cartesian, wrap_angle
from geojax.forces import shadow_fraction
from geojax.integrate import propagate_steps
from geojax.propagate import MEE, CycleMeans, cycle_means
from geojax.propulsion import ArmLimits, delta_v_direction_rsw, firing_fraction, sunlit_clock


class LoopParams(NamedTuple):
    """What a sweep can vary in a QFFC closed loop (array leaves)."""

    limits: ArmLimits
    thrust_n: jnp.ndarray
    isp_s: jnp.ndarray
    min_burn_s: jnp.ndarray
    target: jnp.ndarray  # [6] (lon rad, drift rad/s, e_x, e_y, i_x, i_y), Li 2022 eq. (10)
    sigma_r_m: jnp.ndarray = jnp.asarray(0.0)  # 1-sigma OD position error per axis
    sigma_v_mps: jnp.ndarray = jnp.asarray(0.0)  # 1-sigma OD velocity error per axis
    sigma_att_rad: jnp.ndarray = jnp.asarray(0.0)  # 1-sigma yaw and pitch error of a burn
    vdt_estimate: jnp.ndarray = jnp.asarray(0.0)  # 1: start V_DT from eqs. (37)-(39); 0: from the drift target
    mpc: fompc.MpcParams = fompc.MpcParams()  # FOMPC only


CONTROLLERS = ("qffc", "fompc")


# Li 2022, eq. (48): nominal 3-sigma errors, scaled by H_rv and H_att.
NOMINAL_3SIGMA_R_M = 0.3
NOMINAL_3SIGMA_V_MPS = 5e-5
NOMINAL_3SIGMA_ATT_DEG = 0.05


class CycleRecord(NamedTuple):
    means: CycleMeans  # mean elements over the cycle
    burns: qffc.BurnPair  # the planned solution
    burn_s: jnp.ndarray  # [2] firing time of each thruster (after any cut at the cycle end)
    prediction: jnp.ndarray  # [6] predicted mean elements at the end of the cycle, without burns
    fraction: jnp.ndarray  # [] north-south correction flown, as a fraction of the QFFC's (1 for the QFFC)


def reference_window(controller: str, annealing: fompc.Annealing = fompc.Annealing()) -> int:
    """Reference boundaries a cycle's plan reads, from its own start on."""
    return (annealing.n_max if controller == "fompc" else 1) + 2


def rollout(state, env_grid, fm, step_s, ref: Reference, params: LoopParams, key=None,
            controller: str = "qffc", annealing: fompc.Annealing = fompc.Annealing()):
    """Closed loop over the cycles of ``env_grid``; ``ref`` holds the reference from the same start.

    ``ref`` needs ``reference_window(controller, annealing) - 1`` boundaries
    beyond the last cycle's start.  ``key`` (a ``jax.random`` key) draws the
    errors and the annealing; without it the errors are zero.
    ``controller`` and ``annealing`` are static.

    Returns (final state, CycleRecord with a leading cycle axis).
    """
    cycle_s = env_grid.earth_angle_rad.shape[1] * step_s
    mu = fm.mu_m3_s2

    if controller not in CONTROLLERS:
        raise ValueError(f"controller: must be one of {', '.join(CONTROLLERS)}, got {controller!r}")
    n_steps = env_grid.earth_angle_rad.shape[1]
    n_cycles = env_grid.earth_angle_rad.shape[0]
    width = reference_window(controller, annealing)
    if ref.mean.shape[0] < n_cycles + width - 1:
        raise ValueError(f"ref: {controller} over {n_cycles} cycles needs {n_cycles + width - 1} reference "
                         f"boundaries, got {ref.mean.shape[0]}")

    def one_cycle(carry, xs):
        state, warm_start = carry
        k, env_steps, osc_ref, windows = xs
        t0 = k * cycle_s
        cycle_key = jax.random.fold_in(key, k)
        od_noise, att_noise = jax.random.normal(cycle_key, (2, 6))
        measured = measured_mee(state.orbit, od_noise, params, mu)
        estimate = estimate_mean(boundary_elements(measured, env_steps.earth_angle_rad[0, 0]), osc_ref, windows[0], mu)
        l_start = measured[5]
        model = (estimate, windows, params.target, l_start, params.limits, cycle_s, params.vdt_estimate)
        prediction, burns, _ = model_cycle(*model)
        fraction = jnp.asarray(1.0)
        if controller == "fompc":
            planned = fompc.plan(jax.random.fold_in(cycle_key, 1), *model, params.mpc, annealing, warm_start)
            burns, fraction, warm_start = planned.burns, planned.fractions[0], fompc.shifted(planned.fractions, params.mpc.horizon)
        # Burn mid-points at the right ascensions l_1, l_2: the orbit turns 2 pi per cycle.
        t_mid = jnp.mod(burns.l_rad - l_start, 2 * jnp.pi) / (2 * jnp.pi) * cycle_s
        burn_s = burns.v_mps * state.mass_kg / params.thrust_n  # eq. (13)
        burn_s = jnp.where((burn_s >= params.min_burn_s) & burns.feasible, burn_s, 0.0)
        start = jnp.clip(t_mid - burn_s / 2, 0.0, cycle_s - burn_s)
        attitude_error = params.sigma_att_rad * att_noise[:4].reshape(2, 2)
        directions = delta_v_direction_rsw(burns.alpha_rad + attitude_error[0], burns.beta_rad + attitude_error[1])
        clock = sunlit_clock(sunlit_fraction(env_steps, params.target[0], fm), step_s)  # [n_steps + 1]
        clock_start = jnp.interp(start, jnp.arange(n_steps + 1) * step_s, clock)

        def thrust_fn(t, h):
            # The burns are half a cycle apart, so a step meets at most one of them.
            j = jnp.round((t - t0) / h).astype(int)
            fraction = firing_fraction(clock[j], clock[j + 1], clock_start, burn_s, h)
            direction = jnp.where(fraction[0] > 0, directions[0], directions[1])
            return Thrust(direction, params.thrust_n, params.isp_s, jnp.sum(fraction))

        final, starts = propagate_steps(MEE.rhs, state, env_steps, fm, step_s, t0, thrust_fn)
        orbits = jnp.concatenate([starts.orbit, final.orbit[None]], axis=0)
        angles = jnp.concatenate([env_steps.earth_angle_rad[:, 0], env_steps.earth_angle_rad[-1:, 2]])
        means = cycle_means(orbits, angles, mu, cycle_s, t0 + cycle_s / 2)
        fired_s = jnp.stack([jnp.minimum(burn_s[i], clock[-1] - clock_start[i]) for i in range(2)])
        return (final, warm_start), CycleRecord(means, burns, jnp.maximum(fired_s, 0.0), prediction, fraction)

    key = jax.random.key(0) if key is None else key
    windows = ref.mean[jnp.arange(n_cycles)[:, None] + jnp.arange(width)[None, :]]  # [n_cycles, width, 7]
    xs = (jnp.arange(n_cycles), env_grid, ref.osc[:n_cycles], windows)
    (final, _), records = jax.lax.scan(one_cycle, (state, jnp.ones(annealing.n_max)), xs)
    return final, records


def measured_mee(mee, noise, params: LoopParams, mu):
    """The orbit-determination fix: the true state with Gaussian errors on r and v (``noise`` [6] ~ N(0, 1))."""
    r, v = mee_to_cartesian(mee, mu)
    r = r + params.sigma_r_m * noise[:3]
    v = v + params.sigma_v_mps * noise[3:]
    fix = cartesian_to_mee(r, v, mu)
    # Keep the true longitude continuous with the state's (cartesian_to_mee wraps it).
    return fix.at[5].set(mee[5] + wrap_angle(fix[5] - mee[5]))


def sunlit_fraction(env_steps, station_lon_rad, fm):
    """Sunlit fraction [n_steps] at the mid-step of each step, at the station's nominal position."""
    angle = env_steps.earth_angle_rad[:, 1] + station_lon_rad
    r_station = R_SYNC_M * jnp.stack([jnp.cos(angle), jnp.sin(angle), jnp.zeros_like(angle)], -1)
    lit = shadow_fraction(r_station, env_steps.r_sun_eci_m[:, 1], fm.r_earth_m)
    return 1.0 - fm.shadow_on * (1.0 - lit)
