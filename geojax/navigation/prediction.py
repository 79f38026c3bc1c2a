"""The filter's time update: its model of one step (``predict``, ``error_state_prediction``), the state
transition matrix of (r, v, eps, phi) over it (``transition``), and the force model the filter assumes
(``filter_forces``).  The derivation: docs/navigation.md."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from geojax.physics.execution import executed
from geojax.navigation.state import N_STATE, Layout, Navigation, n_estimated
from geojax.physics.dynamics import SpacecraftState, Thrust, cartesian_rhs, mee_rhs
from geojax.physics.elements import cartesian_to_mee, mee_to_cartesian, wrap_angle
from geojax.physics.frames import rsw_basis
from geojax.physics.integrate import rk4_step


def filter_forces(fm, layout: Layout):
    if layout.filter_forces == "two_body":
        return fm._replace(j2_on=0.0, c22_on=0.0, sun_on=0.0, moon_on=0.0, srp_on=0.0, gravity=None)
    return fm


def predict(x, execution, mass_kg, state: Navigation, env3, fm, step_s):
    """Elements ``x`` [6] one RK4 step later: the loop's MEE equations, the planned thrust executed with the
    errors (eps, phi) ``execution`` [4].  The filter's prediction computed directly (the loop computes it as
    ``error_state_prediction``; the tests compare the two)."""
    direction, thrust_n = executed(state.planned_direction_rsw, state.planned_thrust_n, execution[0], execution[1:])
    thrust = Thrust(direction, thrust_n, state.isp_s, state.planned_on_fraction)
    return rk4_step(mee_rhs, SpacecraftState(x, mass_kg, jnp.zeros_like(mass_kg)), env3, fm, thrust, step_s).orbit


def transition(rv, mass_kg, state: Navigation, step_s, mu):
    """The state transition matrix [n, n] of (r, v, eps, phi, the estimated biases) over one step:
    [[Phi, Gamma, 0], [0, I, 0], [0, 0, I]] (the biases are constants).

    Phi: the variational equations d Phi / dt = A(t) Phi, A = [[0, I], [G, 0]], G = mu / r^3 (3 r_hat r_hat^T - I)
    the point-mass gravity gradient, by the fourth-order Magnus expansion (Iserles & Norsett 1999): with A_1, A_2
    at the Gauss points t = h (1/2 -+ sqrt(3)/6), Omega = h (A_1 + A_2) / 2 + (sqrt(3) h^2 / 12) [A_2, A_1] and
    Phi = exp(Omega) (in closed form to first order in the commutator, below); the positions at the Gauss points from the estimate's
    Taylor series to the jerk.  Gamma = int_0^h Phi(h - t) [0; B(t)] dt, B = d a_thrust / d (eps, phi) = a R (d,
    -[d x]) (a the planned acceleration, R the RSW -> ECI rotation, d the planned direction), with G and R at the
    midpoint and R's turning over the step to first order.  The point of expansion is the truth's (its state and
    execution errors, ``error_state_prediction``): the extended Kalman filter takes its Jacobians at its
    estimate, which differs by the estimation error's relative size (1e-6 in the orbit; in the partials by phi,
    the magnitude error's 1 + eps: 2 % at the scenario's sigma).  Relative to G at GEO, left out: J2's gradient
    3 J2 (R_E / r)^2 = 9e-5, the Moon's and the Sun's 3e-5 and 1e-5, the thrust frame's turning a / (r G) = 5e-4;
    the expansion's remainder (n h)^5 is 1e-6 at 900 s.  ``tests/test_navigation_loop.py`` checks the matrix
    against ``jax.jacfwd`` of the filter's full MEE step, and the filter's covariance against the Cramer-Rao
    bound.  A frozen G at the midpoint (second order) put the along-track sigma 24 % below the bound after three
    days: the error accumulates in the along-track drift.  Written out rather than ``jax.jacfwd`` of the MEE
    step: XLA's CPU compiler copies the step's producers into each of the ten tangents' kernels (140 us per
    sample-step against a few, measured).
    """
    h = step_s
    r, v = rv[:3], rv[3:]
    r_norm = jnp.linalg.norm(r)
    a0 = -mu * r / r_norm**3
    jerk = -mu * (v / r_norm**3 - 3.0 * r * jnp.dot(r, v) / r_norm**5)
    eye = jnp.eye(3)

    def gradient(t):
        at = r + v * t + a0 * (t * t / 2) + jerk * (t**3 / 6)
        norm = jnp.linalg.norm(at)
        unit = at / norm
        return mu / norm**3 * (3.0 * jnp.outer(unit, unit) - eye)

    offset = h * np.sqrt(3.0) / 6
    g1, g2 = gradient(h / 2 - offset), gradient(h / 2 + offset)
    g = 0.5 * (g1 + g2)
    # Omega = Omega_0 + Delta, Omega_0 = h [[0, I], [G, 0]] (G the Gauss points' mean), Delta = (sqrt(3) h^2 / 12)
    # [A_2, A_1] = diag(D, -D), D = (sqrt(3) h^2 / 12) (G_1 - G_2).  exp(Omega_0) in closed form (Omega_0^2 = h^2
    # diag(G, G), ...), and exp(Omega) = exp(Omega_0) + Delta + O(h |Omega_0| |Delta|): the commutator terms are
    # O((n h)^4) relative (6e-7 against the series of exp(Omega) to the fifth power, measured), one 3 x 3 product
    # instead of five 6 x 6 ones (2.8 against 6.2 us per sample-step, measured).
    d = (np.sqrt(3.0) * h * h / 12) * (g1 - g2)
    gg = g @ g
    diagonal = eye + g * (h**2 / 2) + gg * (h**4 / 24)
    phi = jnp.block([[diagonal + d, eye * h + g * (h**3 / 6) + gg * (h**5 / 120)],
                     [g * h + gg * (h**3 / 6), diagonal - d]])
    r_mid, v_mid = r + v * (h / 2) + a0 * (h * h / 8), v + a0 * (h / 2)
    accel = state.planned_on_fraction * state.planned_thrust_n / mass_kg
    e = state.truth_execution  # the expansion's point (``error_state_prediction``)
    d, _ = executed(state.planned_direction_rsw, 1.0, 0.0, e[1:])
    d_cross = jnp.array([[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]])
    b_rsw = accel * jnp.concatenate([d[:, None], -(1.0 + e[0]) * d_cross], axis=1)  # d a / d (eps, phi), RSW
    basis = rsw_basis(r_mid, v_mid)  # rows R, S, W at the midpoint
    rate = jnp.linalg.norm(jnp.cross(r_mid, v_mid)) / jnp.dot(r_mid, r_mid)  # the RSW frame turns at it about W
    turning = rate * jnp.stack([basis[1], -basis[0], jnp.zeros(3)], axis=1)  # d (RSW -> ECI) / dt
    b = basis.T @ b_rsw  # [3, 4] ECI, at the midpoint
    # int_0^h (h - t) R(t) dt B = (h^2 / 2) R_mid B - (h^3 / 12) R' B: the frame's turning weighs the early thrust
    gamma = jnp.concatenate([(eye * (h**2 / 2) + g * (h**4 / 24)) @ b - (h**3 / 12) * turning @ b_rsw,
                             (eye * h + g * (h**3 / 6)) @ b])
    return jnp.eye(N_STATE + n_estimated(state)).at[:6, :6].set(phi).at[:6, 6:N_STATE].set(gamma)


def error_state_prediction(layout: Layout, f, state: Navigation, ctx, start):
    """The estimate [6] at the step's end: the filter's model f(x, e) (the planned thrust executed with the
    estimated e = (eps, phi)) expanded about the true step, f(x_true, e_true) + Phi (x - x_true) + Gamma (e -
    e_true), ``f`` = [[Phi, Gamma], [0, I]].  f(x_true, e_true) is the truth's own step end where the filter's
    model is the loop's (``filter_forces = "loop"``), else point-mass gravity's RK4 step from the true start with
    the thrust flown.  The expansion's remainder is second order in the deviation: at GEO the flow's second
    derivative is 3 mu / r^4 per m^2 of position over h^2 / 2, 2e-21 m per m^2 over 900 s (a 1 km error: 2e-15 m),
    so this is the extended Kalman filter's prediction from its own estimate to rounding (``predict`` computes it
    directly; ``tests/test_navigation_loop.py`` compares them), without a second integration of the force model
    (which would cost as much as the truth's own step)."""
    if layout.filter_forces == "loop":
        anchor = jnp.concatenate([ctx.r_end_eci_m, ctx.v_end_eci_mps])
    else:
        fm = filter_forces(ctx.force_model, layout)
        anchor = rk4_step(cartesian_rhs, SpacecraftState(start, ctx.mass_kg, jnp.zeros_like(ctx.mass_kg)),
                          ctx.env, fm, ctx.thrust, ctx.step_s).orbit
    deviation = jnp.concatenate([state.x - start, state.execution - state.truth_execution])
    return anchor + f[:6, :N_STATE] @ deviation


def rv_of(x, mu):
    """ECI (r, v) [6] of the estimate's elements [6]."""
    return jnp.concatenate(mee_to_cartesian(x[:6], mu))


def elements_of(rv, near, mu):
    """The elements [6] of ECI (r, v) [6], L continuous with the elements ``near``."""
    x = cartesian_to_mee(rv[:3], rv[3:], mu)
    return x.at[5].set(near[5] + wrap_angle(x[5] - near[5]))
