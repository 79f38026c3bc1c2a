"""Orbit determination in the loop: an extended Kalman filter on ground-station tracking (or a GNSS-in-GEO receiver)
and the burns' execution errors, a state of the loop (``states.base``), selected by ``navigation.model = "ekf"``.

What the model carries.  The filter's state is the estimate's ECI position and velocity [6] and the current
burn's estimated execution error, a magnitude error eps (a fraction) and a pointing error phi [3] (a small
rotation vector in RSW, rad), with the covariance P [10, 10] of (r, v, eps, phi).  It also carries the truth's
execution error of the current burn, the measurement biases drawn for the sample, the thrust planned over the
current step, and the cycle's consistency sums.

The truth's execution errors (``thrust``, the model's hook on the thrust flown).  Every burn of every controller
(a burn: a run of consecutive firing steps) is flown with its own drawn errors: thrust level (1 + eps) F and
direction d + phi x d (its length kept), eps ~ N(0, sigma_m^2), phi ~ N(0, sigma_p^2 I) (the component of phi
along d turns nothing, so the direction is off by sigma_p per perpendicular axis:
``navigation.burn_magnitude_sigma_pct``, ``navigation.burn_pointing_sigma_deg``).  The filter knows the plan
(the thrust the hook receives, the wheels' dumping tilt included where they ride first) and the errors'
statistics: at a burn's start it resets its (eps, phi) to 0 with covariance diag(sigma_m^2, sigma_p^2 I) and no
correlation (the last burn's errors are marginalised out: what they did to the orbit stays in P), and predicts
with the planned thrust executed with its estimated (eps, phi), so the state transition matrix carries the burn's
uncertainty into the orbit as it is flown, correlated over the burn's steps (a burn's error is one draw, not
white noise per step).

Burns and passes.  With ``navigation.burns_during_passes = false`` no step that starts inside any station's pass
fires (Gazzino 2016 keeps manoeuvres out of its orbit-determination periods): the hook zeroes the thrust planned
there before anything else, so the filter knows it; the controllers do not plan around the windows, the next
cycle's plan makes up what was not flown, and the Delta-V against the same draws with burns allowed is the cost.

Time update (``step``): the filter's model (the planned thrust executed with its estimated (eps, phi), the force
model ``filter_forces``: the loop's, or point-mass gravity alone, to study model error) taken one step from the
estimate, computed as an error-state expansion about the true step (``error_state_prediction``: the model's step
from the true state plus the transition matrix times the estimate's deviation, exact to second order in it);
the covariance through the transition matrix of (r, v, eps, phi) (``transition``: point-mass variational
equations by the fourth-order Magnus expansion, and the thrust's partials) plus state-noise compensation
(``navigation.ekf.process_noise``, white acceleration of density ``snc_mps2_per_rthz`` per axis).

Measurement updates (``step``): at every step end (the step's length is the tracking interval, 900 s by
default), each station's measurements of the types it makes (``navigation.measurements``: two-way range with
light time, range rate, azimuth and elevation) and the receiver's position fix, simulated from the true state
with the sample's bias and white noise (keys from the cycle's), weighted 0/1 by the station's schedule and by
the true elevation against its mask (``navigation.schedule``), processed one station at a time in Joseph form
(``navigation.ekf.measurement_update``; the azimuth's residual wrapped).  Biases are drawn once per sample.  By
default they are not estimated: with a bias the filter is knowingly inconsistent (NEES shows by how much).  With
``navigation.estimate_biases`` (``Layout.biases``) every measurement component's bias is a state appended to
(r, v, eps, phi): constant (identity transition, no process noise), prior N(0, sigma_b^2), z = h(x) + b (a 1 in
its column of H); a burn's start resets the execution errors' rows only (``_reset_execution``).

Decision (``estimate``): at each cycle start the controller is told the estimate's elements as its fix (L made
continuous with the truth's, as the Gaussian fix's is), and the covariance of its ECI position and velocity,
``states["navigation"]`` [6, 6], for a controller that wants it.

Records and metrics.  At each cycle start (``cycle``) the estimation error (estimate - truth) and the filter's
1-sigma in radial, along-track and cross-track axes (position m, velocity m/s) and the NEES of the six Cartesian
components; over the cycle the NIS sum, its degrees of freedom, and the measurements used.  Metrics: the error's
RMS and 95th percentile of |error| per axis over the cycle starts, the NEES averaged over them, the NIS averaged
per degree of freedom, the measurements used.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.navigation import ekf
from geojax.navigation.measurements import MODELS
from geojax.navigation.schedule import Schedule, station_schedules, tracking_weight
from geojax.navigation.stations import Station, station_eci_m, station_from_geodetic
from geojax.physics.dynamics import SpacecraftState, Thrust, cartesian_rhs, mee_rhs
from geojax.physics.elements import cartesian_to_mee, mee_to_cartesian, wrap_angle
from geojax.physics.frames import ecef_to_eci, rsw_basis
from geojax.physics.fusion import skipped_where_idle
from geojax.physics.integrate import rk4_step
from geojax.reductions import mean_over_cycles, percentile_over_cycles, sum_in_order, sum_over_cycles
from geojax.navigation.keys import FIELDS as KEYS, check_with
from geojax.states.base import NAVIGATION_STREAM, Part, StateModel

NAME = "navigation"
N_STATE = 10  # the elements, eps, phi [3]; then the measurement biases where they are estimated (``n_state``)
# ``fold_in`` constants of the model's draws from its cycle key (the step's draws fold the step index into
# MEASUREMENT_KEY first).
INITIAL_KEY, BIAS_KEY, MEASUREMENT_KEY, BURN_KEY = 0, 1, 2, 3


class Layout(NamedTuple):
    """What fixes the filter's compiled shape (static): each station's measurement types, the receiver, the
    prediction model."""

    stations: tuple[tuple[str, ...], ...]
    gnss: bool
    filter_forces: str
    biases: bool = False  # the measurement biases estimated (``navigation.estimate_biases``)


class Navigation(NamedTuple):
    """The carried state."""

    x: jnp.ndarray  # [6] the estimate: ECI position (m) and velocity (m/s)
    execution: jnp.ndarray  # [4] the estimate of the current burn's (eps, phi rad)
    p: jnp.ndarray  # [10, 10] the covariance of (r m, v m/s, eps, phi), r and v ECI
    key: jnp.ndarray  # the cycle's key (``cycle``), its draws folded from it
    step_index: jnp.ndarray  # [] int, steps since the cycle start
    bias: jnp.ndarray  # [n_components] the sample's measurement biases (drawn at cycle 0)
    truth_execution: jnp.ndarray  # [4] the current burn's true (eps, phi)
    firing: jnp.ndarray  # [] bool, whether the latest step fired
    planned_direction_rsw: jnp.ndarray  # [3] the thrust planned over the current step (``thrust``)
    planned_thrust_n: jnp.ndarray  # []
    planned_on_fraction: jnp.ndarray  # []
    isp_s: jnp.ndarray  # []
    error_rsw: jnp.ndarray  # [6] estimate - truth at the cycle start, RSW (m, m/s)
    sigma_rsw: jnp.ndarray  # [6] the filter's 1-sigma there, RSW (m, m/s)
    nees: jnp.ndarray  # [] at the cycle start
    nis_sum: jnp.ndarray  # [] over the cycle so far
    nis_dof: jnp.ndarray  # [] degrees of freedom of those NIS
    measurements: jnp.ndarray  # [] measurement components used over the cycle so far
    # where the biases are estimated (``Layout.biases``), else None (no leaves: the filter is today's, bit for bit)
    bias_estimate: jnp.ndarray | None = None  # [n_components]
    bias_error: jnp.ndarray | None = None  # [n_components] bias_estimate - bias at the cycle start
    bias_sigma: jnp.ndarray | None = None  # [n_components] the filter's 1-sigma of it there


class NavigationCycle(NamedTuple):
    """Per cycle (always kept)."""

    error_rsw: jnp.ndarray  # [6] at the cycle start
    sigma_rsw: jnp.ndarray  # [6]
    nees: jnp.ndarray  # []
    nis_sum: jnp.ndarray  # [] over the cycle
    nis_dof: jnp.ndarray  # []
    measurements: jnp.ndarray  # []
    bias_error: jnp.ndarray | None = None  # [n_components] the biases' estimation error at the cycle start, where
    bias_sigma: jnp.ndarray | None = None  # [n_components] estimated (else None), and the filter's 1-sigma of it


# --- the scenario's leaves -------------------------------------------------------------------------------------

def layout_of(table: dict) -> Layout:
    """The static layout of a validated ``[navigation]`` table."""
    return Layout(tuple(tuple(s["measurements"]) for s in table["stations"]), table["gnss"] is not None,
                  table["filter_forces"], table["estimate_biases"])


def leaves_of(table: dict) -> dict:
    """``Params.navigation``: the SI leaves of a validated ``[navigation]`` table, stations stacked on a leading
    axis (outages padded with empty windows)."""
    stations, gnss = table["stations"], table["gnss"]
    deg = np.pi / 180.0
    out = {
        "snc_mps2_per_rthz": table["snc_mps2_per_rthz"],
        "burn_magnitude_sigma": table["burn_magnitude_sigma_pct"] / 100.0,
        "burn_pointing_sigma_rad": table["burn_pointing_sigma_deg"] * deg,
        "initial_sigma_r_m": table["initial_sigma_r_m"],
        "initial_sigma_v_mps": table["initial_sigma_v_mps"],
        "burns_during_passes": float(table["burns_during_passes"]),
        "station_lat_rad": [s["lat_deg"] * deg for s in stations],
        "station_lon_rad": [s["lon_deg"] * deg for s in stations],
        "station_alt_m": [s["alt_m"] for s in stations],
        "station_mask_rad": [s["mask_deg"] * deg for s in stations],
        "range_sigma_m": [s["range_sigma_m"] for s in stations],
        "range_bias_sigma_m": [s["range_bias_sigma_m"] for s in stations],
        "range_rate_sigma_mps": [s["range_rate_sigma_mps"] for s in stations],
        "range_rate_bias_sigma_mps": [s["range_rate_bias_sigma_mps"] for s in stations],
        "angles_sigma_rad": [s["angles_sigma_deg"] * deg for s in stations],
        "angles_bias_sigma_rad": [s["angles_bias_sigma_deg"] * deg for s in stations],
        "station_cadence_s": [s["cadence_s"] for s in stations],
        "station_pass_s": [s["pass_s"] for s in stations],
        "station_phase_s": [s["phase_s"] for s in stations],
        "station_outages_s": _padded([s["outages_s"] for s in stations]),
    }
    if gnss is not None:
        out.update(gnss_sigma_m=gnss["sigma_m"], gnss_bias_sigma_m=gnss["bias_sigma_m"],
                   gnss_cadence_s=gnss["cadence_s"], gnss_pass_s=gnss["pass_s"], gnss_phase_s=gnss["phase_s"],
                   gnss_outages_s=_padded([gnss["outages_s"]])[0])
    return {k: jnp.asarray(v, jnp.float64) for k, v in out.items()}


def _padded(windows: list) -> np.ndarray:
    """[n, k, 2] outage windows, each list padded to the longest with empty windows [0, 0)."""
    k = max([len(w) for w in windows], default=0)
    out = np.zeros((len(windows), k, 2))
    for i, w in enumerate(windows):
        if w:
            out[i, : len(w)] = w
    return out


# --- the pieces --------------------------------------------------------------------------------------------------

def executed(direction_rsw, thrust_n, eps, phi):
    """(direction [3], thrust N) of a planned thrust flown with magnitude error ``eps`` and pointing error ``phi``
    [3]: (d + phi x d) with d's length, (1 + eps) F.  Smooth at phi = 0 and at d = 0 (no burn)."""
    turned = direction_rsw + jnp.cross(phi, direction_rsw)
    size, turned_size = jnp.linalg.norm(direction_rsw), jnp.linalg.norm(turned)
    scale = jnp.where(turned_size > 0, size / jnp.where(turned_size > 0, turned_size, 1.0), 1.0)
    return turned * scale, (1.0 + eps) * thrust_n


def _filter_forces(fm, layout: Layout):
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
    return jnp.eye(N_STATE + _n_estimated(state)).at[:6, :6].set(phi).at[:6, 6:N_STATE].set(gamma)


def rv_of(x, mu):
    """ECI (r, v) [6] of the estimate's elements [6]."""
    return jnp.concatenate(mee_to_cartesian(x[:6], mu))


def elements_of(rv, near, mu):
    """The elements [6] of ECI (r, v) [6], L continuous with the elements ``near``."""
    x = cartesian_to_mee(rv[:3], rv[3:], mu)
    return x.at[5].set(near[5] + wrap_angle(x[5] - near[5]))


def stations_of(nav: dict) -> Station:
    return station_from_geodetic(nav["station_lat_rad"], nav["station_lon_rad"], nav["station_alt_m"])


def components(layout: Layout) -> list[tuple[int, str]]:
    """(tracker, type) of every measurement, in order (tracker -1: the GNSS receiver)."""
    out = [(i, kind) for i, kinds in enumerate(layout.stations) for kind in kinds]
    return out + ([(-1, "gnss")] if layout.gnss else [])


def _sigma_bias(nav: dict, tracker: int, kind: str):
    """(noise, bias sigma) of a measurement type, scalars in its unit."""
    if kind == "gnss":
        return nav["gnss_sigma_m"], nav["gnss_bias_sigma_m"]
    name = {"range": ("range_sigma_m", "range_bias_sigma_m"),
            "range_rate": ("range_rate_sigma_mps", "range_rate_bias_sigma_mps"),
            "angles": ("angles_sigma_rad", "angles_bias_sigma_rad")}[kind]
    return nav[name[0]][tracker], nav[name[1]][tracker]


def bias_sigmas(nav: dict, layout: Layout):
    """[n_components] the 1-sigma of each measurement component's per-sample bias."""
    parts = [jnp.broadcast_to(_sigma_bias(nav, t, kind)[1], (MODELS[kind].size,)) for t, kind in components(layout)]
    return jnp.concatenate(parts) if parts else jnp.zeros(0)


def _n_estimated(state: Navigation) -> int:
    """The biases ``state`` estimates (static: its shape)."""
    return 0 if state.bias_estimate is None else state.bias_estimate.shape[0]


def n_biases(layout: Layout) -> int:
    """The biases the filter estimates: every measurement component's where ``layout.biases``, else none."""
    return sum(MODELS[kind].size for _, kind in components(layout)) if layout.biases else 0


# --- the protocol ------------------------------------------------------------------------------------------------

def init(layout: Layout, params, r_eci_m, v_eci_mps, env, fm) -> Navigation:
    """The filter at the run's start: the true elements (``cycle`` adds the initial error at cycle 0) and the
    initial covariance diag(sigma_r^2 I, sigma_v^2 I); no burn."""
    nav, mu = params.states[NAME], fm.mu_m3_s2
    n_b = n_biases(layout)
    p = jnp.zeros((N_STATE + n_b, N_STATE + n_b)).at[:6, :6].set(_initial_cartesian(nav))
    if n_b:  # the estimated biases' prior: the sigmas they are drawn with, uncorrelated
        p = p.at[N_STATE:, N_STATE:].set(jnp.diag(bias_sigmas(nav, layout) ** 2))
    zero = jnp.zeros_like(r_eci_m[0])
    return Navigation(jnp.concatenate([r_eci_m, v_eci_mps]), jnp.zeros(4), p, jax.random.key(0), jnp.asarray(0),
                      jnp.zeros(bias_sigmas(nav, layout).shape[0]), jnp.zeros(4), jnp.asarray(False), jnp.zeros(3),
                      zero, zero, zero, jnp.zeros(6), jnp.zeros(6), zero, zero, zero, zero,
                      **({"bias_estimate": jnp.zeros(n_b), "bias_error": jnp.zeros(n_b), "bias_sigma": jnp.zeros(n_b)}
                         if n_b else {}))


def _initial_cartesian(nav: dict):
    return jnp.diag(jnp.concatenate([jnp.full(3, nav["initial_sigma_r_m"] ** 2),
                                     jnp.full(3, nav["initial_sigma_v_mps"] ** 2)]))


def cycle(layout: Layout, params, state: Navigation, start) -> Navigation:
    """At a cycle start: the cycle's key; at cycle 0 the initial estimate error (Gaussian, the initial
    covariance) and the sample's biases; the estimation error, 1-sigma and NEES at this decision time; the
    cycle's sums reset."""
    nav, mu = params.states[NAME], params.forces.mu_m3_s2
    first = start.index == 0
    truth = jnp.concatenate([start.r_eci_m, start.v_eci_mps])
    drawn = truth + jnp.sqrt(jnp.diag(_initial_cartesian(nav))) * jax.random.normal(
        jax.random.fold_in(start.key, INITIAL_KEY), (6,))
    x = jnp.where(first, drawn, state.x)
    bias = jnp.where(first, bias_sigmas(nav, layout) * jax.random.normal(
        jax.random.fold_in(start.key, BIAS_KEY), state.bias.shape), state.bias)
    cov = state.p[:6, :6]
    basis = rsw_basis(start.r_eci_m, start.v_eci_mps)  # rows R, S, W
    rot = jnp.zeros((6, 6)).at[:3, :3].set(basis).at[3:, 3:].set(basis)
    error = x - truth
    zero = jnp.zeros_like(state.nees)
    state = state._replace(x=x, key=start.key, step_index=jnp.zeros_like(state.step_index), bias=bias,
                           error_rsw=rot @ error, sigma_rsw=jnp.sqrt(jnp.diag(rot @ cov @ rot.T)),
                           nees=ekf.nees(error, cov), nis_sum=zero, nis_dof=zero, measurements=zero)
    if _n_estimated(state):
        state = state._replace(bias_error=state.bias_estimate - bias,
                               bias_sigma=jnp.sqrt(jnp.diag(state.p)[N_STATE:]))
    return state


def thrust(layout: Layout, params, state: Navigation, planned: Thrust, ctx):
    """The thrust flown: the planned one with the current burn's true execution errors, a new draw at each burn's
    start (where the filter resets its own (eps, phi) to the errors' prior); the plan noted for ``step``."""
    nav = params.states[NAME]
    if layout.stations:  # burns forbidden while a station's schedule is on (where ``burns_during_passes`` is 0)
        in_pass = jnp.any(jax.vmap(tracking_weight, in_axes=(None, 0))(ctx.t_s, station_schedules(nav)) > 0)
        allowed = jnp.where(in_pass, nav["burns_during_passes"], 1.0)
        planned = planned._replace(on_fraction=planned.on_fraction * allowed)
    firing = (planned.on_fraction > 0) & (planned.thrust_n > 0)
    new_burn = firing & ~state.firing
    sigma = jnp.concatenate([nav["burn_magnitude_sigma"][None], jnp.full(3, nav["burn_pointing_sigma_rad"])])
    key = jax.random.fold_in(jax.random.fold_in(state.key, BURN_KEY), state.step_index)
    truth = jnp.where(new_burn, sigma * jax.random.normal(key, (4,)), state.truth_execution)
    prior = _reset_execution(state.p, sigma)
    direction, thrust_n = executed(planned.direction_rsw, planned.thrust_n, truth[0], truth[1:])
    state = state._replace(p=jnp.where(new_burn, prior, state.p),
                           execution=jnp.where(new_burn, 0.0, state.execution), truth_execution=truth, firing=firing,
                           planned_direction_rsw=planned.direction_rsw, planned_thrust_n=planned.thrust_n,
                           planned_on_fraction=planned.on_fraction, isp_s=planned.isp_s)
    flown = planned._replace(direction_rsw=jnp.where(firing, direction, planned.direction_rsw),
                             thrust_n=jnp.where(firing, thrust_n, planned.thrust_n))
    return state, flown


def _reset_execution(p, sigma):
    """P at a burn's start: the execution errors' rows and columns replaced by their prior diag(``sigma``^2),
    uncorrelated with the orbit and the biases (the last burn's errors marginalised out), the rest kept."""
    n_b = p.shape[0] - N_STATE
    kept = jnp.zeros_like(p).at[:6, :6].set(p[:6, :6]).at[6:N_STATE, 6:N_STATE].set(jnp.diag(sigma**2))
    if n_b:
        kept = kept.at[:6, N_STATE:].set(p[:6, N_STATE:]).at[N_STATE:, :6].set(p[N_STATE:, :6])
        kept = kept.at[N_STATE:, N_STATE:].set(p[N_STATE:, N_STATE:])
    return kept


def step(layout: Layout, params, state: Navigation, ctx):
    """One integration step: the time update (planned thrust, SNC) and the measurement updates at the step's end
    (skipped for a whole batch where no sample tracks: most steps of a pass schedule)."""
    nav, fm = params.states[NAME], ctx.force_model
    mu = fm.mu_m3_s2
    n_b = _n_estimated(state)
    start = jnp.concatenate([ctx.r_eci_m, ctx.v_eci_mps])
    f = transition(start, ctx.mass_kg, state, ctx.step_s, mu)
    x = error_state_prediction(layout, f, state, ctx, start)
    p = f @ state.p @ f.T
    p = (0.5 * (p + p.T)).at[:6, :6].add(ekf.process_noise(ctx.step_s, nav["snc_mps2_per_rthz"]))  # symmetric
    truth = jnp.concatenate([ctx.r_end_eci_m, ctx.v_end_eci_mps])
    angle = ctx.env.earth_angle_rad[2]
    weights = tracking_weights(layout, nav, ctx.t_s + ctx.step_s, truth[:3], angle)
    key = jax.random.fold_in(jax.random.fold_in(state.key, MEASUREMENT_KEY), state.step_index)
    # the filter as one flat vector: the gate's vmap rule handles one array out
    packed = jnp.concatenate([x, state.execution, p.ravel(), jnp.stack([state.nis_sum, state.nis_dof,
                                                                       state.measurements]),
                              *([state.bias_estimate] if n_b else [])])
    args = (packed, weights, nav, truth, angle, state.bias, jax.random.key_data(key), mu)
    leaves, tree = jax.tree_util.tree_flatten(args)  # every array an argument: the gate closes over none

    def updates(*leaves):
        packed, weights, nav, truth, angle, bias, key, mu = jax.tree_util.tree_unflatten(tree, leaves)
        out = _updates(layout, mu, _unpacked(packed, n_b), weights, nav, truth, angle, bias,
                       jax.random.wrap_key_data(key))
        return jnp.concatenate([out[0], out[1], out[2].ravel(), jnp.stack(out[3:6]), *([out[6]] if n_b else [])])

    packed = skipped_where_idle(updates, lambda *a: jnp.any(jax.tree_util.tree_unflatten(tree, a)[1] > 0),
                                lambda *a: a[0], *leaves)
    x, execution, p, nis_sum, nis_dof, used, bias_estimate = _unpacked(packed, n_b)
    return state._replace(x=x, execution=execution, p=p, step_index=state.step_index + 1, nis_sum=nis_sum,
                          nis_dof=nis_dof, measurements=used, bias_estimate=bias_estimate), ()


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
        fm = _filter_forces(ctx.force_model, layout)
        anchor = rk4_step(cartesian_rhs, SpacecraftState(start, ctx.mass_kg, jnp.zeros_like(ctx.mass_kg)),
                          ctx.env, fm, ctx.thrust, ctx.step_s).orbit
    deviation = jnp.concatenate([state.x - start, state.execution - state.truth_execution])
    return anchor + f[:6, :N_STATE] @ deviation


def _unpacked(packed, n_b: int = 0):
    """(x [6], execution [4], P [n, n], NIS sum, its dof, measurements, bias estimate [n_b]) of the flat vector
    ``step`` packs (n = 10 + n_b)."""
    size = N_STATE + n_b
    n = size * size
    return (packed[:6], packed[6:10], packed[10:10 + n].reshape(size, size), packed[10 + n],
            packed[11 + n], packed[12 + n], packed[13 + n:13 + n + n_b] if n_b else None)


def _trackers(layout: Layout):
    """(tracker, its measurement types): the stations in order, then the receiver (-1)."""
    return [(i, kinds) for i, kinds in enumerate(layout.stations)] + ([(-1, ("gnss",))] if layout.gnss else [])


def tracking_weights(layout: Layout, nav: dict, t_s, r_eci_m, earth_angle_rad):
    """[n_trackers] 1.0 where a tracker measures at ``t_s``: in its schedule and, for a station, the true satellite
    at or above its elevation mask (geometric elevation: the down leg's light time turns it by 2 arc seconds)."""
    out = []
    if layout.stations:
        stations = stations_of(nav)
        los = r_eci_m - station_eci_m(stations, earth_angle_rad)  # [n, 3]
        up = ecef_to_eci(stations.enu_ecef[:, 2], earth_angle_rad)
        visible = jnp.sum(up * los, axis=-1) >= jnp.sin(nav["station_mask_rad"]) * jnp.linalg.norm(los, axis=-1)
        out.append(jax.vmap(tracking_weight, in_axes=(None, 0))(t_s, station_schedules(nav)) * visible)
    if layout.gnss:
        plan = Schedule(nav["gnss_cadence_s"], nav["gnss_pass_s"], nav["gnss_phase_s"], nav["gnss_outages_s"])
        out.append(tracking_weight(t_s, plan)[None])
    return jnp.concatenate(out)


def _updates(layout: Layout, mu, filtered, weights, nav, truth, angle, bias, key):
    """The measurement updates of one step end, one tracker at a time (Joseph form, weighted by ``weights``):
    ``filtered`` = (x, execution, P, NIS sum, its dof, measurements used) after them."""
    x, execution, p, nis_sum, nis_dof, used, bias_estimate = filtered
    n = p.shape[0]
    n_b = n - N_STATE
    all_stations = stations_of(nav) if layout.stations else None
    rv = x
    offset = 0
    for place, (i, kinds) in enumerate(_trackers(layout)):
        station = (jax.tree_util.tree_map(lambda leaf, i=i: leaf[i], all_stations) if i >= 0
                   else Station(jnp.zeros(3), jnp.eye(3)))
        weight = weights[place]

        def h(y, station=station, kinds=kinds):
            return jnp.concatenate([MODELS[kind].h(y, station, angle) for kind in kinds])

        size = sum(MODELS[kind].size for kind in kinds)
        sigma = jnp.concatenate([jnp.broadcast_to(_sigma_bias(nav, i, kind)[0], (MODELS[kind].size,))
                                 for kind in kinds])
        z = h(truth) + bias[offset:offset + size] + sigma * jax.random.normal(jax.random.fold_in(key, offset), (size,))
        jac, predicted = jax.jacfwd(lambda y, h=h: (h(y), h(y)), has_aux=True)(rv)
        if n_b:  # the estimated biases' part of the prediction: z = h(x) + b
            predicted = predicted + bias_estimate[offset:offset + size]
        innovation = z - predicted
        at = 0
        for kind in kinds:  # the azimuth's residual wrapped to (-pi, pi]
            if kind == "angles":
                innovation = innovation.at[at].set(wrap_angle(innovation[at]))
            at += MODELS[kind].size
        h_x = jnp.zeros((size, n)).at[:, :6].set(jac)
        if n_b:
            h_x = h_x.at[:, N_STATE + offset:N_STATE + offset + size].set(jnp.eye(size))
        delta, p, s = ekf.measurement_update(jnp.zeros(n), p, innovation, h_x, jnp.diag(sigma**2), weight)
        rv = rv + delta[:6]
        execution = execution + delta[6:N_STATE]
        if n_b:
            bias_estimate = bias_estimate + delta[N_STATE:]
        nis_sum = nis_sum + weight * ekf.nis(innovation, s)
        nis_dof = nis_dof + weight * size
        used = used + weight * size
        offset += size
    return rv, execution, p, nis_sum, nis_dof, used, bias_estimate


def estimate(params, state: Navigation, told):
    """What the controller is told at a cycle start: the filter's estimate as the fix (its elements, L continuous
    with the truth's, as the Gaussian fix's is) and the covariance [6, 6] of its ECI (r, v) in
    ``states["navigation"]``."""
    fix = elements_of(state.x, told.fix_mee, params.forces.mu_m3_s2)
    return told._replace(fix_mee=fix, states={**told.states, NAME: state.p[:6, :6]})

def summary(params, start: Navigation, end: Navigation, steps) -> NavigationCycle:
    """The cycle's record: the decision time's error, 1-sigma and NEES; the cycle's NIS sums and measurements."""
    return NavigationCycle(start.error_rsw, start.sigma_rsw, start.nees, end.nis_sum, end.nis_dof, end.measurements,
                           start.bias_error, start.bias_sigma)


AXES = ("radial", "along", "cross")


def metrics(params, cycles: NavigationCycle, n_steps_total: int, run_s: float):
    """({name: []}, False): the estimation error at the decision times (RMS and 95th percentile of |error| per RSW
    axis, position and velocity), NEES averaged over them, NIS averaged per degree of freedom over every update,
    the measurement components used.  The filter never fails a sample."""
    out = {}
    for k, axis in enumerate(AXES):
        for offset, unit in ((0, "m"), (3, "mps")):
            e = cycles.error_rsw[:, offset + k]
            out[f"nav_{axis}_rms_{unit}"] = jnp.sqrt(mean_over_cycles(e**2))
            out[f"nav_{axis}_p95_{unit}"] = percentile_over_cycles(jnp.abs(e), 95.0)
    out["nav_position_rms_m"] = jnp.sqrt(mean_over_cycles(sum_in_order(cycles.error_rsw[:, :3] ** 2)))
    out["nees_mean"] = mean_over_cycles(cycles.nees)
    dof = sum_over_cycles(cycles.nis_dof)
    out["nis_mean_per_dof"] = sum_over_cycles(cycles.nis_sum) / jnp.where(dof > 0, dof, 1.0)
    out["measurements_used"] = sum_over_cycles(cycles.measurements)
    return out, jnp.asarray(False)


def columns(cycles: NavigationCycle) -> dict:
    """The per-cycle series in edge units: error and 1-sigma at each decision time per RSW axis, NEES, NIS per
    degree of freedom, measurements."""
    error, sigma = cycles.error_rsw, cycles.sigma_rsw
    out = {}
    for k, axis in enumerate(AXES):  # [..., k]: one sample's records or a batch's (a sweep's, traced)
        out[f"nav_error_{axis}_m"], out[f"nav_sigma_{axis}_m"] = error[..., k], sigma[..., k]
        out[f"nav_error_{axis}_mps"], out[f"nav_sigma_{axis}_mps"] = error[..., 3 + k], sigma[..., 3 + k]
    out["nees"] = cycles.nees
    dof = cycles.nis_dof
    out["nis_per_dof"] = cycles.nis_sum / jnp.where(dof > 0, dof, 1.0)
    out["measurements"] = cycles.measurements
    for i in range(0 if cycles.bias_error is None else cycles.bias_error.shape[-1]):  # each estimated bias's
        out[f"nav_bias_error_{i}"], out[f"nav_bias_sigma_{i}"] = cycles.bias_error[..., i], cycles.bias_sigma[..., i]
    return out


@functools.lru_cache(maxsize=None)
def model(layout: Layout) -> StateModel:
    """The filter for a layout: one object per layout (a static argument of the compiled loop)."""
    n_b = n_biases(layout)  # NavigationCycle: 16 values, and each estimated bias's error and sigma
    return StateModel(NAME, functools.partial(init, layout), functools.partial(step, layout), summary, metrics,
                      cycle=functools.partial(cycle, layout), columns=columns,
                      thrust=functools.partial(thrust, layout), estimate=estimate,
                      bytes_per_cycle=(16 + 2 * n_b) * 8, columns_per_cycle=15 + 2 * n_b, stream=NAVIGATION_STREAM)


# The registry's entry (metrics and columns, which do not depend on the layout).
MODEL = model(Layout((), False, "loop"))

DESCRIBED_AXES = tuple(zip(AXES, ("radial", "along-track", "cross-track")))
DESCRIBED_UNITS = (("m", "position"), ("mps", "velocity"))
DESCRIPTIONS = {
    **{f"nav_{axis}_{stat}_{unit}": f"{what_stat} of the filter's {name} {what} error at the decision times"
       for axis, name in DESCRIBED_AXES for unit, what in DESCRIBED_UNITS
       for stat, what_stat in (("rms", "RMS"), ("p95", "95th percentile of the magnitude"))},
    "nav_position_rms_m": "RMS of the filter's position error (3-D) at the decision times",
    "nees_mean": "the filter's NEES (6 dof: position and velocity) averaged over the decision times; 6 if consistent",
    "nis_mean_per_dof": "the filter's NIS per degree of freedom over every measurement update; 1 if consistent",
    "measurements_used": "measurement components the filter processed over the run",
    **{f"nav_{kind}_{axis}_{unit}": f"the filter's {name} {what} {label} at the cycle start"
       for axis, name in DESCRIBED_AXES for unit, what in DESCRIBED_UNITS
       for kind, label in (("error", "error (estimate - truth)"), ("sigma", "1-sigma"))},
    "nees": "the filter's NEES at the cycle start (6 dof)",
    "nis_per_dof": "the filter's NIS per degree of freedom over the cycle's updates",
    "measurements": "measurement components the filter processed in the cycle",
}


PART = Part(NAME, table="navigation", fields=KEYS,
            select=lambda table: model(layout_of(table)) if table["model"] == "ekf" else None,
            leaves=leaves_of, validate=check_with, descriptions=DESCRIPTIONS, figures="geojax.plots.parts:navigation_figures",
            model=MODEL)  # its metrics and columns, which do not depend on the layout
