"""Fixed-step Runge-Kutta integration in ``lax.scan``.

A step takes the environment (Sun, Moon, Earth angle) at its three RK4 stage
times, precomputed once for the whole batch, so nothing astronomical is
evaluated inside the vmapped loop.  Thrust is constant over a step at the
step's duty fraction (``Thrust.on_fraction``): a window [start, stop) that
begins or ends inside a step delivers exactly F/m times its length, and the
position error of spreading the burn over the step is second order in the
step (tested in ``tests/test_integrate.py``).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp

from geojax.physics.dynamics import SpacecraftState, Thrust, no_thrust
from geojax.physics.forces import Environment, ForceModel

Rhs = Callable[[SpacecraftState, Environment, ForceModel, Thrust], SpacecraftState]


class ThrustWindow(NamedTuple):
    """One constant-thrust window in seconds since the start of the propagation."""

    start_s: jnp.ndarray
    stop_s: jnp.ndarray
    direction_rsw: jnp.ndarray  # [3]
    thrust_n: jnp.ndarray
    isp_s: jnp.ndarray


def overlap_fraction(step_start_s, step_s, start_s, stop_s):
    """Fraction of [step_start, step_start + step) covered by [start, stop)."""
    overlap = jnp.minimum(step_start_s + step_s, stop_s) - jnp.maximum(step_start_s, start_s)
    return jnp.clip(overlap, 0.0, step_s) / step_s


def window_thrust(window: ThrustWindow, step_start_s, step_s) -> Thrust:
    """Thrust over one step from a thrust window."""
    fraction = overlap_fraction(step_start_s, step_s, window.start_s, window.stop_s)
    return Thrust(window.direction_rsw, window.thrust_n, window.isp_s, fraction)


def _axpy(scale, x, y):
    return jax.tree_util.tree_map(lambda a, b: a + scale * b, y, x)


# The classical RK4 tableau: each stage's node (fraction of the step), its weight in the increment (over 6), and
# which of the step's three environment samples (start, middle, end) it reads.
RK4_NODES, RK4_WEIGHTS, RK4_SAMPLES = (0.0, 0.5, 0.5, 1.0), (1.0, 2.0, 2.0, 1.0), (0, 1, 1, 2)


def rk4_step(rhs: Rhs, state, env3: Environment, fm: ForceModel, thrust: Thrust, step_s,
             stages_in_loop: bool = False):
    """One classical RK4 step; ``env3`` leaves carry a leading axis of 3 (t, t + h/2, t + h).

    ``stages_in_loop``: the four stages as a loop over the tableau, the right-hand side traced and compiled once
    instead of four times (a program of one sample compiles ~1 s faster and runs faster; the same step to
    rounding, ``tests/test_integrate.py``); else written out, the four evaluations in one straight-line body
    (what a vmapped batch runs fastest).
    """
    if stages_in_loop:
        return _rk4_step_in_loop(rhs, state, env3, fm, thrust, step_s)
    env_at = [jax.tree_util.tree_map(lambda x, j=j: x[j], env3) for j in range(3)]
    k1 = rhs(state, env_at[0], fm, thrust)
    k2 = rhs(_axpy(step_s / 2, k1, state), env_at[1], fm, thrust)
    k3 = rhs(_axpy(step_s / 2, k2, state), env_at[1], fm, thrust)
    k4 = rhs(_axpy(step_s, k3, state), env_at[2], fm, thrust)
    increment = jax.tree_util.tree_map(lambda a, b, c, d: (a + 2 * b + 2 * c + d) / 6, k1, k2, k3, k4)
    return _axpy(step_s, increment, state)


def _rk4_step_in_loop(rhs: Rhs, state, env3: Environment, fm: ForceModel, thrust: Thrust, step_s):
    """``rk4_step`` with its stages in a ``fori_loop``: stage s evaluates ``rhs`` at state + (node_s h) k_(s-1),
    and the weighted sum accumulates in the tableau's order, as the written-out step sums it."""
    offsets = jnp.asarray([node * step_s for node in RK4_NODES])
    weights, samples = jnp.asarray(RK4_WEIGHTS), jnp.asarray(RK4_SAMPLES)

    def stage(s, carry):
        k, total = carry
        env = jax.tree_util.tree_map(lambda x: jax.lax.dynamic_index_in_dim(x, samples[s], keepdims=False), env3)
        k = rhs(_axpy(offsets[s], k, state), env, fm, thrust)
        return k, _axpy(weights[s], k, total)

    zeros = jax.tree_util.tree_map(jnp.zeros_like, state)
    _, total = jax.lax.fori_loop(0, len(RK4_NODES), stage, (zeros, zeros))
    return _axpy(step_s, jax.tree_util.tree_map(lambda x: x / 6, total), state)


def propagate_steps(rhs: Rhs, state, env_steps: Environment, fm: ForceModel, step_s, t0_s, thrust_fn=None):
    """Propagate over the steps of ``env_steps`` (leaves [n_steps, 3, ...]).

    ``thrust_fn(step_start_s, step_s) -> Thrust`` gives the thrust of each step
    (none if omitted).  Returns the final state and the states at the start of
    every step ([n_steps] leading axis).
    """
    n_steps = env_steps.earth_angle_rad.shape[0]

    def body(carry, xs):
        index, env3 = xs
        step_start_s = t0_s + index * step_s
        thrust = no_thrust() if thrust_fn is None else thrust_fn(step_start_s, step_s)
        return rk4_step(rhs, carry, env3, fm, thrust, step_s), carry

    return jax.lax.scan(body, state, (jnp.arange(n_steps), env_steps))

